#include "surface/particle_level_set.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "base/errors.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "parameters.h"
#include "sph/fluid_grid_map.h"
#include "sph/interior_fill.h"
#include "surface/bricks.h"

namespace meniscus {

namespace {

// Mantaflow's margin on the mesh particle radius (calculateRadiusFactor adds 1 % of a cell).
constexpr double kRadiusMargin = 0.01;
// A cell weighs when its particles' weights sum to more than this (Mantaflow's VECTOR_EPSILON).
constexpr double kWeighs = 1e-6;
// Outside value on the bounds (Mantaflow's setBound(0.5, ...)).
constexpr float kBound = 0.5f;
// How deep under the classification's air (solver cells) the simulation's level set stands in: see its use.
constexpr double kFillDepth = 2.5;
// The extrapolation's reach outside the surface, in cells (Mantaflow's mesh step).
constexpr int kOutsideLayers = 3;
// Bytes per refined cell at the peak: phi, the mean position (3 floats), the weighed flag, the searched mask and its
// second buffer, the particles' cell offsets.
constexpr double kBytesPerCell = 4.0 + 12.0 + 1.0 + 2.0 + 8.0;

struct Lattice {
    std::array<int, 3> n{};
    int64_t sx = 1, sy = 0, sz = 0, cells = 0;
    explicit Lattice(const std::array<int, 3>& resolution) : n(resolution) {
        sy = n[0];
        sz = int64_t(n[0]) * n[1];
        cells = sz * n[2];
    }
    int64_t index(int i, int j, int k) const { return i + sy * j + sz * k; }
    bool inner(int i, int j, int k) const { return i > 0 && j > 0 && k > 0 && i < n[0] - 1 && j < n[1] - 1 && k < n[2] - 1; }
};

// Calls body(i, j, k, cell) for every cell, in parallel over the z slices: each call writes its own cell only.
template <class F>
void for_each_cell(const Lattice& g, int threads, F&& body) {
    parallel_for(g.n[2], threads, [&](int64_t k) {
        for (int j = 0; j < g.n[1]; ++j)
            for (int i = 0; i < g.n[0]; ++i) body(i, j, int(k), g.index(i, j, int(k)));
    });
}

// The largest real part among the eigenvalues of the 3 x 3 matrix m (rows), from its characteristic cubic.
double largest_eigenvalue(const double m[3][3]) {
    const double trace = m[0][0] + m[1][1] + m[2][2];
    const double minors = m[0][0] * m[1][1] - m[0][1] * m[1][0] + m[0][0] * m[2][2] - m[0][2] * m[2][0] + m[1][1] * m[2][2] - m[1][2] * m[2][1];
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    // l^3 + a l^2 + b l + c = 0, l = t - a / 3: t^3 + p t + q = 0.
    const double a = -trace, b = minors, c = -det;
    const double p = b - a * a / 3.0, q = 2.0 * a * a * a / 27.0 - a * b / 3.0 + c;
    const double discriminant = q * q / 4.0 + p * p * p / 27.0;
    double t = 0.0;
    if (discriminant > 0.0) {  // one real root and a complex pair, whose real part is -root / 2
        const double s = std::sqrt(discriminant);
        const double root = std::cbrt(-q / 2.0 + s) + std::cbrt(-q / 2.0 - s);
        t = std::max(root, -root / 2.0);
    } else if (p < 0.0) {  // three real roots: the largest of the trigonometric form's
        const double m2 = 2.0 * std::sqrt(-p / 3.0);
        const double angle = std::acos(std::clamp(3.0 * q / (p * m2), -1.0, 1.0)) / 3.0;
        t = m2 * std::cos(angle);
    }
    return t - a / 3.0;
}

// One 7-point mean of `from` into `to` on the inner cells (Mantaflow's knSmoothGrid and knSmoothGridNeg, whose
// destination's outer layer keeps what it held). Negative: `to` takes the mean only where it lowers what `to`
// held, else `from`'s value.
void smoothing_pass(const Lattice& g, const std::vector<float>& from, std::vector<float>& to, bool negative, int threads) {
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (!g.inner(i, j, k)) return;
        const float mean = (from[c] + from[c + 1] + from[c - 1] + from[c + g.sy] + from[c - g.sy] + from[c + g.sz] + from[c - g.sz]) * float(1.0 / 7.0);
        to[c] = !negative || mean < to[c] ? mean : from[c];
    });
}

