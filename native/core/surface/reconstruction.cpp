#include "surface/reconstruction.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <string>

#if defined(__SSE2__) || defined(_M_X64)
#include <immintrin.h>
#endif

#include "base/errors.h"
#include "sph/kernel.h"
#include "surface/marching_cubes.h"
#include "base/memory.h"
#include "base/parallel.h"

namespace meniscus {

namespace {

// Cubes per brick edge: a brick of 32^3 cubes needs 33^3 floats (144 KiB) of level set, which stays in L2.
constexpr int kBrick = 32;
constexpr int kBrickPoints = kBrick + 1;
// Vertices are kept this fraction of a cube edge away from grid points, so that no triangle degenerates when the
// level set equals the threshold at a grid point.
constexpr double kEdgeMargin = 1e-3;

using Coords = std::array<int64_t, 3>;

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

bool coords_less(const Coords& a, const Coords& b) {
    if (a[2] != b[2]) return a[2] < b[2];
    if (a[1] != b[1]) return a[1] < b[1];
    return a[0] < b[0];
}

// A brick's piece of the mesh. Vertices live on grid edges and belong to the brick holding the edge's start
// point; triangles of this brick that use an edge starting in a neighbouring brick refer to it as "foreign".
struct BrickMesh {
    std::vector<float> vertices;                          // 3 per local vertex
    std::vector<int32_t> triangles;                       // >= 0: local vertex; < 0: -(foreign index + 1)
    std::vector<std::pair<Coords, uint32_t>> foreign;     // (owner brick, edge key in owner)
    std::vector<std::pair<uint32_t, int32_t>> border;     // (edge key, local vertex) for edges on the brick's low faces
};

uint32_t edge_key(int x, int y, int z, int axis) { return ((uint32_t(z) * kBrick + uint32_t(y)) * kBrick + uint32_t(x)) * 3 + uint32_t(axis); }

struct Scratch {
    std::vector<float> values = std::vector<float>(kBrickPoints * kBrickPoints * kBrickPoints);
    std::vector<int32_t> edge_vertex = std::vector<int32_t>(kBrick * kBrick * kBrick * 3);
    std::vector<uint8_t> row_state = std::vector<uint8_t>(kBrickPoints * kBrickPoints);
    std::vector<float> dx2, dy2, dz2;
};

int point_index(int x, int y, int z) { return (z * kBrickPoints + y) * kBrickPoints + x; }

bool crosses_threshold(const std::vector<float>& values, float threshold) {
    bool any_inside = false, any_outside = false;
    for (float v : values) {
        if (v > threshold) any_inside = true;
        else any_outside = true;
        if (any_inside && any_outside) return true;
    }
    return false;
}

// Adds factor * W-shape(q) to row[0 .. n) with q = sqrt(dyz + dx2[i]) / H. With a = max(1 - q, 0) and
// b = max(1 - 2q, 0) the cubic spline is 2a^3 - b^3 on all of [0, 1] and exactly 0 beyond: no branch. Written with
// SSE intrinsics where available because the compiler turns the max into four instructions (a blend, for NaN
// semantics the values here cannot have); the scalar tail does the same operations in the same order, so every
// point gets the same bits either way.
inline float spline_shape(float q) {
    const float a = std::max(1.0f - q, 0.0f), b = std::max(1.0f - 2.0f * q, 0.0f);
    return 2.0f * a * a * a - b * b * b;
}

inline void splat_row(float* row, const float* dx2, int n, float dyz, float inverse_support, float factor) {
    int i = 0;
#if defined(__SSE2__) || defined(_M_X64)
    const __m128 dyz4 = _mm_set1_ps(dyz), inverse4 = _mm_set1_ps(inverse_support), factor4 = _mm_set1_ps(factor);
    const __m128 one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f), zero = _mm_setzero_ps();
    for (; i + 4 <= n; i += 4) {
        const __m128 q = _mm_mul_ps(_mm_sqrt_ps(_mm_add_ps(dyz4, _mm_loadu_ps(dx2 + i))), inverse4);
        const __m128 a = _mm_max_ps(_mm_sub_ps(one, q), zero);
        const __m128 b = _mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(two, q)), zero);
        const __m128 shape = _mm_sub_ps(_mm_mul_ps(_mm_mul_ps(_mm_mul_ps(two, a), a), a), _mm_mul_ps(_mm_mul_ps(b, b), b));
        _mm_storeu_ps(row + i, _mm_add_ps(_mm_loadu_ps(row + i), _mm_mul_ps(factor4, shape)));
    }
