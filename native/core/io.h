// Particle readers and mesh writers. Every error is a FormatError whose message starts with the file path and
// says what is wrong (truncated at byte N, unknown type, a count the file size cannot hold, ...). Readers never
// allocate more than the file's size can justify.
#pragma once
#include <string>

#include "mesh.h"
#include "particles.h"

namespace meniscus {

// Reads a particle file; the format is chosen by content (magic bytes / header), falling back to the extension.
// Supported: legacy VTK (ASCII and binary big-endian; UNSTRUCTURED_GRID and POLYDATA; float and double; POINT_DATA
// SCALARS / VECTORS / FIELD arrays), BGEO v5 (Partio layout, gzip-compressed or plain).
// Attributes become float32 arrays (ints converted), named as in the file.
ParticleData read_particles(const std::string& path);

// Writes a mesh; the format follows the extension: .ply (binary little-endian, with normals and every vertex
// attribute), .obj (with normals), .vtk (legacy, binary, POLYDATA with normals and attributes as point data).
void write_mesh(const TriMesh& mesh, const std::string& path);

// Reads a triangle mesh written by write_mesh (PLY binary/ASCII or OBJ), with normals and attributes where present.
TriMesh read_mesh(const std::string& path);

}  // namespace meniscus
