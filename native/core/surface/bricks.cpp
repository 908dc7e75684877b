#include "surface/bricks.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "base/errors.h"
#include "base/parallel.h"
#include "surface/marching_cubes.h"

namespace meniscus {

namespace {

// Vertices are kept this fraction of a cube edge away from grid points, so that no triangle degenerates when the
// level set equals the threshold at a grid point.
constexpr double kEdgeMargin = 1e-3;

// A brick's piece of the mesh. Vertices live on grid edges and belong to the brick holding the edge's start
// point; triangles of this brick that use an edge starting in a neighbouring brick refer to it as "foreign".
struct BrickMesh {
    std::vector<float> vertices;                              // 3 per local vertex
    std::vector<int32_t> triangles;                           // >= 0: local vertex; < 0: -(foreign index + 1)
    std::vector<std::pair<LatticeCoords, uint32_t>> foreign;  // (owner brick, edge key in owner)
    std::vector<std::pair<uint32_t, int32_t>> border;         // (edge key, local vertex) for edges on the brick's low faces
};

uint32_t edge_key(int x, int y, int z, int axis) { return ((uint32_t(z) * kBrick + uint32_t(y)) * kBrick + uint32_t(x)) * 3 + uint32_t(axis); }

class BrickMesher {
public:
    BrickMesher(double cube_edge, double threshold, const MeshBox* box)
        : cube_(cube_edge), threshold_(static_cast<float>(threshold)), box_(box) {}

    BrickMesh run(const LatticeCoords& brick, BrickScratch& scratch, const BrickSampler& sample) const {
        BrickMesh out;
        const LatticeCoords base{brick[0] * kBrick, brick[1] * kBrick, brick[2] * kBrick};
        const BoxCover cover = box_cover(base);
        if (cover == kBoxOutside) return out;
        const bool crossing = sample(base, scratch);
        // A brick the wall cuts needs meshing even when wholly inside the fluid: the wall makes the surface there.
        if (cover == kBoxPartial ? !close_at_walls(base, scratch) : !crossing) return out;
        create_vertices(base, scratch, out);
        create_triangles(brick, scratch, out);
        return out;
    }

private:
    // Eq. 2: linear interpolation of the threshold crossing along the edge from grid point (x, y, z) along axis.
    void edge_vertex_position(const LatticeCoords& base, int x, int y, int z, int axis, float a, float b, float* position) const {
        const double raw = (double(threshold_) - double(a)) / (double(b) - double(a));
        const double fraction = std::min(std::max(raw, kEdgeMargin), 1.0 - kEdgeMargin);
        const int64_t g[3] = {base[0] + x, base[1] + y, base[2] + z};
        for (int k = 0; k < 3; ++k) position[k] = static_cast<float>((double(g[k]) + (k == axis ? fraction : 0.0)) * cube_);
        if (box_) place_on_wall(g, axis, raw, b, position);
    }

    // With a box: whether lattice coordinate g along axis k lies inside it (kEdgeMargin cubes within the walls).
    bool in_box(int64_t g, int k) const {
        const double p = double(g) * cube_, margin = kEdgeMargin * cube_;
        return p >= box_->lower[k] + margin && p <= box_->upper[k] - margin;
    }
    bool point_in_box(const int64_t* g) const { return in_box(g[0], 0) && in_box(g[1], 1) && in_box(g[2], 2); }

    // An edge that leaves the box: its vertex goes onto the wall unless the level set crosses the threshold before
    // the wall (seen from the end inside). An outside end whose value close_at_walls set to the threshold is
    // outside only because of the wall, so the wall is the crossing.
    void place_on_wall(const int64_t* g, int axis, double raw_fraction, float b, float* position) const {
        int64_t h[3] = {g[0], g[1], g[2]};
        h[axis] += 1;
        const bool a_in = point_in_box(g), b_in = point_in_box(h);
        if (a_in == b_in) return;
        const double wall = a_in ? box_->upper[axis] : box_->lower[axis];
        const double wall_fraction = wall / cube_ - double(g[axis]);
        const bool outside_end_at_threshold = a_in ? b >= threshold_ : raw_fraction <= 0.0;
        const bool wall_first = outside_end_at_threshold || (a_in ? wall_fraction <= raw_fraction : wall_fraction >= raw_fraction);
        if (wall_first) position[axis] = static_cast<float>(wall);
    }