#endif
    for (; i < n; ++i) row[i] += factor * spline_shape(std::sqrt(dyz + dx2[i]) * inverse_support);
}

class ParticleSampler {
public:
    ParticleSampler(const SurfaceReconstruction& r, const CubicSplineKernel& kernel)
        : r_(r), kernel_(kernel), cube_(r.params.cube_edge()), threshold_(static_cast<float>(r.params.iso_threshold)) {}

    // Colour field (Eq. 1) at the brick's (B+1)^3 points. Particles are visited in sorted order, and each point
    // adds its contributions in that order: a point shared with a neighbouring brick gets the same value, bit for
    // bit, so both bricks agree on which side of the surface it is. Returns false when no surface crosses the brick.
    bool operator()(const Coords& base, Scratch& s) const {
        std::fill(s.values.begin(), s.values.end(), 0.0f);
        const double support = kernel_.support();
        const float support_squared = kernel_.support_squared();
        const double cell = r_.grid.cell_size();
        Coords lo, hi;
        for (int k = 0; k < 3; ++k) {
            // One extra cell on each side: rounding of a particle's cell must not drop it from the gather.
            lo[k] = static_cast<int64_t>(std::floor((double(base[k]) * cube_ - support) / cell)) - 1;
            hi[k] = static_cast<int64_t>(std::floor((double(base[k] + kBrick) * cube_ + support) / cell)) + 1;
        }
        const float inverse_support = 1.0f / kernel_.support();
        r_.grid.for_each_cell_in_box(lo, hi, [&](std::size_t c) {
            for (std::size_t j = r_.grid.cell_begin(c); j < r_.grid.cell_end(c); ++j) {
                const float* x = r_.grid.position(j);
                int64_t first[3], last[3];
                bool empty = false;
                for (int k = 0; k < 3; ++k) {
                    first[k] = std::max<int64_t>(static_cast<int64_t>(std::ceil((double(x[k]) - support) / cube_)), base[k]);
                    last[k] = std::min<int64_t>(static_cast<int64_t>(std::floor((double(x[k]) + support) / cube_)), base[k] + kBrick);
                    if (first[k] > last[k]) empty = true;
                }
                if (empty) continue;
                auto fill_axis = [&](std::vector<float>& d2, int k) {
                    d2.resize(static_cast<std::size_t>(last[k] - first[k] + 1));
                    for (int64_t g = first[k]; g <= last[k]; ++g) {
                        const float d = grid_coordinate(g) - x[k];
                        d2[static_cast<std::size_t>(g - first[k])] = d * d;
                    }
                };
                fill_axis(s.dx2, 0);
                fill_axis(s.dy2, 1);
                fill_axis(s.dz2, 2);
                const float factor = r_.volumes[j] * kernel_.value(0.0f);  // V_j * 8/(pi H^3)
                const int nx = static_cast<int>(s.dx2.size()), ny = static_cast<int>(s.dy2.size()), nz = static_cast<int>(s.dz2.size());
                const int ox = static_cast<int>(first[0] - base[0]), oy = static_cast<int>(first[1] - base[1]), oz = static_cast<int>(first[2] - base[2]);
                for (int iz = 0; iz < nz; ++iz) {
                    for (int iy = 0; iy < ny; ++iy) {
                        const float dyz = s.dz2[iz] + s.dy2[iy];
                        if (dyz >= support_squared) continue;
                        splat_row(&s.values[point_index(ox, oy + iy, oz + iz)], s.dx2.data(), nx, dyz, inverse_support, factor);
                    }
                }
            }
        });
        return crosses_threshold(s.values, threshold_);
    }

private:
    float grid_coordinate(int64_t g) const { return static_cast<float>(static_cast<double>(g) * cube_); }