void set_bound(const Lattice& g, std::vector<float>& phi, int width, int threads) {
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (std::min({i, j, k}) <= width || i >= g.n[0] - 1 - width || j >= g.n[1] - 1 - width || k >= g.n[2] - 1 - width) phi[c] = kBound;
    });
}

// Mantaflow's extrapolateLsSimple: the first layer across the surface keeps its value, the next layers up to
// `distance` take the mean of their neighbours in the layer before plus one cell (inside: minus), the cells beyond
// +-(distance + 2). The grid's outer layer is left as it is. Layer by layer, each cell reading only the layer
// before: the same for any thread count.
void extrapolate(const Lattice& g, std::vector<float>& phi, std::vector<uint8_t>& layer, int distance, bool inside, int threads) {
    const float direction = inside ? -1.0f : 1.0f;
    const int64_t steps[6] = {1, -1, g.sy, -g.sy, g.sz, -g.sz};
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        layer[c] = g.inner(i, j, k) && (inside ? phi[c] > 0.0f : phi[c] < 0.0f) ? 1 : 0;
    });
    const auto next_to = [&](int64_t c, int d) {
        for (int64_t s : steps)
            if (layer[c + s] == d) return true;
        return false;
    };
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (g.inner(i, j, k) && layer[c] == 0 && next_to(c, 1)) layer[c] = 2;
    });
    for (int d = 2; d <= distance; ++d) {
        for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
            if (!g.inner(i, j, k) || layer[c] != 0) return;
            float total = 0.0f;
            int count = 0;
            for (int64_t s : steps)
                if (layer[c + s] == d) {
                    total += phi[c + s];
                    ++count;
                }
            if (count == 0) return;
            phi[c] = total / float(count) + direction;
            layer[c] = uint8_t(d + 1);
        });
    }
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (g.inner(i, j, k) && layer[c] == 0) phi[c] = direction * float(distance + 2);
    });
}

// The mask grown by `radius` cells along each axis (a box, as the particles' search reaches), one axis after the
// other through a second buffer, each line on its own.
void grow_box(const Lattice& g, std::vector<uint8_t>& mask, int radius, int threads) {
    const int64_t strides[3] = {1, g.sy, g.sz};
    std::vector<uint8_t> grown(mask.size());
    for (int axis = 0; axis < 3; ++axis) {
        const int n = g.n[axis], a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        parallel_for(int64_t(g.n[a1]) * g.n[a2], threads, [&](int64_t line) {
            const int64_t first = (line % g.n[a1]) * strides[a1] + (line / g.n[a1]) * strides[a2], step = strides[axis];
            for (int q = 0; q < n; ++q) {
                uint8_t any = 0;
                for (int r = std::max(0, q - radius); r <= std::min(n - 1, q + radius) && !any; ++r) any = mask[first + r * step];
                grown[first + q * step] = any;
            }
        }, 16);
        mask.swap(grown);
    }
}

// Far beyond any grid (squared cells), below float's limit so that sums stay finite.
constexpr float kFar = 1e30f;

// Squared Euclidean distance (in cells) from each cell to the nearest cell holding 0, in place: `d` holds 0 at those
// cells and kFar elsewhere. Felzenszwalb and Huttenlocher's lower envelope of parabolas, one axis after the other,
// each line on its own: the same for any thread count.
void squared_distance_transform(const Lattice& g, std::vector<float>& d, int threads) {
    const int64_t strides[3] = {1, g.sy, g.sz};
    for (int axis = 0; axis < 3; ++axis) {
        const int n = g.n[axis], a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        const int64_t lines = int64_t(g.n[a1]) * g.n[a2];
        parallel_for(lines, threads, [&](int64_t line) {
            const int64_t first = (line % g.n[a1]) * strides[a1] + (line / g.n[a1]) * strides[a2], step = strides[axis];
            std::vector<double> f(n), boundary(n + 1);
            std::vector<int> vertex(n);
            for (int q = 0; q < n; ++q) f[q] = d[first + q * step];
            int hull = 0;
            vertex[0] = 0;
            boundary[0] = -std::numeric_limits<double>::infinity();
            boundary[1] = std::numeric_limits<double>::infinity();
            for (int q = 1; q < n; ++q) {
                double cross = 0.0;
                while (true) {  // boundary[0] is minus infinity: stops at the first parabola at the latest
                    const int v = vertex[hull];
                    cross = ((f[q] + double(q) * q) - (f[v] + double(v) * v)) / (2.0 * (q - v));
                    if (cross > boundary[hull]) break;
                    --hull;
                }
                ++hull;
                vertex[hull] = q;
                boundary[hull] = cross;
                boundary[hull + 1] = std::numeric_limits<double>::infinity();
            }
            int h = 0;
            for (int q = 0; q < n; ++q) {
                while (boundary[h + 1] < q) ++h;
                const double x = q - vertex[h];
                d[first + q * step] = float(std::min(double(kFar), x * x + f[vertex[h]]));
            }
        }, 16);
    }
}

