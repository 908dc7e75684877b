#include "sph/interior_fill.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "base/errors.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "parameters.h"
#include "sph/fluid_grid_map.h"

namespace meniscus {

namespace {

// A cell is shell when a particle lies within this many cells of it: a band of jittered particles leaves some cells
// empty, and the shell must have no gap the interior could leak through.
constexpr double kShellReach = 1.0;
// More lattice points per cell edge than this would only mean a particle radius far below the solver's cells.
constexpr int kMaxPointsPerEdge = 8;
// In shell cells a lattice point is added only this many lattice spacings or further from every particle: it fills
// the band's gaps, but a particle of the band at its rest spacing keeps the lattice points around it away.
constexpr double kKeepAway = 0.75;
// The fewest columns under a cover whose depth in particles tells a sheet from a band (see the column votes).
constexpr std::size_t kMinThinCoverColumns = 4;

struct Grid {
    std::array<int, 3> n{};
    std::array<int64_t, 3> stride{};
    int64_t cells = 0;

    explicit Grid(const std::array<int, 3>& resolution) : n(resolution) {
        stride = {1, int64_t(n[0]), int64_t(n[0]) * n[1]};
        cells = stride[2] * n[2];
    }
    int64_t index(int i, int j, int k) const { return i + stride[1] * j + stride[2] * k; }
    std::array<int, 3> coords(int64_t c) const {
        return {int(c % n[0]), int((c / n[0]) % n[1]), int(c / stride[2])};
    }
};

// Calls visit(next) for each face neighbour of the cell inside the grid, in a fixed order; visit(-1) once per face
// on the grid's edge.
template <class Visit>
void for_each_face_neighbour(const Grid& grid, int64_t cell, Visit&& visit) {
    const std::array<int, 3> c = grid.coords(cell);
    for (int a = 0; a < 3; ++a)
        for (int dir = -1; dir <= 1; dir += 2) {
            const int x = c[a] + dir;
            visit(x < 0 || x >= grid.n[a] ? int64_t(-1) : cell + dir * grid.stride[a]);
        }
}

// Breadth-first spread from the queued cells, whose values are set: each cell that `enter(from, to)` allows and that
// is still `unset` takes the value of the cell it is first reached from. The queue's order settles ties, so the
// result is the same on every run.
template <class T, class Enter>
void spread(const Grid& grid, std::vector<int64_t>& queue, std::vector<T>& value, T unset, Enter&& enter) {
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const int64_t cell = queue[q];
        for_each_face_neighbour(grid, cell, [&](int64_t next) {
            if (next < 0 || value[next] != unset || !enter(cell, next)) return;
            value[next] = value[cell];
            queue.push_back(next);
        });
    }
}

std::string field(const char* name) { return std::string("fluid_domain.") + name; }

// Whether every edge of the soup is shared by an even number of its triangles (corners matched exactly: a mesh's
// triangles share their corners' world coordinates): a closed surface, whose inside parity can tell.
bool closed_soup(const std::vector<float>& soup) {
    using Corner = std::array<float, 3>;
    std::vector<std::pair<Corner, Corner>> edges;
    edges.reserve(soup.size() / 3);
    for (std::size_t t = 0; t + 9 <= soup.size(); t += 9)
        for (int e = 0; e < 3; ++e) {
            const std::size_t a = t + 3 * e, b = t + 3 * ((e + 1) % 3);
            Corner p{soup[a], soup[a + 1], soup[a + 2]}, q{soup[b], soup[b + 1], soup[b + 2]};
            if (q < p) std::swap(p, q);
            edges.emplace_back(p, q);
        }
    std::sort(edges.begin(), edges.end());
    for (std::size_t s = 0; s < edges.size();) {
        std::size_t e = s;
        while (e < edges.size() && edges[e] == edges[s]) ++e;
        if ((e - s) % 2 != 0) return false;
        s = e;
    }
    return !edges.empty();
}

// Whether the triangle (grid coordinates) meets the closed unit cell at `lo`, by the separating axis test: the
// cell's three axes, the triangle's normal and the nine cross products of its edges with the cell's axes.
bool triangle_meets_cell(const std::array<Vec3, 3>& p, const std::array<int, 3>& lo) {
    std::array<Vec3, 3> v;
    for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a) v[c][a] = p[c][a] - (lo[a] + 0.5);
    const auto cross = [](const Vec3& a, const Vec3& b) { return Vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; };
    const auto separates = [&](const Vec3& axis) {
        const double radius = 0.5 * (std::fabs(axis[0]) + std::fabs(axis[1]) + std::fabs(axis[2]));
        double lo_p = std::numeric_limits<double>::infinity(), hi_p = -lo_p;
        for (const Vec3& q : v) {
            const double d = q[0] * axis[0] + q[1] * axis[1] + q[2] * axis[2];
            lo_p = std::min(lo_p, d);
            hi_p = std::max(hi_p, d);
        }
        return lo_p > radius || hi_p < -radius;  // a zero axis never separates
    };
    const std::array<Vec3, 3> edge{Vec3{v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]},
                                   Vec3{v[2][0] - v[1][0], v[2][1] - v[1][1], v[2][2] - v[1][2]},
                                   Vec3{v[0][0] - v[2][0], v[0][1] - v[2][1], v[0][2] - v[2][2]}};
    for (int a = 0; a < 3; ++a) {
        Vec3 unit{0.0, 0.0, 0.0};
        unit[a] = 1.0;
        if (separates(unit)) return false;
        for (const Vec3& e : edge)
            if (separates(cross(e, unit))) return false;
    }
    return !separates(cross(edge[0], edge[1]));
}