    const SurfaceReconstruction& r_;
    const CubicSplineKernel& kernel_;
    double cube_;
    float threshold_;
};

// Fills a brick's (B+1)^3 level-set values; returns false when no surface crosses the brick.
using Sampler = std::function<bool(const Coords& base, Scratch& scratch)>;

class BrickMesher {
public:
    BrickMesher(double cube_edge, double threshold) : cube_(cube_edge), threshold_(static_cast<float>(threshold)) {}

    BrickMesh run(const Coords& brick, Scratch& scratch, const Sampler& sample) const {
        BrickMesh out;
        const Coords base{brick[0] * kBrick, brick[1] * kBrick, brick[2] * kBrick};
        if (!sample(base, scratch)) return out;
        create_vertices(base, scratch, out);
        create_triangles(brick, scratch, out);
        return out;
    }

private:
    // Eq. 2: linear interpolation of the threshold crossing along the edge from grid point (x, y, z) along axis.
    void edge_vertex_position(const Coords& base, int x, int y, int z, int axis, float a, float b, float* position) const {
        double fraction = (double(threshold_) - double(a)) / (double(b) - double(a));
        fraction = std::min(std::max(fraction, kEdgeMargin), 1.0 - kEdgeMargin);
        const int64_t g[3] = {base[0] + x, base[1] + y, base[2] + z};
        for (int k = 0; k < 3; ++k) position[k] = static_cast<float>((double(g[k]) + (k == axis ? fraction : 0.0)) * cube_);
    }

    // Rows of points along x, classified once: most rows lie wholly inside or outside, and a row of cubes (or of
    // edges) whose bounding point rows agree that way has nothing to mesh.
    enum RowState : uint8_t { kRowOutside = 0, kRowInside = 1, kRowMixed = 2 };
    void classify_rows(Scratch& s) const {
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y) {
                const float* row = &s.values[point_index(0, y, z)];
                int inside = 0;
                for (int x = 0; x < kBrickPoints; ++x) inside += row[x] > threshold_;
                s.row_state[z * kBrickPoints + y] = inside == 0 ? kRowOutside : inside == kBrickPoints ? kRowInside : kRowMixed;
            }
    }
    bool rows_uniform(const Scratch& s, int y, int z, bool cube_row) const {
        const uint8_t first = s.row_state[z * kBrickPoints + y];
        if (first == kRowMixed) return false;
        const bool same = s.row_state[z * kBrickPoints + y + 1] == first && s.row_state[(z + 1) * kBrickPoints + y] == first;
        return same && (!cube_row || s.row_state[(z + 1) * kBrickPoints + y + 1] == first);
    }

    void create_vertices(const Coords& base, Scratch& s, BrickMesh& out) const {
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

    void create_triangles(const Coords& brick, Scratch& s, BrickMesh& out) const {
        const Coords base{brick[0] * kBrick, brick[1] * kBrick, brick[2] * kBrick};
        const auto& edges = mc::edges();
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
                    unsigned joined = 0;
                    for (int face = 0; face < 6; ++face) {
                        const auto& fc = mc::face_corners(face);
                        const bool in0 = (inside >> fc[0]) & 1u, in1 = (inside >> fc[1]) & 1u, in2 = (inside >> fc[2]) & 1u,
                                   in3 = (inside >> fc[3]) & 1u;
                        if (mc::face_is_ambiguous(in0, in1, in2, in3) &&
                            mc::inside_corners_joined(corner[fc[0]], corner[fc[1]], corner[fc[2]], corner[fc[3]], threshold_))
                            joined |= 1u << face;
                    }
                    const mc::Case& cube_case = mc::lookup(inside, joined);
                    int32_t centre_vertex[mc::kMaxCentres];
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
                            const Coords owner{brick[0] + (px >= kBrick), brick[1] + (py >= kBrick), brick[2] + (pz >= kBrick)};
                            out.foreign.emplace_back(owner, edge_key(px % kBrick, py % kBrick, pz % kBrick, e.axis));
                            out.triangles.push_back(-static_cast<int32_t>(out.foreign.size()));
                        }
                    }
                }
            }
        std::sort(out.border.begin(), out.border.end());
    }

    double cube_;
    float threshold_;
};

