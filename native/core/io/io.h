// Particle readers and mesh writers. Every error is a FormatError whose message starts with the file path and
// says what is wrong (truncated at byte N, unknown type, a count the file size cannot hold, ...). Readers never
// allocate more than the file's size can justify.
#pragma once
#include <string>

#include "mesh/mesh.h"
#include "sph/particles.h"

namespace meniscus {

// Reads a particle file; the format is chosen by content (magic bytes / header), falling back to the extension.
// Supported (details and variants in docs/formats.md): legacy VTK (ASCII and binary big-endian; UNSTRUCTURED_GRID and
// POLYDATA; POINT_DATA SCALARS / VECTORS / FIELD arrays), VTK XML .vtu / .vtp (ascii, base64, appended raw or base64,
// zlib, either byte order), BGEO v5 (Partio layout), Houdini JSON geometry (binary .bgeo, ASCII .geo), PLY (ASCII
// and binary vertex properties), raw float32 or text .xyz, NumPy .npy / .npz, CSV with an x, y, z header; any of
// them gzip-compressed; Mantaflow's UNI particle systems (Blender's fluid cache data/pp_####.uni: placed in the world
// by the cache's config/config_####.uni, with the sibling pVel_####.uni as `velocity` in m/s, and
// ParticleData::fluid_domain set); OpenVDB point data grids (.vdb: Houdini, Blender's Mantaflow data cache, read
// without the OpenVDB library; Mantaflow's placed like its UNI files). Not supported, with a message naming the variant: Houdini .sc (Blosc), classic ASCII
// PGEOMETRY, parallel .pvtu, non-zlib VTK compressors, pickled .npy.
// Attributes become float32 arrays (ints converted), named as in the file. Legacy VTK "long" is read as 8 bytes (as
// VTK writes it on 64-bit Unix). Decompression (gzip, VTK zlib blocks, .npz members) is capped at 64x the compressed
// size + 64 MiB (see io_util.h).
ParticleData read_particles(const std::string& path);

// Writes a mesh; the format follows the extension: .ply (binary little-endian, with normals and every vertex
// attribute), .obj (with normals), .vtk (legacy, binary, POLYDATA with normals and attributes as point data).
// PLY attribute properties: NAME for 1 component, NAME_x NAME_y NAME_z for 3, NAME_0 .. NAME_{k-1} otherwise (details
// in formats/ply.cpp). An invalid mesh or an unknown extension is an InputError; a failed write a FormatError.
// Records are encoded on `threads` threads (0: all cores) and written in order: the same bytes for any count.
void write_mesh(const TriMesh& mesh, const std::string& path, int threads = 1);

// Writes particles and their attributes; the format follows the extension: .vtk (legacy, binary, an unstructured grid
// of vertex cells, as splashsurf and ParaView read it), .ply (binary vertices with every attribute), .xyz (raw float32
// positions only). Sizes that disagree or an unknown extension are an InputError; a failed write a FormatError.
void write_particles(const ParticleData& particles, const std::string& path);

// Reads a triangle mesh such as write_mesh writes (PLY binary/ASCII, OBJ, legacy VTK POLYDATA binary/ASCII; chosen by
// the 'ply' or '# vtk DataFile' header, else by the extension), with normals and attributes where present; polygons
// are fanned into triangles. Mantaflow's own surface (mesh/fluid_mesh_####.bobj.gz) is placed in the world by its
// cache's config/config_####.uni, as Blender shows it (without normals).
TriMesh read_mesh(const std::string& path);

}  // namespace meniscus