// The cells an open soup's triangles meet (a plane, an open box, a mesh with holes): parity cannot tell its inside,
// and a single-sided wall holds water all the same. The cells form a layer that no face-to-face path crosses.
void voxelize_surface(const std::vector<float>& soup, const GridMap& map, const Grid& grid, std::vector<CellClass>& cells) {
    for (std::size_t t = 0; t + 9 <= soup.size(); t += 9) {
        std::array<Vec3, 3> p;
        for (int c = 0; c < 3; ++c) p[c] = map.grid({soup[t + 3 * c], soup[t + 3 * c + 1], soup[t + 3 * c + 2]});
        std::array<int, 3> lo{}, hi{};
        bool outside = false;
        for (int a = 0; a < 3; ++a) {
            // Clamped to the grid before the conversion to int: an obstacle far outside must not overflow it.
            const double low = std::min({p[0][a], p[1][a], p[2][a]}), high = std::max({p[0][a], p[1][a], p[2][a]});
            lo[a] = int(std::clamp(std::floor(low), 0.0, double(grid.n[a])));
            hi[a] = int(std::clamp(std::floor(high), -1.0, double(grid.n[a] - 1)));
            outside = outside || lo[a] > hi[a];
        }
        if (outside) continue;
        for (int k = lo[2]; k <= hi[2]; ++k)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i)
                    if (triangle_meets_cell(p, {i, j, k})) cells[grid.index(i, j, k)] = CellClass::solid;
    }
}

// Obstacles (triangle soups, world space) -> solid cells. A closed soup: a cell is inside when its centre is, by the
// parity of the crossings along the grid's third axis (the cells its surface only grazes stay water, so the water
// reaches the obstacle). An open soup: the cells its triangles meet.
void voxelize_obstacles(const FluidDomain& domain, const GridMap& map, const Grid& grid, std::vector<CellClass>& cells) {
    std::vector<std::pair<int64_t, double>> crossings;  // (column i + nx j, height in cells)
    for (const std::vector<float>& soup : domain.obstacles) {
        if (!closed_soup(soup)) {
            voxelize_surface(soup, map, grid, cells);
            continue;
        }
        for (std::size_t t = 0; t + 9 <= soup.size(); t += 9) {
            std::array<Vec3, 3> p;
            for (int c = 0; c < 3; ++c) p[c] = map.grid({soup[t + 3 * c], soup[t + 3 * c + 1], soup[t + 3 * c + 2]});
            const double area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
            if (area == 0.0) continue;
            const double lo_x = std::min({p[0][0], p[1][0], p[2][0]}), hi_x = std::max({p[0][0], p[1][0], p[2][0]});
            const double lo_y = std::min({p[0][1], p[1][1], p[2][1]}), hi_y = std::max({p[0][1], p[1][1], p[2][1]});
            // Clamped to the grid before the conversion to int: an obstacle far outside must not overflow it.
            const auto column = [](double x, int n) { return int(std::clamp(x, -1.0, double(n))); };
            const int i0 = std::max(0, column(std::ceil(lo_x - 0.5), grid.n[0])), i1 = std::min(grid.n[0] - 1, column(std::floor(hi_x - 0.5), grid.n[0]));
            const int j0 = std::max(0, column(std::ceil(lo_y - 0.5), grid.n[1])), j1 = std::min(grid.n[1] - 1, column(std::floor(hi_y - 0.5), grid.n[1]));
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) {
                    // Sampled a hair off the centre, so that a ray through a shared edge or vertex counts once.
                    const double x = i + 0.5 + 1.3e-7, y = j + 0.5 + 0.7e-7;
                    double w[3];
                    for (int e = 0; e < 3; ++e) {
                        const Vec3& a = p[(e + 1) % 3];
                        const Vec3& b = p[(e + 2) % 3];
                        w[e] = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / area;
                    }
                    if (w[0] < 0 || w[1] < 0 || w[2] < 0) continue;
                    crossings.emplace_back(i + int64_t(grid.n[0]) * j, w[0] * p[0][2] + w[1] * p[1][2] + w[2] * p[2][2]);
                }
        }
    }
    std::sort(crossings.begin(), crossings.end());
    for (std::size_t s = 0; s + 1 < crossings.size();) {
        const int64_t column = crossings[s].first;
        std::size_t e = s;
        while (e < crossings.size() && crossings[e].first == column) ++e;
        for (std::size_t a = s; a + 1 < e; a += 2) {
            const int k0 = std::max(0, int(std::clamp(std::ceil(crossings[a].second - 0.5), -1.0, double(grid.n[2]))));
            const int k1 = std::min(grid.n[2] - 1, int(std::clamp(std::floor(crossings[a + 1].second - 0.5), -1.0, double(grid.n[2]))));
            for (int k = k0; k <= k1; ++k) cells[column + grid.stride[2] * k] = CellClass::solid;
        }
        s = e;
    }
}

