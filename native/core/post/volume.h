// Volume-preserving correction after smoothing (beyond the paper). Laplacian smoothing shrinks convex features;
// the feature weights protect droplets and splashes, but a thin tube a few particles across looks like a flat
// surface to them and loses up to half its volume. After smoothing, each connected component gets back the
// volume it had before, by an offset along the vertex normals proportional to how strongly each vertex was
// smoothed (its weight): droplets (weight ~0) do not move, smoothed regions move together, so no bump returns.
// A guard then gives a component that smoothing collapsed its positions back.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/adjacency.h"
#include "mesh/mesh.h"
#include "parameters.h"
#include "post/normals.h"
#include "post/wall_constraints.h"

namespace meniscus {

// The surface as smoothing found it: what restoration and the collapse guard measure against.
struct UnsmoothedSurface {
    std::vector<int32_t> labels;   // connected component of each vertex (mesh/components.h)
    int32_t components = 0;
    std::vector<double> volumes;   // signed enclosed volume per component
    std::vector<float> positions;  // 3 per vertex
};
UnsmoothedSurface record_unsmoothed_surface(const TriMesh& mesh, int threads);

// Moves vertices along their smoothed area-weighted normals (normal_iterations of Eq. 12, computed once on the
// smoothed surface) by s_c * amount_i so that component c's volume returns to its unsmoothed volume; amount empty
// means 1 everywhere. |s_c| is capped at max_offset. At most newton_steps Newton steps, until every component is within
// 1e-5 of its volume. Returns the normals it moved along: the offsets are tiny against the edge lengths, so they are
// the restored surface's normals too. With walls, applied after every step, vertices on a container's wall end on it.
// The heat flow's final correction (post/heat_smoothing.h) is this with 4 steps: its wall vertices move too and are
// put back on the wall, which slows the convergence (3 left a sphere pressed onto a wall 1.0e-4 off its volume).
SmoothedNormals restore_component_volumes(TriMesh& mesh, const MeshAdjacency& adjacency, const UnsmoothedSurface& unsmoothed,
                                          const std::vector<float>& amount, double max_offset, int normal_iterations, int threads,
                                          const WallConstraints* walls = nullptr, int newton_steps = 2);

// The smoothing iterations of the normals restoration moves along: the output's own when it asks for smoothed
// area-weighted normals (so that the normals stage can take them as they are), otherwise 10.
int restoration_normal_iterations(const PostprocessParams& post);

// Smoothing may collapse a component smaller than a few cubes (a blob around one grid point) into a point or a
// line. Such a component gets its unsmoothed positions back: smoothing never leaves a degenerate triangle or an
// inverted component. Returns the number of components reverted.
std::size_t revert_collapsed_components(TriMesh& mesh, const UnsmoothedSurface& unsmoothed, int threads);

}  // namespace meniscus
