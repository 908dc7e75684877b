// Volume-preserving correction after smoothing (beyond the paper). Laplacian smoothing shrinks convex features;
// the feature weights protect droplets and splashes, but a thin tube a few particles across looks like a flat
// surface to them and loses up to half its volume. After smoothing, each connected component gets back the
// volume it had before, by an offset along the vertex normals proportional to how strongly each vertex was
// smoothed (its weight): droplets (weight ~0) do not move, smoothed regions move together, so no bump returns.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace meniscus {

// Connected components by shared vertices: a label per vertex (0 .. count-1, numbered by smallest vertex index,
// so deterministic) and their count. Unreferenced vertices get their own labels.
std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count);

// Signed enclosed volume per component (divergence theorem, in double). Summed over fixed blocks of triangles,
// blocks added in order: the same bits for any thread count.
std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads = 1);

// Moves vertices along their smoothed area-weighted normals (normal_iterations of Eq. 12) by s_c * amount_i so
// that component c's volume returns to target[c]; amount empty means 1 everywhere. |s_c| is capped at
// max_offset. A few Newton steps. Leaves those normals in mesh.normals: the offsets are tiny against the edge
// lengths, so they are the surface's normals too and the pipeline does not compute them a second time.
struct MeshAdjacency;
void restore_component_volumes(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<int32_t>& labels,
                               const std::vector<double>& target, const std::vector<float>& amount, double max_offset,
                               int normal_iterations, int threads);

// Smoothing may collapse a component smaller than a few cubes (a blob around one grid point) into a point or a
// line. Such a component gets its positions from `before` back: smoothing never leaves a degenerate triangle or
// an inverted component. Returns the number of components reverted.
std::size_t revert_collapsed_components(TriMesh& mesh, const std::vector<float>& before, const std::vector<int32_t>& labels,
                                        int32_t count, const std::vector<double>& volumes_before, int threads = 1);

}  // namespace meniscus