// Meshes every brick independently, then stitches: global vertex numbers follow the brick order, and foreign
// references are resolved through the owner brick's border list.
TriMesh mesh_bricks(const std::vector<Coords>& bricks, const Sampler& sample, double cube, double threshold, int threads) {
    std::vector<BrickMesh> pieces(bricks.size());
    {
        BrickMesher mesher(cube, threshold);
        ParallelErrors errors;
#pragma omp parallel num_threads(threads)
        {
            std::unique_ptr<Scratch> scratch;
            errors.run([&] { scratch = std::make_unique<Scratch>(); });
#pragma omp for schedule(dynamic, 1)
            for (int64_t b = 0; b < static_cast<int64_t>(bricks.size()); ++b)
                errors.run([&] { pieces[static_cast<std::size_t>(b)] = mesher.run(bricks[static_cast<std::size_t>(b)], *scratch, sample); });
        }
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
    mesh.vertices.resize(3 * vertex_offset.back());
    mesh.triangles.resize(triangle_offset.back());
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

// Sorted particle coordinates as x, y, z arrays padded by one block of kLanes, for neighbour loops that visit
// candidates kLanes at a time without a branch: only about 15 % of the particles of the 27 cells around a point
// lie within the support, and a branch per candidate mispredicts too often. Lane l sums the candidates
// j = l (mod kLanes) of each range and the lanes are added in order at the end: the same sum for any thread count.
constexpr int kLanes = 8;

struct LanePositions {
    std::vector<float> x, y, z;
    explicit LanePositions(const ParticleGrid& grid) : x(grid.size() + kLanes), y(grid.size() + kLanes), z(grid.size() + kLanes) {
        for (std::size_t j = 0; j < grid.size(); ++j) x[j] = grid.position(j)[0], y[j] = grid.position(j)[1], z[j] = grid.position(j)[2];
    }
};

// A per-particle array padded by one block, so that lane loops may read past the last particle.
std::vector<float> padded(const std::vector<float>& values) {
    std::vector<float> out(values.size() + kLanes, 0.0f);
    std::copy(values.begin(), values.end(), out.begin());
    return out;
}

// Densities (rho_j / m_j = W(0) + sum_k W_jk, so that V_j = m_j / rho_j needs no rest density) and the hat-weighted
// neighbour counts of Eq. 10-11 with h = H, in one pass over the cell neighbourhoods.
void compute_particle_quantities(SurfaceReconstruction& r, const CubicSplineKernel& kernel, int threads) {
    const ParticleGrid& grid = r.grid;
    const std::size_t n = grid.size();
    r.volumes.assign(n, 0.0f);
    r.neighbor_counts.assign(n, 0.0f);
    const float support_squared = kernel.support_squared();
    const float inverse_support = 1.0f / kernel.support();
    const float normalisation = kernel.value(0.0f);  // W(0) = 8 / (pi H^3): shapes are summed, scaled once
    const LanePositions lanes(grid);
    const float *xs = lanes.x.data(), *ys = lanes.y.data(), *zs = lanes.z.data();
    parallel_for(static_cast<int64_t>(grid.num_cells()), threads, [&](int64_t cell) {
        const auto c = grid.cell_coords(static_cast<std::size_t>(cell));
        std::array<std::pair<std::size_t, std::size_t>, 27> ranges;
        int range_count = 0;
        grid.for_each_cell_in_box({c[0] - 1, c[1] - 1, c[2] - 1}, {c[0] + 1, c[1] + 1, c[2] + 1}, [&](std::size_t other) {
            ranges[range_count++] = {grid.cell_begin(other), grid.cell_end(other)};
        });
        for (std::size_t i = grid.cell_begin(cell); i < grid.cell_end(cell); ++i) {
            const float xi = xs[i], yi = ys[i], zi = zs[i];
            float shape_sum[kLanes] = {}, hat_sum[kLanes] = {};
            for (int k = 0; k < range_count; ++k) {
                const std::size_t end = ranges[k].second;
                for (std::size_t block = ranges[k].first; block < end; block += kLanes) {
                    const int valid_lanes = static_cast<int>(std::min<std::size_t>(kLanes, end - block));
                    const int self_lane = i >= block && i < block + kLanes ? static_cast<int>(i - block) : -1;
                    const float *bx = xs + block, *by = ys + block, *bz = zs + block;
                    for (int l = 0; l < kLanes; ++l) {
                        const float dx = xi - bx[l], dy = yi - by[l], dz = zi - bz[l];
                        const float d2 = dx * dx + dy * dy + dz * dz;
                        // 1 or 0 as a factor rather than a branch (positions are finite, so 0 * value is 0).
                        const float counts = static_cast<float>((l < valid_lanes) & (l != self_lane) & (d2 < support_squared));
                        const float q = std::sqrt(d2) * inverse_support;
                        shape_sum[l] += counts * spline_shape(q);
                        hat_sum[l] += counts * (1.0f - q);  // Eq. 10-11: linear hat with h = H
                    }
                }
            }
            float shape = 0.0f, count = 0.0f;
            for (int l = 0; l < kLanes; ++l) shape += shape_sum[l], count += hat_sum[l];
            r.volumes[i] = 1.0f / (normalisation * (1.0f + shape));  // rho_i / m_i = W(0) + sum_j W_ij
            r.neighbor_counts[i] = count;
        }
    }, 16);
}

// Rough upper estimate of the bytes the mesh of this frame needs, from the particle cells on the fluid's boundary
// (cells with a missing face neighbour): each carries about one kernel support squared of surface, meshed with
// about 4 triangles per cube face area; about 120 bytes per triangle cover the mesh, the bricks' pieces before
// stitching and the post-processing's adjacency.
double estimate_mesh_bytes(const ParticleGrid& grid, double cube_edge, std::size_t* estimated_triangles) {
    std::size_t boundary_cells = 0;
    for (std::size_t cell = 0; cell < grid.num_cells(); ++cell) {
        const auto c = grid.cell_coords(cell);
        int neighbours = 0;
        const int64_t offsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& o : offsets)
            grid.for_each_cell_in_box({c[0] + o[0], c[1] + o[1], c[2] + o[2]}, {c[0] + o[0], c[1] + o[1], c[2] + o[2]},
                                      [&](std::size_t) { ++neighbours; });
        if (neighbours < 6) ++boundary_cells;
    }
    const double ratio = grid.cell_size() / cube_edge;
    const double triangles = 4.0 * double(boundary_cells) * ratio * ratio;
    if (estimated_triangles) *estimated_triangles = static_cast<std::size_t>(std::min(triangles, 1e18));
    return triangles * 120.0;
}

}  // namespace