std::string field(const char* name) { return std::string("fluid_domain.") + name; }

}  // namespace

void validate_mesh_settings(const FluidDomain& d) {
    if (d.mesh_upres < 1 || d.mesh_upres > 16)
        throw InputError(field("mesh_upres") + " (Mantaflow's Upres Factor) must be a whole number from 1 to 16, got " + std::to_string(d.mesh_upres));
    if (!(d.mesh_particle_radius > 0.0) || !(d.mesh_particle_radius <= 100.0))
        throw InputError(field("mesh_particle_radius") + " must be above 0 and at most 100, got " + format_number(d.mesh_particle_radius));
    const auto check_passes = [](const char* name, int passes) {
        if (passes < 0 || passes > 100) throw InputError(field(name) + " must be a whole number from 0 to 100, got " + std::to_string(passes));
    };
    check_passes("mesh_smoothen_pos", d.mesh_smoothen_pos);
    check_passes("mesh_smoothen_neg", d.mesh_smoothen_neg);
    if (!std::isfinite(d.mesh_concave_lower) || !std::isfinite(d.mesh_concave_upper) || !(d.mesh_concave_lower < d.mesh_concave_upper))
        throw InputError(field("mesh_concave_lower") + " must be below " + field("mesh_concave_upper") + ", got " + format_number(d.mesh_concave_lower) +
                         " and " + format_number(d.mesh_concave_upper));
}

