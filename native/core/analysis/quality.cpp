#include "analysis/quality.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

#include "analysis/scale_metrics.h"
#include "base/numbers.h"
#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "mesh/components.h"
#include "mesh/geometry.h"
#include "post/decimation.h"
#include "post/smoothing.h"

namespace meniscus {

namespace {

// Sums go over fixed blocks added in block order (base/parallel.h): totals do not depend on the thread count.
constexpr int64_t kSumBlock = 8192;

// Centre of the bounding box of the finite vertices (the origin when there are none): the point volumes are
// measured from. Near the mesh the terms stay small, so far from the origin no digits are lost to cancellation.
Vec3d reference_point(const TriMesh& mesh) {
    Vec3d lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3d p = vertex_position(mesh.vertices.data(), static_cast<int32_t>(v));
        if (!std::isfinite(p.x + p.y + p.z)) continue;
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    return lo.x <= hi.x ? Vec3d{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)} : Vec3d{0, 0, 0};
}

// Signed volume of the tetrahedron (reference, triangle t): summed over a closed oriented surface it is the
// enclosed volume. 0 where not finite.
double triangle_volume(const TriMesh& mesh, const int32_t* t, Vec3d reference) {
    const float* p = mesh.vertices.data();
    const double v = tetrahedron_volume(vertex_position(p, t[0]) - reference, vertex_position(p, t[1]) - reference,
                                        vertex_position(p, t[2]) - reference);
    return std::isfinite(v) ? v : 0.0;
}

// Connected components by shared vertices (mesh/components.h: labels follow each component's smallest vertex, so
// they do not depend on the triangle order), summed in triangle order, sorted by volume, then triangle count, then
// first label. Components without triangles (unreferenced vertices) are left out.
std::vector<ComponentQuality> components_by_volume(const TriMesh& mesh, Vec3d reference) {
    int32_t count = 0;
    const std::vector<int32_t> labels = component_labels(mesh, &count);
    std::vector<ComponentQuality> components;
    std::vector<int32_t> slot(static_cast<std::size_t>(count), -1), first_label;
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t label = labels[mesh.triangles[3 * t]];
        if (slot[label] < 0) {
            slot[label] = static_cast<int32_t>(components.size());
            components.emplace_back();
            first_label.push_back(label);
        }
        ComponentQuality& c = components[slot[label]];
        ++c.triangles;
        c.volume += triangle_volume(mesh, &mesh.triangles[3 * t], reference);
    }
    std::vector<std::size_t> order(components.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        const ComponentQuality &ca = components[a], &cb = components[b];
        if (ca.volume != cb.volume) return ca.volume > cb.volume;
        if (ca.triangles != cb.triangles) return ca.triangles > cb.triangles;
        return first_label[a] < first_label[b];
    });
    std::vector<ComponentQuality> sorted;
    sorted.reserve(order.size());
    for (std::size_t i : order) sorted.push_back(components[i]);
    return sorted;
}

// Distance of each vertex to its own position in a Taubin low-pass copy (uniform umbrella, lambda = 0.5 /
// mu = -0.53, 60 pairs), averaged over the referenced vertices. The lambda|mu pair removes high frequencies while
// (almost) keeping the shape, so what moves is the bumps.
double bumpiness(const TriMesh& mesh, const MeshAdjacency& adj, int threads) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    std::vector<float> a(mesh.vertices), b(mesh.vertices.size());
    for (int pair = 0; pair < 60; ++pair) {
        umbrella_step(adj.vertex_neighbours, a.data(), b.data(), nullptr, 0.5, threads);
        umbrella_step(adj.vertex_neighbours, b.data(), a.data(), nullptr, -0.53, threads);
    }
    int64_t used = 0;
    for (int64_t v = 0; v < nv; ++v) used += adj.valence(v) > 0 ? 1 : 0;
    const double total = ordered_block_sum(nv, threads, kSumBlock, [&](int64_t v) {
        if (adj.valence(v) == 0) return 0.0;
        const double d = length(vertex_position(mesh.vertices.data(), static_cast<int32_t>(v)) - to_vec3d(&a[3 * v]));
        return std::isfinite(d) ? d : 0.0;
    });
    return used > 0 ? total / double(used) : 0.0;
}