    enum BoxCover { kBoxInside, kBoxPartial, kBoxOutside };
    BoxCover box_cover(const LatticeCoords& base) const {
        if (!box_) return kBoxInside;
        bool all_in = true;
        for (int k = 0; k < 3; ++k) {
            const bool lo_in = in_box(base[k], k), hi_in = in_box(base[k] + kBrick, k);
            const double lo = double(base[k]) * cube_, hi = double(base[k] + kBrick) * cube_;
            if (hi < box_->lower[k] || lo > box_->upper[k]) return kBoxOutside;
            all_in = all_in && lo_in && hi_in;
        }
        return all_in ? kBoxInside : kBoxPartial;
    }

    // Points outside the box become outside the fluid: a value above the threshold is lowered to the threshold
    // itself (which counts as outside), so place_on_wall can tell such a point from one the fluid does not reach.
    // Returns whether the brick still has both sides.
    bool close_at_walls(const LatticeCoords& base, BrickScratch& s) const {
        std::array<std::array<uint8_t, kBrickPoints>, 3> inside{};
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < kBrickPoints; ++i) inside[k][i] = in_box(base[k] + i, k);
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y)
                for (int x = 0; x < kBrickPoints; ++x) {
                    float& v = s.values[point_index(x, y, z)];
                    if (!(inside[0][x] && inside[1][y] && inside[2][z]) && v > threshold_) v = threshold_;
                }
        return crosses_threshold(s.values, threshold_);
    }