SurfaceReconstruction reconstruct_surface(const PositionsView& positions, const ReconstructionParams& params,
                                          const ExecutionOptions& execution, PipelineStats* stats) {
    validate(params);
    const int threads = resolve_threads(execution.threads);

    // Non-finite positions: refused with a count, or dropped when the caller asked for it.
    std::vector<uint8_t> keep;
    std::size_t invalid = 0, first_invalid = 0;
    for (std::size_t i = 0; i < positions.count; ++i) {
        const bool finite = std::isfinite(positions.coord(i, 0)) && std::isfinite(positions.coord(i, 1)) && std::isfinite(positions.coord(i, 2));
        if (!finite && invalid++ == 0) first_invalid = i;
    }
    if (invalid > 0) {
        if (!execution.skip_invalid)
            throw InputError(std::to_string(invalid) + " of " + std::to_string(positions.count) +
                             " particles have NaN or Inf coordinates (the first is particle " + std::to_string(first_invalid) +
                             "); pass skip_invalid (--skip-invalid) to drop them");
        keep.resize(positions.count);
        for (std::size_t i = 0; i < positions.count; ++i)
            keep[i] = std::isfinite(positions.coord(i, 0)) && std::isfinite(positions.coord(i, 1)) && std::isfinite(positions.coord(i, 2));
        if (stats) stats->warnings.push_back("dropped " + std::to_string(invalid) + " particles with NaN or Inf coordinates");
    }

    const double support = params.compact_support();
    const double cube = params.cube_edge();
    StageTimer grid_timer(stats, "neighborhood");
    SurfaceReconstruction r{params, ParticleGrid(positions, support, threads, keep.empty() ? nullptr : &keep), {}, {}, {}};
    grid_timer.stop();

    std::size_t estimated_triangles = 0;
    const double estimate = estimate_mesh_bytes(r.grid, cube, &estimated_triangles);
    check_memory_budget(estimate, execution.memory_budget_bytes(),
                        "the surface mesh at cube size " + format_number(params.cube_size) + " r (about " + std::to_string(estimated_triangles) +
                            " triangles)");

    CubicSplineKernel kernel(support);
    {
        StageTimer timer(stats, "density");
        compute_particle_quantities(r, kernel, threads);
    }

    StageTimer mc_timer(stats, "level set and marching cubes");
    // Active bricks: those within H + one cube of a particle's cell. The extra cube guarantees that every edge with
    // a sign change starts in an active brick, so each vertex has an owner that creates it.
    std::vector<Coords> bricks;
    {
        std::vector<std::vector<Coords>> per_thread(static_cast<std::size_t>(threads));
        const double cell = r.grid.cell_size();
        const double margin = support + cube;
        ParallelErrors errors;
#pragma omp parallel num_threads(threads)
        {
            int thread = 0;
#ifdef _OPENMP
            thread = omp_get_thread_num();
#endif
            std::vector<Coords>& mine = per_thread[static_cast<std::size_t>(thread)];
#pragma omp for schedule(static)
            for (int64_t cell_index = 0; cell_index < static_cast<int64_t>(r.grid.num_cells()); ++cell_index)
                errors.run([&] {
                    const auto c = r.grid.cell_coords(static_cast<std::size_t>(cell_index));
                    Coords lo, hi;
                    for (int k = 0; k < 3; ++k) {
                        lo[k] = floor_div(static_cast<int64_t>(std::floor((double(c[k]) * cell - margin) / cube)), kBrick);
                        hi[k] = floor_div(static_cast<int64_t>(std::ceil((double(c[k] + 1) * cell + margin) / cube)), kBrick);
                    }
                    for (int64_t z = lo[2]; z <= hi[2]; ++z)
                        for (int64_t y = lo[1]; y <= hi[1]; ++y)
                            for (int64_t x = lo[0]; x <= hi[0]; ++x) mine.push_back({x, y, z});
                });
        }
        errors.rethrow();
        for (auto& list : per_thread) bricks.insert(bricks.end(), list.begin(), list.end());
        std::sort(bricks.begin(), bricks.end(), coords_less);
        bricks.erase(std::unique(bricks.begin(), bricks.end()), bricks.end());
    }

    r.mesh = mesh_bricks(bricks, ParticleSampler(r, kernel), cube, params.iso_threshold, threads);
    mc_timer.stop();
    if (stats) {
        stats->set_count("particles", static_cast<double>(r.grid.size()));
        stats->set_count("active_bricks", static_cast<double>(bricks.size()));
        stats->set_count("raw_vertices", static_cast<double>(r.mesh.num_vertices()));
        stats->set_count("raw_triangles", static_cast<double>(r.mesh.num_triangles()));
    }
    return r;
}