// Column votes along gravity: air where nothing but air lies above (the liquid's free surface would be shell);
// liquid where shell lies above and a floor (a wall, an obstacle, the grid's end) below; no vote where shell lies
// both above and below (under a falling sheet, or above a bubble): the region decides.
enum Vote : int8_t { kAbstain = 0, kLiquid = 1, kAir = 2 };

std::vector<int8_t> column_votes(const Grid& grid, const std::vector<CellClass>& cells, int up_axis, bool up_positive, int threads) {
    std::vector<int8_t> votes(static_cast<std::size_t>(grid.cells), kAbstain);
    const int a1 = (up_axis + 1) % 3, a2 = (up_axis + 2) % 3;
    const int height = grid.n[up_axis];
    const int64_t step = up_positive ? grid.stride[up_axis] : -grid.stride[up_axis];
    const int64_t columns = int64_t(grid.n[a1]) * grid.n[a2];
    parallel_for(columns, threads, [&](int64_t column) {
        std::array<int, 3> c{};
        c[a1] = int(column % grid.n[a1]);
        c[a2] = int(column / grid.n[a1]);
        c[up_axis] = up_positive ? 0 : height - 1;
        const int64_t bottom = grid.index(c[0], c[1], c[2]);
        std::vector<uint8_t> shell_below(static_cast<std::size_t>(height));
        bool below = false;  // shell met since the last floor, going up
        for (int h = 0; h < height; ++h) {
            const CellClass cls = cells[bottom + step * h];
            if (cls == CellClass::shell) below = true;
            if (cls == CellClass::solid) below = false;
            shell_below[h] = below;
        }
        bool above = false;  // shell met going down from the top; solid cells let the view through
        // Under an obstacle with no shell over it, a column alone cannot tell air under a table from water under a
        // floating raft: those cells abstain, and their region's other votes decide (the pool around the raft). The
        // closed top border's layer is no obstacle.
        bool shadowed = false;
        for (int h = height - 1; h >= 0; --h) {
            const int64_t cell = bottom + step * h;
            const CellClass cls = cells[cell];
            if (cls == CellClass::shell) {
                above = true;
                continue;
            }
            if (cls == CellClass::solid) {
                shadowed = shadowed || (!above && h < height - 1);
                continue;
            }
            if (!above) votes[cell] = shadowed ? kAbstain : kAir;
            else if (!shell_below[h]) votes[cell] = kLiquid;
        }
    }, 16);
    return votes;
}

}  // namespace

std::size_t InteriorClassification::count(CellClass c) const { return static_cast<std::size_t>(std::count(cells.begin(), cells.end(), c)); }

void validate_fluid_domain(const FluidDomain& d) {
    for (int a = 0; a < 3; ++a)
        if (d.resolution[a] < 1 || d.resolution[a] > 16384)
            throw InputError(field("resolution") + " must be three whole numbers from 1 to 16384, got " + std::to_string(d.resolution[0]) + " " +
                             std::to_string(d.resolution[1]) + " " + std::to_string(d.resolution[2]));
    for (double x : d.origin)
        if (!std::isfinite(x)) throw InputError(field("origin") + " must be three finite numbers, got " + format_number(x) + " in it");
    for (const auto& axis : d.axes)
        for (double x : axis)
            if (!std::isfinite(x)) throw InputError(field("axes") + " must be finite numbers, got " + format_number(x) + " in them");
    const GridMap map(d);
    for (const auto& row : map.to_grid)
        for (double x : row)
            if (!std::isfinite(x)) throw InputError(field("axes") + " must span a volume (three independent cell edges), got a flat or empty cell");
    double g2 = 0.0;
    for (double x : d.gravity) {
        if (!std::isfinite(x)) throw InputError(field("gravity") + " must be three finite numbers, got " + format_number(x) + " in it");
        g2 += x * x;
    }
    if (g2 == 0.0) throw InputError(field("gravity") + " must be a direction, got (0, 0, 0)");
    if (!std::isfinite(d.band_width_cells) || d.band_width_cells < 0.0)
        throw InputError(field("band_width_cells") + " must be 0 or more, got " + format_number(d.band_width_cells));
    for (std::size_t o = 0; o < d.obstacles.size(); ++o) {
        if (d.obstacles[o].size() % 9 != 0)
            throw InputError(field("obstacles") + "[" + std::to_string(o) + "] must hold 9 numbers per triangle, got " +
                             std::to_string(d.obstacles[o].size()));
        for (float x : d.obstacles[o])
            if (!std::isfinite(x))
                throw InputError(field("obstacles") + "[" + std::to_string(o) + "] must be finite numbers, got " + format_number(x) + " in it");
    }
}