    // Rows of points along x, classified once: most rows lie wholly inside or outside, and a row of cubes (or of
    // edges) whose bounding point rows agree that way has nothing to mesh.
    enum RowState : uint8_t { kRowOutside = 0, kRowInside = 1, kRowMixed = 2 };
    void classify_rows(BrickScratch& s) const {
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y) {
                const float* row = &s.values[point_index(0, y, z)];
                int inside = 0;
                for (int x = 0; x < kBrickPoints; ++x) inside += row[x] > threshold_;
                s.row_state[z * kBrickPoints + y] = inside == 0 ? kRowOutside : inside == kBrickPoints ? kRowInside : kRowMixed;
            }
    }
    bool rows_uniform(const BrickScratch& s, int y, int z, bool cube_row) const {
        const uint8_t first = s.row_state[z * kBrickPoints + y];
        if (first == kRowMixed) return false;
        const bool same = s.row_state[z * kBrickPoints + y + 1] == first && s.row_state[(z + 1) * kBrickPoints + y] == first;
        return same && (!cube_row || s.row_state[(z + 1) * kBrickPoints + y + 1] == first);
    }

    void create_vertices(const LatticeCoords& base, BrickScratch& s, BrickMesh& out) const {
        classify_rows(s);
        for (int z = 0; z < kBrick; ++z)
            for (int y = 0; y < kBrick; ++y) {
                if (rows_uniform(s, y, z, false)) {
                    std::fill_n(&s.edge_vertex[edge_key(0, y, z, 0)], 3 * kBrick, -1);
                    continue;
                }
                for (int x = 0; x < kBrick; ++x) {
                    const float a = s.values[point_index(x, y, z)];
                    const bool a_in = a > threshold_;
                    for (int axis = 0; axis < 3; ++axis) {
                        const float b = s.values[point_index(x + (axis == 0), y + (axis == 1), z + (axis == 2))];
                        const uint32_t key = edge_key(x, y, z, axis);
                        if ((b > threshold_) == a_in) {
                            s.edge_vertex[key] = -1;
                            continue;
                        }
                        const int32_t index = static_cast<int32_t>(out.vertices.size() / 3);
                        float position[3];
                        edge_vertex_position(base, x, y, z, axis, a, b, position);
                        out.vertices.insert(out.vertices.end(), position, position + 3);
                        s.edge_vertex[key] = index;
                        if (x == 0 || y == 0 || z == 0) out.border.emplace_back(key, index);
                    }
                }
            }
    }

    // Ambiguous faces of a cube whose inside corners are joined through the face (asymptotic decider).
    unsigned joined_faces(unsigned inside, const float* corner) const {
        unsigned joined = 0;
        for (int face = 0; face < 6; ++face) {
            const auto& fc = mc::face_corners(face);
            const bool in0 = (inside >> fc[0]) & 1u, in1 = (inside >> fc[1]) & 1u, in2 = (inside >> fc[2]) & 1u, in3 = (inside >> fc[3]) & 1u;
            if (mc::face_is_ambiguous(in0, in1, in2, in3) &&
                mc::inside_corners_joined(corner[fc[0]], corner[fc[1]], corner[fc[2]], corner[fc[3]], threshold_))
                joined |= 1u << face;
        }
        return joined;
    }

    // The case's loop centres as new vertices of the brick, each at the mean of its loop's edge vertices.
    void add_centre_vertices(const LatticeCoords& base, int x, int y, int z, const float* corner, const mc::Case& cube_case,
                             int32_t* centre_vertex, BrickMesh& out) const {
        const auto& edges = mc::edges();
        for (int k = 0; k < cube_case.centre_count; ++k) {
            double sum[3] = {0, 0, 0};
            int members = 0;
            for (int edge = 0; edge < 12; ++edge) {
                if (!((cube_case.centre_loops[k] >> edge) & 1u)) continue;
                const mc::Edge& e = edges[edge];
                const int c1 = e.corner | (1 << e.axis);
                float position[3];
                edge_vertex_position(base, x + (e.corner & 1), y + ((e.corner >> 1) & 1), z + ((e.corner >> 2) & 1), e.axis,
                                     corner[e.corner], corner[c1], position);
                for (int d = 0; d < 3; ++d) sum[d] += position[d];
                ++members;
            }
            centre_vertex[k] = static_cast<int32_t>(out.vertices.size() / 3);
            for (int d = 0; d < 3; ++d) out.vertices.push_back(static_cast<float>(sum[d] / members));
        }
    }

    // The case's triangles of cube (x, y, z): edge vertices of this brick by index, those of edges starting in a
    // neighbouring brick as foreign references, centres as just created.
    void add_cube_triangles(const LatticeCoords& brick, int x, int y, int z, const mc::Case& cube_case, const int32_t* centre_vertex,
                            const BrickScratch& s, BrickMesh& out) const {
        const auto& edges = mc::edges();
        for (int i = 0; i < 3 * cube_case.triangle_count; ++i) {
            if (cube_case.edges[i] >= 12) {
                out.triangles.push_back(centre_vertex[cube_case.edges[i] - 12]);
                continue;
            }
            const mc::Edge& e = edges[cube_case.edges[i]];
            const int px = x + (e.corner & 1), py = y + ((e.corner >> 1) & 1), pz = z + ((e.corner >> 2) & 1);
            if (px < kBrick && py < kBrick && pz < kBrick) {
                out.triangles.push_back(s.edge_vertex[edge_key(px, py, pz, e.axis)]);
            } else {
                const LatticeCoords owner{brick[0] + (px >= kBrick), brick[1] + (py >= kBrick), brick[2] + (pz >= kBrick)};
                out.foreign.emplace_back(owner, edge_key(px % kBrick, py % kBrick, pz % kBrick, e.axis));
                out.triangles.push_back(-static_cast<int32_t>(out.foreign.size()));
            }
        }
    }

    void create_triangles(const LatticeCoords& brick, BrickScratch& s, BrickMesh& out) const {
        const LatticeCoords base{brick[0] * kBrick, brick[1] * kBrick, brick[2] * kBrick};
        float corner[8];
        for (int z = 0; z < kBrick; ++z)
            for (int y = 0; y < kBrick; ++y) {
                if (rows_uniform(s, y, z, true)) continue;
                for (int x = 0; x < kBrick; ++x) {
                    unsigned inside = 0;
                    for (int c = 0; c < 8; ++c) {
                        corner[c] = s.values[point_index(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1))];
                        if (corner[c] > threshold_) inside |= 1u << c;
                    }
                    if (inside == 0 || inside == 255) continue;
                    const mc::Case& cube_case = mc::lookup(inside, joined_faces(inside, corner));
                    int32_t centre_vertex[mc::kMaxCentres];
                    add_centre_vertices(base, x, y, z, corner, cube_case, centre_vertex, out);
                    add_cube_triangles(brick, x, y, z, cube_case, centre_vertex, s, out);
                }
            }
        std::sort(out.border.begin(), out.border.end());
    }

    double cube_;
    float threshold_;
    const MeshBox* box_;
};

}  // namespace

bool crosses_threshold(const std::vector<float>& values, float threshold) {
    bool any_inside = false, any_outside = false;
    for (float v : values) {
        if (v > threshold) any_inside = true;
        else any_outside = true;
        if (any_inside && any_outside) return true;
    }
    return false;
}