TriMesh marching_cubes_on_function(const std::function<float(double, double, double)>& field, const double lower[3],
                                   const double upper[3], double cube_edge, double threshold, int threads) {
    if (!(cube_edge > 0.0)) throw InputError("cube_edge must be positive");
    Coords lo, hi;
    for (int k = 0; k < 3; ++k) {
        lo[k] = floor_div(static_cast<int64_t>(std::floor(lower[k] / cube_edge)), kBrick);
        hi[k] = floor_div(static_cast<int64_t>(std::ceil(upper[k] / cube_edge)), kBrick);
    }
    std::vector<Coords> bricks;
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
        for (int64_t y = lo[1]; y <= hi[1]; ++y)
            for (int64_t x = lo[0]; x <= hi[0]; ++x) bricks.push_back({x, y, z});
    const float t = static_cast<float>(threshold);
    const Sampler sample = [&](const Coords& base, Scratch& s) {
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y)
                for (int x = 0; x < kBrickPoints; ++x)
                    s.values[point_index(x, y, z)] =
                        field(double(base[0] + x) * cube_edge, double(base[1] + y) * cube_edge, double(base[2] + z) * cube_edge);
        return crosses_threshold(s.values, t);
    };
    return mesh_bricks(bricks, sample, cube_edge, threshold, threads);
}