bool narrow_band_domain(const FluidDomain& domain) { return domain.band_width_cells > 0.0; }

InteriorClassification classify_interior(const PositionsView& positions, const FluidDomain& domain, int threads) {
    validate_fluid_domain(domain);
    const GridMap map(domain);
    const Grid grid(domain.resolution);
    InteriorClassification out;
    out.resolution = domain.resolution;
    std::vector<CellClass>& cells = out.cells;
    cells.assign(static_cast<std::size_t>(grid.cells), CellClass::air);

    // Shell: the cells within reach of a particle. Held: the cells a particle lies in.
    std::vector<uint8_t> held(static_cast<std::size_t>(grid.cells), 0);
    for (std::size_t p = 0; p < positions.count; ++p) {
        const Vec3 g = map.grid({positions.coord(p, 0), positions.coord(p, 1), positions.coord(p, 2)});
        if (!(std::isfinite(g[0]) && std::isfinite(g[1]) && std::isfinite(g[2]))) continue;
        if (g[0] >= 0.0 && g[0] < grid.n[0] && g[1] >= 0.0 && g[1] < grid.n[1] && g[2] >= 0.0 && g[2] < grid.n[2])
            held[grid.index(int(g[0]), int(g[1]), int(g[2]))] = 1;
        std::array<int, 3> lo{}, hi{};
        bool outside = false;
        for (int a = 0; a < 3; ++a) {
            // Out of reach of the grid: skipped before any conversion to int (far-away particles would overflow it).
            if (!(g[a] > -kShellReach && g[a] < grid.n[a] + kShellReach)) {
                outside = true;
                break;
            }
            lo[a] = int(std::max(0.0, std::floor(g[a] - kShellReach)));
            hi[a] = int(std::min(double(grid.n[a] - 1), std::floor(g[a] + kShellReach)));
            outside = outside || lo[a] > hi[a];
        }
        if (outside) continue;
        for (int k = lo[2]; k <= hi[2]; ++k)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i) {
                    const int c[3] = {i, j, k};
                    double d2 = 0.0;
                    for (int a = 0; a < 3; ++a) {
                        const double gap = std::max({0.0, c[a] - g[a], g[a] - (c[a] + 1)});
                        d2 += gap * gap;
                    }
                    if (d2 < kShellReach * kShellReach) cells[grid.index(i, j, k)] = CellClass::shell;
                }
    }

    // Solid: the layer of cells on each closed border (the solver's own walls) and the obstacles.
    for (int side = 0; side < 6; ++side) {
        if (!domain.closed_borders[side]) continue;
        const int axis = side / 2;
        const int layer = side % 2 == 0 ? 0 : grid.n[axis] - 1;
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        for (int v = 0; v < grid.n[a2]; ++v)
            for (int u = 0; u < grid.n[a1]; ++u) {
                std::array<int, 3> c{};
                c[axis] = layer;
                c[a1] = u;
                c[a2] = v;
                cells[grid.index(c[0], c[1], c[2])] = CellClass::solid;
            }
    }
    voxelize_obstacles(domain, map, grid, cells);

    // Which way is up in the grid: against gravity, along the grid axis nearest to it.
    const Vec3 down = map.direction(domain.gravity);
    int up_axis = 0;
    for (int a = 1; a < 3; ++a)
        if (std::fabs(down[a]) > std::fabs(down[up_axis])) up_axis = a;
    const bool up_positive = down[up_axis] < 0.0;
    std::vector<int8_t> votes = column_votes(grid, cells, up_axis, up_positive, threads);

    // Every boundary between liquid and air is a free surface, which carries the band's particles. A group of liquid
    // votes that borders air votes directly over more faces than it has shell above it is air under something
    // airborne (a jet or a drop over a dry floor), not water: its sides would need walls. So is a group whose sides
    // border air votes over more than a third of the faces they share with air votes, walls, obstacles, shell and the
    // grid's edge: air under a drop or sheet wider than its height over the floor, open all round or on two sides
    // in a corner (the first rule alone would take it for a pool and raise a pillar of water under it). Water held
    // by an obstacle nobody described borders that obstacle's cells (which look like air) only along the
    // obstacle's sides, and the domain's walls elsewhere. And so is a group under a sheet thinner than the band: the
    // solver keeps particles band_width_cells deep under every free surface, so over water the cells holding
    // particles span that deep above it (deeper where the surface slopes); in most of the group's columns less
    // (the median, half a cell of slack) is a sheet with air under it, whatever walls stand around it. Not judged
    // under fewer columns than kMinThinCoverColumns: one or two columns of a jittered band say too little, and the
    // region around them takes its class from their vote.
    {
        std::vector<int32_t> group(static_cast<std::size_t>(grid.cells), -1);
        std::vector<int64_t> members, stack;
        std::vector<int> held_above;  // per covered column of the group: the cells holding particles in the shell above
        const int64_t up_step = up_positive ? grid.stride[up_axis] : -grid.stride[up_axis];
        int32_t groups = 0;
        for (int64_t seed = 0; seed < grid.cells; ++seed) {
            if (votes[seed] != kLiquid || group[seed] >= 0) continue;
            members.clear();
            held_above.clear();
            stack.assign(1, seed);
            group[seed] = groups;
            int64_t open_faces = 0, covered_faces = 0, open_sides = 0, bounded_sides = 0;
            while (!stack.empty()) {
                const int64_t cell = stack.back();
                stack.pop_back();
                members.push_back(cell);
                const std::array<int, 3> c = grid.coords(cell);
                const int up = c[up_axis] + (up_positive ? 1 : -1);
                if (up >= 0 && up < grid.n[up_axis] && cells[cell + up_step] == CellClass::shell) {
                    ++covered_faces;
                    // The span from the lowest to the highest cell holding particles in the shell above: a cell of
                    // the band that happens to hold none (a sparse Particle Sampling) does not thin the cover.
                    int lowest_held = -1, highest_held = -1, step_up = 0;
                    int64_t above = cell + up_step;
                    for (int h = up; h >= 0 && h < grid.n[up_axis] && cells[above] == CellClass::shell; h += up_positive ? 1 : -1) {
                        if (held[above]) {
                            if (lowest_held < 0) lowest_held = step_up;
                            highest_held = step_up;
                        }
                        ++step_up;
                        above += up_step;
                    }
                    held_above.push_back(lowest_held < 0 ? 0 : highest_held - lowest_held + 1);
                }
                for (int a = 0; a < 3; ++a) {
                    if (a == up_axis) continue;
                    for (int dir = -1; dir <= 1; dir += 2) {
                        const int x = c[a] + dir;
                        if (x < 0 || x >= grid.n[a]) {
                            ++bounded_sides;
                            continue;
                        }
                        const int64_t side = cell + dir * grid.stride[a];
                        if (votes[side] == kAir) ++open_sides;
                        else if (cells[side] == CellClass::shell || cells[side] == CellClass::solid) ++bounded_sides;
                    }
                }
                for_each_face_neighbour(grid, cell, [&](int64_t next) {
                    if (next < 0) return;
                    if (votes[next] == kAir) ++open_faces;
                    if (votes[next] != kLiquid || group[next] >= 0) return;
                    group[next] = groups;
                    stack.push_back(next);
                });
            }
            ++groups;
            bool thin_cover = false;
            if (held_above.size() >= kMinThinCoverColumns && domain.band_width_cells > 0.0) {
                std::nth_element(held_above.begin(), held_above.begin() + held_above.size() / 2, held_above.end());
                thin_cover = held_above[held_above.size() / 2] + 0.5 < domain.band_width_cells;
            }
            if (open_faces > covered_faces || 2 * open_sides > bounded_sides || thin_cover)
                for (int64_t cell : members) votes[cell] = kAir;
        }
    }

    // Connected regions (6-connectivity) of the cells that are neither shell nor solid, in index order.
    struct Region {
        int64_t liquid_votes = 0, air_votes = 0;
        bool enclosed = true;  // touches no wall, obstacle or open border
        CellClass cls = CellClass::air;
        bool split = false;
        int64_t size = 0;
        std::array<int64_t, 6> extreme{};  // its first cell furthest along -x, +x, -y, +y, -z, +z of the grid
        std::array<int, 6> reach{};
        bool resolved = false;
    };
    std::vector<int32_t> label(static_cast<std::size_t>(grid.cells), -1);
    std::vector<Region> regions;
    std::vector<int64_t> stack;
    for (int64_t seed = 0; seed < grid.cells; ++seed) {
        if (label[seed] >= 0 || cells[seed] == CellClass::shell || cells[seed] == CellClass::solid) continue;
        const int32_t id = static_cast<int32_t>(regions.size());
        regions.emplace_back();
        Region& region = regions.back();
        label[seed] = id;
        stack.assign(1, seed);
        while (!stack.empty()) {
            const int64_t cell = stack.back();
            stack.pop_back();
            const std::array<int, 3> c = grid.coords(cell);
            if (votes[cell] == kLiquid) ++region.liquid_votes;
            if (votes[cell] == kAir) ++region.air_votes;
            for (int a = 0; a < 3; ++a) {
                if (region.size == 0 || -c[a] > region.reach[2 * a]) region.reach[2 * a] = -c[a], region.extreme[2 * a] = cell;
                if (region.size == 0 || c[a] > region.reach[2 * a + 1]) region.reach[2 * a + 1] = c[a], region.extreme[2 * a + 1] = cell;
            }
            ++region.size;
            for_each_face_neighbour(grid, cell, [&](int64_t next) {
                if (next < 0 || cells[next] == CellClass::solid) region.enclosed = false;  // an open border or a wall
                if (next < 0 || label[next] >= 0 || cells[next] == CellClass::shell || cells[next] == CellClass::solid) return;
                label[next] = id;
                stack.push_back(next);
            });
        }
    }
    out.components = static_cast<int>(regions.size());

    // Regions reaching a wall, an obstacle or an open border: by their cells' votes. All one way: that class. Both
    // (an air region and the liquid joined through an obstacle nobody described, or through a hole in the shell):
    // cell by cell, each cell without a vote taking the nearest voting cell's, so the error stays where it is.
    std::vector<CellClass> cell_class(static_cast<std::size_t>(grid.cells), CellClass::air);
    std::vector<int64_t> queue;
    for (Region& region : regions) {
        if (region.enclosed) continue;
        region.split = region.liquid_votes > 0 && region.air_votes > 0;
        region.cls = region.liquid_votes > 0 && region.air_votes == 0 ? CellClass::liquid : CellClass::air;
        out.split_components += region.split ? 1 : 0;
    }
    std::vector<int8_t> spread_votes(votes);
    for (int64_t cell = 0; cell < grid.cells; ++cell)
        if (label[cell] >= 0 && regions[label[cell]].split && votes[cell] != kAbstain) queue.push_back(cell);
    spread(grid, queue, spread_votes, int8_t(kAbstain), [&](int64_t from, int64_t to) { return label[to] == label[from]; });
    for (int64_t cell = 0; cell < grid.cells; ++cell) {
        const int32_t id = label[cell];
        if (id < 0) continue;
        const Region& region = regions[id];
        cell_class[cell] = !region.split ? region.cls : spread_votes[cell] == kLiquid ? CellClass::liquid : CellClass::air;
    }

    // Enclosed regions (a droplet's hollow, a bubble): the opposite of what lies beyond their shell, seen through
    // the shell from their furthest cell in each of the six directions (a bubble just under the surface sees air
    // above it but water on its other sides). Larger regions first: a region inside another is the smaller.
    std::vector<int32_t> enclosed;
    for (int32_t id = 0; id < static_cast<int32_t>(regions.size()); ++id)
        if (regions[id].enclosed) enclosed.push_back(id);
    std::sort(enclosed.begin(), enclosed.end(), [&](int32_t a, int32_t b) {
        return regions[a].size != regions[b].size ? regions[a].size > regions[b].size : a < b;
    });
    for (int32_t id : enclosed) {
        Region& region = regions[id];
        int liquid_beyond = 0, air_beyond = 0;
        CellClass above = CellClass::solid;  // what lies beyond going up, the tie's judge
        for (int side = 0; side < 6; ++side) {
            const int a = side / 2, dir = side % 2 == 0 ? -1 : 1;
            int64_t cell = region.extreme[side];
            std::array<int, 3> c = grid.coords(cell);
            CellClass beyond = CellClass::solid;  // nothing to see: a wall, an obstacle or the grid's end
            for (c[a] += dir; c[a] >= 0 && c[a] < grid.n[a]; c[a] += dir) {
                cell += dir * grid.stride[a];
                if (cells[cell] == CellClass::shell) continue;
                const int32_t other = label[cell];
                if (other >= 0 && (!regions[other].enclosed || regions[other].resolved))
                    beyond = regions[other].enclosed ? regions[other].cls : cell_class[cell];
                break;
            }
            liquid_beyond += beyond == CellClass::liquid ? 1 : 0;
            air_beyond += beyond == CellClass::air ? 1 : 0;
            if (a == up_axis && (dir > 0) == up_positive) above = beyond;
        }
        const bool bubble = liquid_beyond > air_beyond || (liquid_beyond == air_beyond && above == CellClass::liquid);
        region.cls = bubble ? CellClass::air : CellClass::liquid;
        region.resolved = true;
        ++out.enclosed_components;
    }
    for (int64_t cell = 0; cell < grid.cells; ++cell) {
        const int32_t id = label[cell];
        if (id >= 0 && regions[id].enclosed) cell_class[cell] = regions[id].cls;
        if (id >= 0) cells[cell] = cell_class[cell];
    }
    return out;
}