// Meshes every brick independently, then stitches: global vertex numbers follow the brick order, and foreign
// references are resolved through the owner brick's border list.
TriMesh mesh_bricks(const std::vector<LatticeCoords>& bricks, const BrickSampler& sample, double cube, double threshold, int threads,
                    const MeshBox* box) {
    std::vector<BrickMesh> pieces(bricks.size());
    {
        BrickMesher mesher(cube, threshold, box);
        ParallelErrors errors;
        parallel_region(threads, [&] {
            std::unique_ptr<BrickScratch> scratch;
            errors.run([&] { scratch = std::make_unique<BrickScratch>(); });
#pragma omp for schedule(dynamic, 1)
            for (int64_t b = 0; b < static_cast<int64_t>(bricks.size()); ++b)
                errors.run([&] { pieces[static_cast<std::size_t>(b)] = mesher.run(bricks[static_cast<std::size_t>(b)], *scratch, sample); });
        });
        errors.rethrow();
    }
    TriMesh mesh;
    std::vector<std::size_t> vertex_offset(pieces.size() + 1, 0), triangle_offset(pieces.size() + 1, 0);
    for (std::size_t b = 0; b < pieces.size(); ++b) {
        vertex_offset[b + 1] = vertex_offset[b] + pieces[b].vertices.size() / 3;
        triangle_offset[b + 1] = triangle_offset[b] + pieces[b].triangles.size();
    }
    if (vertex_offset.back() >= static_cast<std::size_t>(INT32_MAX))
        throw ResourceError("the mesh has " + std::to_string(vertex_offset.back()) + " vertices, more than 32-bit indices allow; use a larger cube size");
    // A mesh's arrays are std::vectors, whose resize zero-fills them on one thread (taking their page faults, ~90 MB
    // at a million particles): the two at least side by side.
    parallel_for(2, threads, [&](int64_t array) {
        if (array == 0) mesh.vertices.resize(3 * vertex_offset.back());
        else mesh.triangles.resize(triangle_offset.back());
    });
    parallel_for(static_cast<int64_t>(pieces.size()), threads, [&](int64_t b) {
        const BrickMesh& piece = pieces[static_cast<std::size_t>(b)];
        std::copy(piece.vertices.begin(), piece.vertices.end(), mesh.vertices.begin() + static_cast<std::ptrdiff_t>(3 * vertex_offset[b]));
        std::vector<int32_t> resolved(piece.foreign.size());
        for (std::size_t f = 0; f < piece.foreign.size(); ++f) {
            const auto& ref = piece.foreign[f];
            const auto owner = std::lower_bound(bricks.begin(), bricks.end(), ref.first, coords_less);
            if (owner == bricks.end() || *owner != ref.first) throw std::logic_error("marching cubes: edge owner brick is not active");
            const std::size_t o = static_cast<std::size_t>(owner - bricks.begin());
            const auto& border = pieces[o].border;
            const auto it = std::lower_bound(border.begin(), border.end(), std::make_pair(ref.second, INT32_MIN));
            if (it == border.end() || it->first != ref.second) throw std::logic_error("marching cubes: owner brick lacks a shared edge vertex");
            resolved[f] = static_cast<int32_t>(vertex_offset[o]) + it->second;
        }
        int32_t* target = mesh.triangles.data() + triangle_offset[b];
        for (std::size_t i = 0; i < piece.triangles.size(); ++i) {
            const int32_t v = piece.triangles[i];
            target[i] = v >= 0 ? static_cast<int32_t>(vertex_offset[b]) + v : resolved[static_cast<std::size_t>(-v - 1)];
        }
    });
    return mesh;
}

TriMesh marching_cubes_on_function(const std::function<float(double, double, double)>& field, const double lower[3],
                                   const double upper[3], double cube_edge, double threshold, int threads) {
    if (!(cube_edge > 0.0)) throw InputError("cube_edge must be positive");
    LatticeCoords lo, hi;
    for (int k = 0; k < 3; ++k) {
        lo[k] = floor_div(static_cast<int64_t>(std::floor(lower[k] / cube_edge)), kBrick);
        hi[k] = floor_div(static_cast<int64_t>(std::ceil(upper[k] / cube_edge)), kBrick);
    }
    std::vector<LatticeCoords> bricks;
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
        for (int64_t y = lo[1]; y <= hi[1]; ++y)
            for (int64_t x = lo[0]; x <= hi[0]; ++x) bricks.push_back({x, y, z});
    const float t = static_cast<float>(threshold);
    const BrickSampler sample = [&](const LatticeCoords& base, BrickScratch& s) {
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y)
                for (int x = 0; x < kBrickPoints; ++x)
                    s.values[point_index(x, y, z)] =
                        field(double(base[0] + x) * cube_edge, double(base[1] + y) * cube_edge, double(base[2] + z) * cube_edge);
        return crosses_threshold(s.values, t);
    };
    return mesh_bricks(bricks, sample, cube_edge, threshold, threads);
}

}  // namespace meniscus