ParticleLevelSetSurface particle_level_set_surface(const PositionsView& positions, const std::vector<AttributeInput>& attributes,
                                                   const FluidDomain& domain, int threads, std::size_t memory_budget_bytes) {
    validate_fluid_domain(domain);
    validate_mesh_settings(domain);
    if (positions.count >= std::size_t(std::numeric_limits<int32_t>::max())) throw InputError("the particle level set takes fewer than 2^31 particles");
    const int upres = domain.mesh_upres;
    std::array<int, 3> resolution{};
    for (int a = 0; a < 3; ++a) resolution[a] = domain.resolution[a] * upres;
    const Lattice g(resolution);
    if (g.cells >= int64_t(std::numeric_limits<int32_t>::max()))
        throw ResourceError("Mantaflow's mesh level set takes fewer than 2^31 cells (the domain's resolution times its Upres Factor, cubed), got " +
                            std::to_string(g.cells));
    check_memory_budget(double(g.cells) * kBytesPerCell + double(positions.count) * 20.0, memory_budget_bytes,
                        "Mantaflow's mesh level set (" + std::to_string(resolution[0]) + " x " + std::to_string(resolution[1]) + " x " +
                            std::to_string(resolution[2]) + " cells: the domain's resolution times its Upres Factor)");
    ParticleLevelSetSurface out;
    out.resolution = resolution;
    const GridMap map(domain);
    const double radius = 0.5 * std::sqrt(3.0) * (domain.mesh_particle_radius + kRadiusMargin);
    const double inverse = 1.0 / (4.0 * radius * radius);
    const int reach = int(radius) + 1;

    // The particles in refined-grid coordinates, sorted by cell (counting sort, stable); clamped into the grid as
    // Mantaflow's particles are kept in it.
    std::vector<float> grid_positions(3 * positions.count);
    // A particle with a non-finite coordinate goes to a last group, which no cell reads.
    std::vector<int32_t> particle_cell(positions.count, int32_t(g.cells));
    parallel_for(int64_t(positions.count), threads, [&](int64_t p) {
        const Vec3 gc = map.grid({positions.coord(p, 0), positions.coord(p, 1), positions.coord(p, 2)});
        std::array<int, 3> c{};
        for (int a = 0; a < 3; ++a) {
            const double x = gc[a] * upres;
            if (!std::isfinite(x)) return;
            grid_positions[3 * p + a] = float(x);
            c[a] = int(std::clamp(std::floor(x), 0.0, double(g.n[a] - 1)));
        }
        particle_cell[p] = int32_t(g.index(c[0], c[1], c[2]));
    }, 4096);
    const CsrList by_cell = group_by_key(particle_cell.data(), int64_t(positions.count), int32_t(g.cells + 1), threads);
    std::vector<int32_t>().swap(particle_cell);
    // Calls visit(particle, weight) for the particles weighing at the point x (refined-grid coordinates), in cell and
    // index order.
    const auto for_each_weighing = [&](const Vec3& x, auto&& visit) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const int c = int(std::clamp(std::floor(x[a]), 0.0, double(g.n[a] - 1)));
            lo[a] = std::max(0, c - reach);
            hi[a] = std::min(g.n[a] - 1, c + reach);
        }
        for (int k = lo[2]; k <= hi[2]; ++k)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i) {
                    const int64_t cell = g.index(i, j, k);
                    for (int64_t s = by_cell.begin(cell); s < by_cell.end(cell); ++s) {
                        const uint32_t p = uint32_t(by_cell.items[s]);
                        double d2 = 0.0;
                        for (int a = 0; a < 3; ++a) {
                            const double d = x[a] - grid_positions[3 * p + a];
                            d2 += d * d;
                        }
                        const double w = 1.0 - d2 * inverse;
                        if (w > 0.0) visit(p, w);
                    }
                }
    };

    // The averaged level set and the weighted mean positions (0 where nothing weighs, as Mantaflow's grid holds).
    std::vector<float> phi(static_cast<std::size_t>(g.cells), float(radius));
    std::vector<float> mean(3 * static_cast<std::size_t>(g.cells), 0.0f);
    std::vector<uint8_t> weighed(static_cast<std::size_t>(g.cells), 0);
    // The cells whose search box holds a particle: most cells (air, deep water) have none, and their 5^3 cells of
    // search cost more than the rest.
    std::vector<uint8_t> searched(static_cast<std::size_t>(g.cells), 0);
    for_each_cell(g, threads, [&](int, int, int, int64_t c) { searched[c] = by_cell.end(c) > by_cell.begin(c) ? 1 : 0; });
    grow_box(g, searched, reach, threads);
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (!searched[c]) return;
        const Vec3 x{i + 0.5, j + 0.5, k + 0.5};
        double total = 0.0;
        Vec3 sum{0.0, 0.0, 0.0};
        for_each_weighing(x, [&](uint32_t p, double w) {
            total += w;
            for (int a = 0; a < 3; ++a) sum[a] += w * grid_positions[3 * p + a];
        });
        if (!(total > kWeighs)) return;
        weighed[c] = 1;
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) {
            mean[3 * c + a] = float(sum[a] / total);
            const double d = x[a] - sum[a] / total;
            d2 += d * d;
        }
        phi[c] = float(std::sqrt(d2) - radius);
    });

    std::vector<uint8_t>().swap(searched);

    // Solenthaler's correction on the inner cells that weigh.
    const double lower = domain.mesh_concave_lower, upper = domain.mesh_concave_upper;
    for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
        if (!weighed[c] || !g.inner(i, j, k)) return;
        const int64_t steps[3] = {1, g.sy, g.sz};
        double jacobian[3][3];
        for (int column = 0; column < 3; ++column)
            for (int row = 0; row < 3; ++row)
                jacobian[row][column] = 0.5 * (double(mean[3 * (c + steps[column]) + row]) - double(mean[3 * (c - steps[column]) + row]));
        const double largest = largest_eigenvalue(jacobian);
        double correction = 1.0;
        if (largest >= lower) {
            const double t = (upper - largest) / (upper - lower);
            correction = t * t * t - 3.0 * t * t + 3.0 * t;
        }
        correction = std::clamp(correction, 0.0, 1.0);
        double d2 = 0.0;
        const double x[3] = {i + 0.5, j + 0.5, k + 0.5};
        for (int a = 0; a < 3; ++a) d2 += (x[a] - mean[3 * c + a]) * (x[a] - mean[3 * c + a]);
        phi[c] = float(std::min(std::sqrt(d2) - radius * correction, radius));
    });
    std::vector<float>().swap(mean);
    std::vector<uint8_t>().swap(weighed);

    // Smoothing, as Mantaflow alternates its passes, each into a fresh grid (outer layer 0).
    {
        std::vector<float> other;
        for (int pass = 0; pass < std::max(domain.mesh_smoothen_pos, domain.mesh_smoothen_neg); ++pass) {
            other.assign(phi.size(), 0.0f);
            if (pass < domain.mesh_smoothen_pos) {
                smoothing_pass(g, phi, other, false, threads);
                phi.swap(other);
            }
            if (pass < domain.mesh_smoothen_neg) {
                smoothing_pass(g, phi, other, true, threads);
                phi.swap(other);
            }
        }
    }
    set_bound(g, phi, 0, threads);

    // The simulation's level set, which the cache does not hold: the cells of the classification's liquid and shell
    // more than kFillDepth solver cells from its air (the air starts about 1.5 cells beyond the outermost particles,
    // where Mantaflow's liquid level set lies, and Mantaflow shrinks that by a cell before joining it), measured on
    // the refined grid so that the joined surface is as fine as the rest.
    {
        const InteriorClassification classes = classify_interior(positions, domain, threads);
        const Lattice solver(domain.resolution);
        const auto solver_cell = [&](int i, int j, int k) { return classes.cells[solver.index(i / upres, j / upres, k / upres)]; };
        std::vector<float> distance2(static_cast<std::size_t>(g.cells));
        for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) { distance2[c] = solver_cell(i, j, k) == CellClass::air ? 0.0f : kFar; });
        squared_distance_transform(g, distance2, threads);
        const float depth2 = float(kFillDepth * upres * kFillDepth * upres);
        std::vector<uint8_t> joined(static_cast<std::size_t>(g.cells), 0);
        // The closed borders' layer of solver cells (solid in the classification) is water too where it is deep
        // enough: Mantaflow's level set reaches into it, and the bound set after the extrapolation ends the mesh.
        const auto wall = [&](int i, int j, int k) {
            const int c[3] = {i / upres, j / upres, k / upres};
            for (int a = 0; a < 3; ++a)
                if ((c[a] == 0 && domain.closed_borders[2 * a]) || (c[a] == solver.n[a] - 1 && domain.closed_borders[2 * a + 1])) return true;
            return false;
        };
        for_each_cell(g, threads, [&](int i, int j, int k, int64_t c) {
            const CellClass cls = solver_cell(i, j, k);
            const bool water = cls == CellClass::liquid || cls == CellClass::shell || (cls == CellClass::solid && wall(i, j, k));
            if (water && distance2[c] > depth2) {
                phi[c] = std::min(phi[c], -1.0f);
                joined[c] = 1;
            }
        });
        out.joined_cells = static_cast<std::size_t>(std::count(joined.begin(), joined.end(), uint8_t(1)));
    }

    std::vector<uint8_t> layer(static_cast<std::size_t>(g.cells), 0);
    extrapolate(g, phi, layer, int(domain.band_width_cells) + 2, true, threads);
    extrapolate(g, phi, layer, kOutsideLayers, false, threads);
    std::vector<uint8_t>().swap(layer);
    set_bound(g, phi, upres - 1, threads);

    // Marching cubes on the lattice of cell centres (lattice point = cell index, cube edge 1), inside where phi < 0:
    // the bricks' table takes inside as above the threshold, so they see -phi. Points beyond the grid are outside.
    std::vector<LatticeCoords> bricks;
    for (int64_t z = 0; z <= floor_div(g.n[2] - 1, kBrick); ++z)
        for (int64_t y = 0; y <= floor_div(g.n[1] - 1, kBrick); ++y)
            for (int64_t x = 0; x <= floor_div(g.n[0] - 1, kBrick); ++x) bricks.push_back({x, y, z});
    const BrickSampler sample = [&](const LatticeCoords& base, BrickScratch& s) {
        for (int z = 0; z < kBrickPoints; ++z)
            for (int y = 0; y < kBrickPoints; ++y)
                for (int x = 0; x < kBrickPoints; ++x) {
                    const int64_t i = base[0] + x, j = base[1] + y, k = base[2] + z;
                    const bool in_grid = i < g.n[0] && j < g.n[1] && k < g.n[2];
                    s.values[point_index(x, y, z)] = in_grid ? -phi[g.index(int(i), int(j), int(k))] : -kBound;
                }
        return crosses_threshold(s.values, 0.0f);
    };
    TriMesh mesh = mesh_bricks(bricks, sample, 1.0, 0.0, threads);
    std::vector<float>().swap(phi);

    // Vertex attributes, from the vertices in refined-grid coordinates (cell centres at + 0.5).
    const std::size_t vertex_count = mesh.num_vertices();
    for (const AttributeInput& a : attributes) mesh.attributes.push_back({a.name, a.components, std::vector<float>(vertex_count * a.components, 0.0f), a.integral});
    std::size_t components = 0;
    for (const AttributeInput& a : attributes) components += static_cast<std::size_t>(a.components);
    std::vector<uint8_t> unweighed(vertex_count, 0);
    if (!attributes.empty())
        parallel_for(int64_t(vertex_count), threads, [&](int64_t v) {
            const Vec3 x{mesh.vertices[3 * v] + 0.5, mesh.vertices[3 * v + 1] + 0.5, mesh.vertices[3 * v + 2] + 0.5};
            double total = 0.0, heaviest = 0.0;
            uint32_t heaviest_particle = 0;
            std::vector<double> sums(components, 0.0);
            for_each_weighing(x, [&](uint32_t p, double w) {
                total += w;
                if (w > heaviest) heaviest = w, heaviest_particle = p;
                std::size_t o = 0;
                for (const AttributeInput& a : attributes)
                    for (int k = 0; k < a.components; ++k) sums[o++] += w * a.values[std::size_t(a.components) * p + k];
            });
            if (!(total > 0.0)) {  // no particle near: on a wall under the band, where the joined interior meets it
                unweighed[v] = 1;
                return;
            }
            std::size_t o = 0;
            for (std::size_t a = 0; a < attributes.size(); ++a) {
                const AttributeInput& in = attributes[a];
                for (int k = 0; k < in.components; ++k, ++o)
                    mesh.attributes[a].values[std::size_t(in.components) * v + k] =
                        in.integral ? in.values[std::size_t(in.components) * heaviest_particle + k] : float(sums[o] / total);
            }
        }, 256);
    // Those take the attributes of the particle nearest through the grid (a breadth-first search from the cells
    // holding particles, in cell order: the same for any thread count), as the fill's particles do.
    if (std::find(unweighed.begin(), unweighed.end(), uint8_t(1)) != unweighed.end()) {
        std::vector<int32_t> source(static_cast<std::size_t>(g.cells), -1);
        std::vector<int32_t> queue;
        queue.reserve(static_cast<std::size_t>(g.cells));
        for (int64_t c = 0; c < g.cells; ++c)
            if (by_cell.end(c) > by_cell.begin(c)) {
                source[c] = by_cell.items[by_cell.begin(c)];
                queue.push_back(int32_t(c));
            }
        const int64_t steps[6] = {1, -1, g.sy, -g.sy, g.sz, -g.sz};
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const int64_t c = queue[q];
            const int64_t i = c % g.sy, j = (c / g.sy) % g.n[1], k = c / g.sz;
            const bool open[6] = {i + 1 < g.n[0], i > 0, j + 1 < g.n[1], j > 0, k + 1 < g.n[2], k > 0};
            for (int n = 0; n < 6; ++n)
                if (open[n] && source[c + steps[n]] < 0) {
                    source[c + steps[n]] = source[c];
                    queue.push_back(int32_t(c + steps[n]));
                }
        }
        for (std::size_t v = 0; v < vertex_count; ++v) {
            if (!unweighed[v]) continue;
            int cell[3];
            for (int a = 0; a < 3; ++a) cell[a] = int(std::clamp(std::floor(mesh.vertices[3 * v + a] + 0.5), 0.0, double(g.n[a] - 1)));
            const int32_t p = source[g.index(cell[0], cell[1], cell[2])];
            if (p < 0) continue;
            for (std::size_t a = 0; a < attributes.size(); ++a) {
                const std::size_t k = static_cast<std::size_t>(attributes[a].components);
                std::copy(attributes[a].values + k * p, attributes[a].values + k * (p + 1), mesh.attributes[a].values.begin() + k * v);
            }
        }
    }

    // To world space: a cell centre of the refined grid at (index + 0.5) / upres solver cells. A mirroring domain
    // matrix turns the winding over.
    parallel_for(int64_t(vertex_count), threads, [&](int64_t v) {
        const Vec3 w = map.world({(mesh.vertices[3 * v] + 0.5) / upres, (mesh.vertices[3 * v + 1] + 0.5) / upres, (mesh.vertices[3 * v + 2] + 0.5) / upres});
        for (int a = 0; a < 3; ++a) mesh.vertices[3 * v + a] = float(w[a]);
    }, 4096);
    const Mat3& m = map.to_world;
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (det < 0.0)
        for (std::size_t t = 0; t < mesh.num_triangles(); ++t) std::swap(mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]);
    out.mesh = std::move(mesh);
    return out;
}

}  // namespace meniscus