InteriorFill fill_interior(const PositionsView& positions, const FluidDomain& domain, double spacing, int threads,
                           std::size_t memory_budget_bytes) {
    validate_fluid_domain(domain);
    if (!(spacing > 0.0) || !std::isfinite(spacing)) throw InputError("the interior fill's spacing must be positive, got " + format_number(spacing));
    if (positions.count >= std::numeric_limits<uint32_t>::max()) throw InputError("the interior fill takes fewer than 2^32 particles");
    const Grid grid(domain.resolution);
    // Per cell: class, region label, votes, reached, cell lists of particles (bytes), and the per-cell source.
    check_memory_budget(double(grid.cells) * 24.0, memory_budget_bytes, "the interior fill's grid");

    InteriorFill out;
    out.classification = classify_interior(positions, domain, threads);
    const std::vector<CellClass>& cells = out.classification.cells;
    const GridMap map(domain);

    // The particles by cell (counting sort, stable: each cell lists its particles in index order).
    std::vector<int64_t> particle_cell(positions.count, -1);
    parallel_for(static_cast<int64_t>(positions.count), threads, [&](int64_t p) {
        const Vec3 g = map.grid({positions.coord(p, 0), positions.coord(p, 1), positions.coord(p, 2)});
        std::array<int, 3> c{};
        for (int a = 0; a < 3; ++a) {
            if (!(g[a] >= 0.0 && g[a] < grid.n[a])) return;
            c[a] = int(g[a]);
        }
        particle_cell[p] = grid.index(c[0], c[1], c[2]);
    }, 4096);
    std::vector<uint32_t> cell_start(static_cast<std::size_t>(grid.cells) + 1, 0);
    for (int64_t c : particle_cell)
        if (c >= 0) ++cell_start[c + 1];
    for (int64_t c = 0; c < grid.cells; ++c) cell_start[c + 1] += cell_start[c];
    std::vector<uint32_t> by_cell(cell_start.back());
    {
        std::vector<uint32_t> next(cell_start.begin(), cell_start.end() - 1);
        for (std::size_t p = 0; p < positions.count; ++p)
            if (particle_cell[p] >= 0) by_cell[next[particle_cell[p]]++] = static_cast<uint32_t>(p);
    }

    // Cells to fill: the liquid ones and the shell cells nearer to liquid than to air (through the shell; ties go to
    // the liquid): the band's inner half, where the particles are sparse or, beside the liquid's cells, absent.
    std::vector<uint8_t> liquid_side(static_cast<std::size_t>(grid.cells), 0);  // 1 liquid side, 2 air side
    {
        std::vector<int64_t> queue;
        for (CellClass seed : {CellClass::liquid, CellClass::air})
            for (int64_t cell = 0; cell < grid.cells; ++cell)
                if (cells[cell] == seed) {
                    liquid_side[cell] = seed == CellClass::liquid ? 1 : 2;
                    queue.push_back(cell);
                }
        spread(grid, queue, liquid_side, uint8_t(0), [&](int64_t, int64_t to) { return cells[to] == CellClass::shell; });
    }
    const auto is_fill_cell = [&](int64_t cell) { return liquid_side[cell] == 1; };

    // Each cell's nearest particle-holding cell's first particle, by a breadth-first search from those cells through
    // shell and liquid cells: the attributes (velocity) a fill particle far from every particle takes.
    constexpr uint32_t kNoSource = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> cell_source(static_cast<std::size_t>(grid.cells), kNoSource);
    {
        std::vector<int64_t> queue;
        for (int64_t cell = 0; cell < grid.cells; ++cell)
            if (cell_start[cell + 1] > cell_start[cell]) {
                cell_source[cell] = by_cell[cell_start[cell]];
                queue.push_back(cell);
            }
        spread(grid, queue, cell_source, kNoSource,
               [&](int64_t, int64_t to) { return cells[to] == CellClass::liquid || cells[to] == CellClass::shell; });
    }

    // The lattice: m points per cell edge, as dense as the particles are where the band is whole (the cells whose six
    // neighbours all hold particles: the solver seeds m^3 per cell), so the filled water has the band's density
    // whatever the particle radius; without such cells, `spacing` apart. In shell cells only where no particle is
    // nearer than the lattice's own spacing.
    std::array<int, 3> m{};
    double lattice_spacing = std::numeric_limits<double>::infinity();
    {
        double held = 0.0, whole_cells = 0.0;
        for (int64_t cell = 0; cell < grid.cells; ++cell) {
            if (cell_start[cell + 1] == cell_start[cell]) continue;
            bool whole = true;
            for_each_face_neighbour(grid, cell, [&](int64_t next) { whole = whole && next >= 0 && cell_start[next + 1] > cell_start[next]; });
            if (!whole) continue;
            held += cell_start[cell + 1] - cell_start[cell];
            whole_cells += 1.0;
        }
        for (int a = 0; a < 3; ++a) {
            const double edge = std::sqrt(domain.axes[a][0] * domain.axes[a][0] + domain.axes[a][1] * domain.axes[a][1] +
                                          domain.axes[a][2] * domain.axes[a][2]);
            const double per_edge = whole_cells > 0.0 ? std::cbrt(held / whole_cells) : edge / spacing;
            m[a] = std::clamp(int(std::lround(per_edge)), 1, kMaxPointsPerEdge);
            lattice_spacing = std::min(lattice_spacing, edge / m[a]);
        }
    }
    const int per_cell = m[0] * m[1] * m[2];
    std::vector<int64_t> fill_cells;
    for (int64_t cell = 0; cell < grid.cells; ++cell)
        if (is_fill_cell(cell)) fill_cells.push_back(cell);
    // Per fill cell its offset; per point its position and source, and the pipeline's copy of the position.
    check_memory_budget(double(fill_cells.size()) * (8.0 + per_cell * (12.0 + 4.0 + 12.0)), memory_budget_bytes, "the interior fill's particles");

    const double keep_away2 = kKeepAway * kKeepAway * lattice_spacing * lattice_spacing;
    // Calls emit(world position, source particle) for each lattice point the fill cell keeps, in a fixed order.
    const auto for_each_point = [&](int64_t f, auto&& emit) {
        const int64_t cell = fill_cells[f];
        const std::array<int, 3> c = grid.coords(cell);
        const bool shell = cells[cell] == CellClass::shell;
        for (int z = 0; z < m[2]; ++z)
            for (int y = 0; y < m[1]; ++y)
                for (int x = 0; x < m[0]; ++x) {
                    const Vec3 g{c[0] + (x + 0.5) / m[0], c[1] + (y + 0.5) / m[1], c[2] + (z + 0.5) / m[2]};
                    const Vec3 w = map.world(g);
                    uint32_t source = cell_source[cell];
                    if (shell) {
                        double nearest = std::numeric_limits<double>::infinity();
                        for (int dk = -1; dk <= 1; ++dk)
                            for (int dj = -1; dj <= 1; ++dj)
                                for (int di = -1; di <= 1; ++di) {
                                    const int i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
                                    if (i < 0 || j < 0 || k < 0 || i >= grid.n[0] || j >= grid.n[1] || k >= grid.n[2]) continue;
                                    const int64_t nearby = grid.index(i, j, k);  // not 'near': a macro in <windows.h>
                                    for (uint32_t s = cell_start[nearby]; s < cell_start[nearby + 1]; ++s) {
                                        const uint32_t p = by_cell[s];
                                        double d2 = 0.0;
                                        for (int a = 0; a < 3; ++a) {
                                            const double d = positions.coord(p, a) - w[a];
                                            d2 += d * d;
                                        }
                                        if (d2 < nearest || (d2 == nearest && p < source)) {
                                            nearest = d2;
                                            source = p;
                                        }
                                    }
                                }
                        if (nearest < keep_away2) continue;
                    }
                    emit(w, source == kNoSource ? 0u : source);
                }
    };
    // Counted per cell first, then written once into the output at each cell's offset: no per-cell buffers (at
    // resolution 512 their headers and allocations cost more than the points) and no second copy of the points.
    std::vector<std::size_t> offset(fill_cells.size() + 1, 0);
    parallel_for(static_cast<int64_t>(fill_cells.size()), threads, [&](int64_t f) {
        if (cells[fill_cells[f]] != CellClass::shell) {  // every point kept
            offset[f + 1] = static_cast<std::size_t>(per_cell);
            return;
        }
        std::size_t kept = 0;
        for_each_point(f, [&](const Vec3&, uint32_t) { ++kept; });
        offset[f + 1] = kept;
    }, 64);
    for (std::size_t f = 0; f < fill_cells.size(); ++f) offset[f + 1] += offset[f];
    const std::size_t total = positions.count == 0 ? 0 : offset.back();  // no particles: nothing to take attributes from
    out.positions.resize(3 * total);
    out.source.resize(total);
    if (total > 0)
        parallel_for(static_cast<int64_t>(fill_cells.size()), threads, [&](int64_t f) {
            std::size_t o = offset[f];
            for_each_point(f, [&](const Vec3& w, uint32_t source) {
                out.positions[3 * o] = float(w[0]);
                out.positions[3 * o + 1] = float(w[1]);
                out.positions[3 * o + 2] = float(w[2]);
                out.source[o++] = source;
            });
        }, 64);
    return out;
}

}  // namespace meniscus
