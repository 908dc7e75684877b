// Marching cubes (paper Sec. 3.1, Eq. 2) over a sparse set of bricks: the lattice of cube edge c, anchored at the
// origin, is cut into bricks of kBrick^3 cubes; each brick is sampled (its level set at its (kBrick + 1)^3 points)
// and meshed on its own, in parallel, with the case table of marching_cubes.h. The pieces are stitched by edge
// ownership: an edge's vertex belongs to the brick holding the edge's start point, and global vertex numbers follow
// the brick order. So the mesh is the same, bit for bit, for any thread count.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "mesh/mesh.h"

namespace meniscus {

// Cubes per brick edge: a brick of 32^3 cubes needs 33^3 floats (144 KiB) of level set, which stays in L2.
constexpr int kBrick = 32;
constexpr int kBrickPoints = kBrick + 1;

// Integer coordinates on the lattice of cubes (a point) or of bricks (a brick).
using LatticeCoords = std::array<int64_t, 3>;

// Rounds a / b towards minus infinity (b > 0): the brick of a lattice coordinate.
inline int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Order of the bricks (z, then y, then x): the order they are stitched in.
inline bool coords_less(const LatticeCoords& a, const LatticeCoords& b) {
    if (a[2] != b[2]) return a[2] < b[2];
    if (a[1] != b[1]) return a[1] < b[1];
    return a[0] < b[0];
}

// Index of brick point (x, y, z), 0 <= x, y, z <= kBrick, in BrickScratch::values.
inline int point_index(int x, int y, int z) { return (z * kBrickPoints + y) * kBrickPoints + x; }

// Working memory of one thread's bricks, allocated once per thread.
struct BrickScratch {
    std::vector<float> values = std::vector<float>(kBrickPoints * kBrickPoints * kBrickPoints);  // the level set
    std::vector<int32_t> edge_vertex = std::vector<int32_t>(kBrick * kBrick * kBrick * 3);
    std::vector<uint8_t> row_state = std::vector<uint8_t>(kBrickPoints * kBrickPoints);
    std::vector<float> dx2, dy2, dz2;  // the colour-field sampler's squared distances along each axis
};

// Fills scratch.values with the level set at the points of the brick whose first point is `base` (lattice point
// coordinates); returns false when no surface crosses the brick. Called concurrently, each thread with its own scratch.
using BrickSampler = std::function<bool(const LatticeCoords& base, BrickScratch& scratch)>;

// Whether `values` has points on both sides of the threshold (inside: value > threshold).
bool crosses_threshold(const std::vector<float>& values, float threshold);

// A container's walls closing the surface (post/container.h): lattice points outside the box count as outside the
// fluid, so the surface is the fluid's intersection with the box, closed by flat faces on the walls. An edge leaving
// the box gets its vertex on the wall's plane exactly (the coordinate is the plane's, not an interpolation), unless
// the level set crosses the threshold first. Points within kEdgeMargin cubes inside a wall count as outside, so no
// vertex lands on a lattice point.
struct MeshBox {
    std::array<double, 3> lower{}, upper{};
};

// The mesh of the given bricks (sorted by coords_less, unique): every edge with a sign change must start in one of
// them, so that its vertex has an owner that creates it. With a box, the surface is closed against its walls.
TriMesh mesh_bricks(const std::vector<LatticeCoords>& bricks, const BrickSampler& sample, double cube_edge, double threshold,
                    int threads, const MeshBox* box = nullptr);

// Marching cubes alone, on a field given as a function (for tests and analytic surfaces): the same table, bricks
// and stitching as the reconstruction, over the lattice of cube_edge covering [lower, upper]. The field must be
// below the threshold on and outside that box for the mesh to be closed.
TriMesh marching_cubes_on_function(const std::function<float(double, double, double)>& field, const double lower[3],
                                   const double upper[3], double cube_edge, double threshold, int threads);

}  // namespace meniscus
