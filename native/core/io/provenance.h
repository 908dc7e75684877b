// What a built mesh was made from, kept beside it so that every consumer can tell a current mesh from a stale one:
// the add-on's cache plays only frames of the surface's current parameters, `meniscus reconstruct --skip-existing`
// (and so every farm task) skips only outputs made with the same parameters and input, a re-exported farm job says
// which frames it will redo.
//
// The record is a small text file next to the mesh, named after it: "fluid_0023.npz" -> "fluid_0023.npz.meniscus"
// (frame patterns never match it: its name does not end in the mesh's extension). It holds a digest of the
// parameters that shape the mesh (every schema parameter but threads and memory limit, which change how the mesh is
// computed, not what it is; the interpolated attributes' names), the values themselves (to say which one changed),
// and the particle file's identity: name, size and modification time. Not its contents: hashing a 100 MB particle
// file costs about as much as reading it, on every frame change of a played cache; size and time are what make and
// rsync trust. A file rewritten with the same size and the same modification time is therefore not noticed.
//
// Writers keep the record honest without locking: the old record is removed before the mesh is replaced and the new
// one written (atomically, by rename) after it, so a mesh never sits beside a record of other parameters; a process
// killed in between leaves a mesh without a record, which counts as stale (redone, never trusted).
#pragma once
#include <string>
#include <vector>

#include "parameters.h"
#include "sph/fluid_domain.h"

namespace meniscus {

// The record a mesh made from this particle file with these parameters and attribute names carries (source_path
// empty: a record of the parameters alone, to check a mesh whose particle file is gone). A fluid domain the
// reconstruction was given (its walls, band, gravity, placement and obstacles shape the filled surface) is recorded
// as a digest. Throws FormatError when the particle file cannot be found.
std::string provenance_record(const Parameters& parameters, const std::vector<std::string>& attributes,
                              const std::string& source_path, const FluidDomain* fluid_domain = nullptr);
// The record file of a mesh file.
std::string provenance_path(const std::string& mesh_path);
// Before a mesh is replaced: removes its record (no error when there is none).
void forget_provenance(const std::string& mesh_path);
// After a mesh is in place: writes its record under a temporary name and renames it. Throws FormatError.
void write_provenance(const std::string& mesh_path, const std::string& record);
// Why the mesh at mesh_path is not the one `expected` describes, in words ("made with particle_radius 0.025, now
// 0.03", "its particle file fluid_0023.vtk changed since (size or modification time)", "no record of what it was
// made from"); empty when it is current.
std::string provenance_mismatch(const std::string& mesh_path, const std::string& expected);

}  // namespace meniscus