namespace {

template <class ValueAt>
void interpolate(const SurfaceReconstruction& r, ValueAt&& value_at, int components, const std::vector<float>& points,
                 std::vector<float>& out, int threads) {
    if (components < 1 || components > 16) throw InputError("interpolation takes 1 to 16 components, got " + std::to_string(components));
    const std::size_t n = points.size() / 3;
    out.assign(n * static_cast<std::size_t>(components), 0.0f);
    CubicSplineKernel kernel(r.params.compact_support());
    constexpr int64_t kBlock = 256;
    parallel_for((static_cast<int64_t>(n) + kBlock - 1) / kBlock, threads, [&](int64_t block) {
        ParticleGrid::NeighborCells cache;
        double sum[16];
        const int64_t end = std::min<int64_t>(static_cast<int64_t>(n), (block + 1) * kBlock);
        for (int64_t p = block * kBlock; p < end; ++p) {
            double weight_sum = 0.0;
            std::fill(sum, sum + components, 0.0);
            r.grid.for_each_neighbor(&points[3 * p], kernel.support(), cache, [&](std::size_t j, float d2) {
                const double w = double(r.volumes[j]) * kernel.value(std::sqrt(d2));
                weight_sum += w;
                const float* v = value_at(j);
                for (int k = 0; k < components; ++k) sum[k] += w * v[k];
            });
            if (weight_sum > 0.0)
                for (int k = 0; k < components; ++k) out[static_cast<std::size_t>(p) * components + k] = static_cast<float>(sum[k] / weight_sum);
        }
    });
}

}  // namespace

void interpolate_at_points(const SurfaceReconstruction& r, const float* values, int components, const std::vector<float>& points,
                           std::vector<float>& out, int threads) {
    interpolate(r, [&](std::size_t j) { return values + static_cast<std::size_t>(r.grid.original_index(j)) * components; }, components,
                points, out, threads);
}

void nearest_particle_at_points(const SurfaceReconstruction& r, const float* values, int components, const std::vector<float>& points,
                                std::vector<float>& out, int threads) {
    if (components < 1 || components > 16) throw InputError("attribute transfer takes 1 to 16 components, got " + std::to_string(components));
    const std::size_t n = points.size() / 3;
    out.assign(n * static_cast<std::size_t>(components), 0.0f);
    const float support = static_cast<float>(r.params.compact_support());
    constexpr int64_t kBlock = 256;
    parallel_for((static_cast<int64_t>(n) + kBlock - 1) / kBlock, threads, [&](int64_t block) {
        ParticleGrid::NeighborCells cache;
        const int64_t end = std::min<int64_t>(static_cast<int64_t>(n), (block + 1) * kBlock);
        for (int64_t p = block * kBlock; p < end; ++p) {
            float nearest_d2 = INFINITY;
            std::size_t nearest = 0;
            // Neighbours come in sorted order: the strict < keeps the first of equally near particles.
            r.grid.for_each_neighbor(&points[3 * p], support, cache, [&](std::size_t j, float d2) {
                if (d2 < nearest_d2) {
                    nearest_d2 = d2;
                    nearest = j;
                }
            });
            if (nearest_d2 == INFINITY) continue;
            const float* v = values + static_cast<std::size_t>(r.grid.original_index(nearest)) * components;
            std::copy(v, v + components, out.begin() + static_cast<std::ptrdiff_t>(p) * components);
        }
    });
}

