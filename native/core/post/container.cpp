#include "post/container.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "base/parallel.h"
#include "mesh/topology.h"

namespace meniscus {

namespace {

// The box as floats: vertices are floats, and a vertex on a wall holds the plane's coordinate rounded to float.
std::array<float, 6> float_planes(const Vector3& lower, const Vector3& upper) {
    std::array<float, 6> planes{};
    for (int k = 0; k < 3; ++k) {
        planes[static_cast<std::size_t>(2 * k)] = static_cast<float>(lower[k]);
        planes[static_cast<std::size_t>(2 * k + 1)] = static_cast<float>(upper[k]);
    }
    return planes;
}

bool outside(const float* p, const std::array<float, 6>& planes) {
    for (int k = 0; k < 3; ++k)
        if (p[k] < planes[static_cast<std::size_t>(2 * k)] || p[k] > planes[static_cast<std::size_t>(2 * k + 1)]) return true;
    return false;
}

}  // namespace

WallConstraints find_wall_vertices(const TriMesh& mesh, const Vector3& lower, const Vector3& upper, int threads) {
    WallConstraints walls;
    walls.planes = float_planes(lower, upper);
    walls.mask.assign(mesh.num_vertices(), 0);
    parallel_for(static_cast<int64_t>(mesh.num_vertices()), threads, [&](int64_t v) {
        uint8_t faces = 0;
        for (int f = 0; f < 6; ++f)
            if (mesh.vertices[static_cast<std::size_t>(3 * v + f / 2)] == walls.planes[static_cast<std::size_t>(f)]) faces |= uint8_t(1u << f);
        walls.mask[static_cast<std::size_t>(v)] = faces;
    });
    return walls;
}

std::vector<float> counts_mirrored_at_walls(const ParticleGrid& grid, const std::vector<float>& counts, const Vector3& lower,
                                            const Vector3& upper, double support, int threads) {
    std::vector<float> out = counts;
    if (counts.size() != grid.size()) return out;
    const double planes[6] = {lower[0], upper[0], lower[1], upper[1], lower[2], upper[2]};
    parallel_for(static_cast<int64_t>(grid.size()), threads, [&](int64_t j) {
        const float* x = grid.position(static_cast<std::size_t>(j));
        double change = 0.0;
        for (int f = 0; f < 6; ++f) {
            const int k = f / 2;
            const double inside = f % 2 ? planes[f] - x[k] : x[k] - planes[f];  // distance to the wall, inside > 0
            if (!(inside >= 0.0 && inside < support)) continue;
            float m[3] = {x[0], x[1], x[2]};
            m[k] = static_cast<float>(2.0 * planes[f] - x[k]);
            // Cells holding the particles within the support of x or of its image.
            float lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                lo[a] = static_cast<float>(std::min(x[a], m[a]) - support);
                hi[a] = static_cast<float>(std::max(x[a], m[a]) + support);
            }
            grid.for_each_cell_in_box(grid.cell_of(lo), grid.cell_of(hi), [&](std::size_t cell) {
                for (std::size_t i = grid.cell_begin(cell); i < grid.cell_end(cell); ++i) {
                    const float* y = grid.position(i);
                    const bool beyond = f % 2 ? y[k] > planes[f] : y[k] < planes[f];
                    const float* centre = beyond ? x : m;  // a real neighbour beyond goes, an image of one inside comes
                    double d2 = 0.0;
                    for (int a = 0; a < 3; ++a) d2 += (double(y[a]) - centre[a]) * (double(y[a]) - centre[a]);
                    if (d2 >= support * support) continue;
                    const double hat = 1.0 - std::sqrt(d2) / support;
                    change += beyond ? -hat : hat;
                }
            });
        }
        out[static_cast<std::size_t>(j)] = static_cast<float>(std::max(0.0, double(counts[static_cast<std::size_t>(j)]) + change));
    });
    return out;
}

std::size_t square_box_edges(TriMesh& mesh, WallConstraints& walls) {
    const std::size_t nv = mesh.num_vertices();
    if (walls.mask.size() != nv) return 0;
    // Walls each vertex is to join: from every triangle edge (u, v) with u on wall a (not v's) and v on a
    // perpendicular wall b (not u's), a < b, u joins b. Collected over all edges first, so the order does not matter.
    std::vector<uint8_t> join(nv, 0);
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t)
        for (int c = 0; c < 3; ++c) {
            const int32_t u = mesh.triangles[3 * t + c], v = mesh.triangles[3 * t + (c + 1) % 3];
            const int32_t ends[2][2] = {{u, v}, {v, u}};
            for (const auto& e : ends) {
                const uint8_t mine = walls.mask[static_cast<std::size_t>(e[0])], theirs = walls.mask[static_cast<std::size_t>(e[1])];
                for (int a = 0; a < 6; ++a) {
                    if (!((mine >> a) & 1u) || ((theirs >> a) & 1u)) continue;
                    for (int b = a + 1; b < 6; ++b)
                        if (b / 2 != a / 2 && ((theirs >> b) & 1u) && !((mine >> b) & 1u)) join[static_cast<std::size_t>(e[0])] |= uint8_t(1u << b);
                }
            }
        }
    // Two vertices of a triangle may land on the same point of the edge: those triangles' vertices stay where they
    // were, and the check is repeated, since staying can leave another triangle flat (each round keeps more).
    const std::vector<float> before = mesh.vertices;
    for (bool changed = true; changed;) {
        for (std::size_t v = 0; v < nv; ++v) {
            std::copy_n(&before[3 * v], 3, &mesh.vertices[3 * v]);
            for (int f = 0; f < 6; ++f)
                if ((join[v] >> f) & 1u) mesh.vertices[3 * v + f / 2] = walls.planes[static_cast<std::size_t>(f)];
        }
        changed = false;
        for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
            const int32_t* q = &mesh.triangles[3 * t];
            if (!(join[q[0]] || join[q[1]] || join[q[2]]) || !triangle_has_zero_area(mesh.vertices.data(), q)) continue;
            for (int c = 0; c < 3; ++c) join[q[c]] = 0;
            changed = true;
        }
    }
    std::size_t moved = 0;
    for (std::size_t v = 0; v < nv; ++v) {
        walls.mask[v] |= join[v];
        moved += join[v] != 0;
    }
    return moved;
}

