// Last line of defence for the host application: every vertex must be finite and near the particles (a single
// vertex thrown far away makes renderers abort). Post-processing only averages positions, so this never triggers
// unless a stage is wrong; it then repairs the vertex and says so rather than handing over a dangerous mesh.
#pragma once
#include <cstddef>

#include "mesh/mesh.h"
#include "sph/neighborhood.h"

namespace meniscus {

// Clamps every vertex coordinate into the particles' bounding box grown by `margin` (a non-finite one to the box's
// centre) and zeroes non-finite normals. Returns the number of vertices moved; nothing without particles.
std::size_t keep_vertices_near_particles(TriMesh& mesh, const ParticleGrid& particles, double margin, int threads);

}  // namespace meniscus