void interpolate_sorted_at_points(const SurfaceReconstruction& r, const float* values, int components, const std::vector<float>& points,
                                  std::vector<float>& out, int threads) {
    if (components != 1) {
        interpolate(r, [&](std::size_t j) { return values + j * components; }, components, points, out, threads);
        return;
    }
    // One value per particle (the feature weights' counts): the branch-free lane loop of the density pass.
    const std::size_t n = points.size() / 3;
    out.assign(n, 0.0f);
    const CubicSplineKernel kernel(r.params.compact_support());
    const float support_squared = kernel.support_squared(), inverse_support = 1.0f / kernel.support();
    const LanePositions lanes(r.grid);
    const std::vector<float> volumes = padded(r.volumes);
    const std::vector<float> sorted_values = padded(std::vector<float>(values, values + r.grid.size()));
    constexpr int64_t kBlock = 256;
    parallel_for((static_cast<int64_t>(n) + kBlock - 1) / kBlock, threads, [&](int64_t block) {
        ParticleGrid::NeighborCells cache;
        const int64_t end = std::min<int64_t>(static_cast<int64_t>(n), (block + 1) * kBlock);
        for (int64_t p = block * kBlock; p < end; ++p) {
            const float px = points[3 * p], py = points[3 * p + 1], pz = points[3 * p + 2];
            const ParticleGrid::NeighborCells& cells = r.grid.neighbor_cells(&points[3 * p], cache);
            float weight_sum[kLanes] = {}, value_sum[kLanes] = {};
            for (int k = 0; k < cells.count; ++k) {
                const std::size_t range_end = cells.ranges[k].second;
                for (std::size_t first = cells.ranges[k].first; first < range_end; first += kLanes) {
                    const int valid_lanes = static_cast<int>(std::min<std::size_t>(kLanes, range_end - first));
                    const float *bx = lanes.x.data() + first, *by = lanes.y.data() + first, *bz = lanes.z.data() + first;
                    const float *bv = volumes.data() + first, *bw = sorted_values.data() + first;
                    for (int l = 0; l < kLanes; ++l) {
                        const float dx = px - bx[l], dy = py - by[l], dz = pz - bz[l];
                        const float d2 = dx * dx + dy * dy + dz * dz;
                        const float counts = static_cast<float>((l < valid_lanes) & (d2 < support_squared));
                        const float w = counts * bv[l] * spline_shape(std::sqrt(d2) * inverse_support);  // V_j W_ij / W(0)
                        weight_sum[l] += w;
                        value_sum[l] += w * bw[l];
                    }
                }
            }
            float weight = 0.0f, value = 0.0f;
            for (int l = 0; l < kLanes; ++l) weight += weight_sum[l], value += value_sum[l];
            if (weight > 0.0f) out[static_cast<std::size_t>(p)] = value / weight;  // Eq. 7: 0th-order (Shepard) correction
        }
    });
}

std::vector<float> colour_field_normals(const SurfaceReconstruction& r, const std::vector<float>& points, int threads) {
    const std::size_t n = points.size() / 3;
    std::vector<float> normals(3 * n, 0.0f);
    CubicSplineKernel kernel(r.params.compact_support());
    parallel_for(static_cast<int64_t>(n), threads, [&](int64_t p) {
        const float* x = &points[3 * p];
        double g[3] = {0, 0, 0};
        r.grid.for_each_neighbor(x, kernel.support(), [&](std::size_t j, float d2) {
            const float d = std::sqrt(d2);
            if (d <= 0.0f) return;
            const double s = double(r.volumes[j]) * kernel.derivative(d) / d;
            const float* xj = r.grid.position(j);
            for (int k = 0; k < 3; ++k) g[k] += s * (double(x[k]) - double(xj[k]));
        });
        // The colour field decreases outwards: the outward normal is minus its gradient.
        const double length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (length > 0.0)
            for (int k = 0; k < 3; ++k) normals[3 * p + k] = static_cast<float>(-g[k] / length);
    }, 256);
    return normals;
}

}  // namespace meniscus