std::vector<float> smoothing_amount_at_walls(const WallConstraints& walls, std::vector<float> amount) {
    if (amount.empty()) amount.assign(walls.mask.size(), 1.0f);
    for (std::size_t v = 0; v < walls.mask.size(); ++v)
        if (walls.mask[v]) amount[v] = 1.0f;
    return amount;
}

CsrList smoothing_neighbours_at_walls(const WallConstraints& walls, const CsrList& neighbours) {
    const std::size_t nv = neighbours.rows();
    if (walls.mask.size() != nv) return neighbours;
    std::vector<uint8_t> contact(nv, 0);
    for (std::size_t v = 0; v < nv; ++v)
        if (walls.mask[v])
            for (int64_t k = neighbours.begin(v); k < neighbours.end(v); ++k)
                if (walls.mask[static_cast<std::size_t>(neighbours.items[k])] == 0) contact[v] = 1;
    CsrList out;
    out.offsets.reserve(nv + 1);
    out.items.reserve(neighbours.items.size());
    std::vector<int32_t> row;
    for (std::size_t v = 0; v < nv; ++v) {
        row.clear();
        for (int64_t k = neighbours.begin(v); k < neighbours.end(v); ++k) {
            const int32_t u = neighbours.items[k];
            if (!contact[v] || contact[static_cast<std::size_t>(u)]) row.push_back(u);
        }
        if (contact[v] && row.size() < 2) row.clear();
        out.items.insert(out.items.end(), row.begin(), row.end());
        out.offsets.push_back(static_cast<int64_t>(out.items.size()));
    }
    return out;
}

std::size_t cut_open_at_box(TriMesh& mesh, const Vector3& lower, const Vector3& upper, bool clamp_vertices) {
    const std::array<float, 6> planes = float_planes(lower, upper);
    const std::size_t nv = mesh.num_vertices();
    std::vector<uint8_t> out(nv);
    for (std::size_t v = 0; v < nv; ++v) out[v] = outside(&mesh.vertices[3 * v], planes);
    std::vector<int32_t> triangles;
    triangles.reserve(mesh.triangles.size());
    std::vector<uint8_t> used(nv, 0);
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t* q = &mesh.triangles[3 * t];
        if (out[q[0]] && out[q[1]] && out[q[2]]) continue;
        triangles.insert(triangles.end(), q, q + 3);
        used[q[0]] = used[q[1]] = used[q[2]] = 1;
    }
    const std::size_t removed = mesh.num_triangles() - triangles.size() / 3;
    // Vertices renumbered in their old order, so the result does not depend on anything but the input.
    std::vector<int32_t> renumbered(nv, -1);
    int32_t next = 0;
    for (std::size_t v = 0; v < nv; ++v)
        if (used[v]) renumbered[v] = next++;
    auto keep_used = [&](std::vector<float>& values, std::size_t width) {
        if (values.empty()) return;
        std::size_t w = 0;
        for (std::size_t v = 0; v < nv; ++v)
            if (used[v]) {
                std::copy_n(&values[width * v], width, &values[width * w]);
                ++w;
            }
        values.resize(width * w);
    };
    keep_used(mesh.vertices, 3);
    keep_used(mesh.normals, 3);
    for (Attribute& a : mesh.attributes) keep_used(a.values, static_cast<std::size_t>(a.components));
    for (int32_t& index : triangles) index = renumbered[static_cast<std::size_t>(index)];
    mesh.triangles.swap(triangles);
    if (clamp_vertices) clamp_into_box(mesh, lower, upper);
    return removed;
}

std::size_t clamp_into_box(TriMesh& mesh, const Vector3& lower, const Vector3& upper) {
    const std::array<float, 6> planes = float_planes(lower, upper);
    std::size_t moved = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        float* p = &mesh.vertices[3 * v];
        if (!outside(p, planes)) continue;
        for (int k = 0; k < 3; ++k)
            p[k] = std::min(std::max(p[k], planes[static_cast<std::size_t>(2 * k)]), planes[static_cast<std::size_t>(2 * k + 1)]);
        ++moved;
    }
    return moved;
}

}  // namespace meniscus