// Mean angle between the normals of the two triangles of every manifold edge, each edge measured at its smaller
// vertex; boundary, non-manifold and degenerate-neighbour edges have no angle.
double mean_normal_angle_deg(const TriMesh& mesh, const MeshAdjacency& adj, int threads) {
    const float* vertices = mesh.vertices.data();
    const int32_t* tris = mesh.triangles.data();
    using SumAndCount = std::pair<double, double>;
    const SumAndCount total = ordered_block_reduce(
        static_cast<int64_t>(mesh.num_vertices()), threads, kSumBlock, SumAndCount{0.0, 0.0},
        [&](int64_t begin, int64_t end, SumAndCount& partial) {
            std::vector<EdgeIncidence> incidences;
            double sum = partial.first, count = partial.second;
            for (int64_t v = begin; v < end; ++v) {
                upper_edge_incidences(mesh, adj.vertex_triangles, static_cast<int32_t>(v), incidences);
                for_each_edge(incidences, [&](const EdgeIncidence* first, const EdgeIncidence* last) {
                    if (last - first != 2) return;
                    const Vec3d n1 = triangle_cross(vertices, tris + 3 * static_cast<int64_t>(first[0].triangle));
                    const Vec3d n2 = triangle_cross(vertices, tris + 3 * static_cast<int64_t>(first[1].triangle));
                    const double sn = length(cross(n1, n2)), cs = dot(n1, n2);
                    if ((sn != 0.0 || cs != 0.0) && std::isfinite(sn + cs)) {
                        sum += std::atan2(sn, cs) * (180.0 / kPi);  // accurate for nearly parallel normals
                        count += 1.0;
                    }
                });
            }
            partial = {sum, count};
        },
        [](SumAndCount& all, const SumAndCount& partial) {
            all.first += partial.first;
            all.second += partial.second;
        });
    return total.second > 0.0 ? total.first / total.second : 0.0;
}

std::vector<std::size_t> valence_histogram(const MeshAdjacency& adj) {
    int32_t max_valence = 0;
    for (std::size_t v = 0; v < adj.vertex_neighbours.rows(); ++v) max_valence = std::max(max_valence, adj.valence(v));
    std::vector<std::size_t> histogram(static_cast<std::size_t>(max_valence) + 1, 0);
    for (std::size_t v = 0; v < adj.vertex_neighbours.rows(); ++v) ++histogram[adj.valence(v)];
    return histogram;
}

}  // namespace

MeshQuality assess_quality(const TriMesh& mesh, int threads, double scale_length, double raw_mean_edge) {
    MeshQuality q;
    q.check = check_mesh(mesh);  // validates the arrays too
    threads = resolve_threads(threads);
    q.vertices = mesh.num_vertices();
    q.triangles = mesh.num_triangles();
    if (q.vertices == 0) return q;
    const int64_t nt = static_cast<int64_t>(q.triangles);
    const int32_t* tris = mesh.triangles.data();

    const Vec3d reference = reference_point(mesh);
    q.volume = ordered_block_sum(nt, threads, kSumBlock, [&](int64_t t) { return triangle_volume(mesh, tris + 3 * t, reference); });
    q.area = ordered_block_sum(nt, threads, kSumBlock, [&](int64_t t) {
        const double area = 0.5 * length(triangle_cross(mesh.vertices.data(), tris + 3 * t));
        return std::isfinite(area) ? area : 0.0;
    });
    q.components = components_by_volume(mesh, reference);

    const MeshAdjacency adj = build_adjacency(mesh, threads);
    q.bumpiness = bumpiness(mesh, adj, threads);
    q.mean_edge_length = mean_edge_length(mesh, adj, threads);
    if (scale_length > 0.0) {
        q.scale_length = scale_length;
        q.hfl_passes = hfl_passes(scale_length, raw_mean_edge > 0.0 ? raw_mean_edge : q.mean_edge_length);
        q.hfl = taubin_distance(mesh, adj, q.hfl_passes, threads);
        q.heat_bumpiness = heat_distance(mesh, adj, scale_length, threads);
    }
    q.mean_normal_angle_deg = mean_normal_angle_deg(mesh, adj, threads);
    q.valence_histogram = valence_histogram(adj);
    q.single_vertex_configurations = count_single_vertex_configurations(adj, threads);
    q.double_vertex_configurations = count_double_vertex_configurations(adj, threads);
    return q;
}

}  // namespace meniscus
