// Quality report of a surface mesh: topology check, enclosed volume per connected component, and the smoothness
// measures used to compare post-processing settings.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "analysis/scale_metrics.h"
#include "mesh/adjacency.h"
#include "base/numbers.h"
#include "post/postprocess.h"
#include "post/volume.h"

namespace meniscus {

namespace {

// Partial sums are taken over fixed-size blocks and added in block order, so floating-point totals do not depend
// on the thread count.
constexpr int64_t kSumBlock = 8192;

template <class F>
double deterministic_sum(int64_t n, int threads, F&& term) {
    const int64_t blocks = (n + kSumBlock - 1) / kSumBlock;
    std::vector<double> partial(static_cast<std::size_t>(std::max<int64_t>(blocks, 0)), 0.0);
    parallel_for(blocks, threads, [&](int64_t b) {
        double s = 0.0;
        const int64_t end = std::min(n, (b + 1) * kSumBlock);
        for (int64_t i = b * kSumBlock; i < end; ++i) s += term(i);
        partial[b] = s;
    });
    double total = 0.0;
    for (double p : partial) total += p;
    return total;
}

struct Vec {
    double x, y, z;
};
inline Vec sub(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double length(Vec a) { return std::sqrt(dot(a, a)); }

inline Vec vertex(const TriMesh& m, int32_t v) {
    const float* p = m.vertices.data() + 3 * static_cast<int64_t>(v);
    return {p[0], p[1], p[2]};
}

// Signed volume of the tetrahedron (r, a, b, c): summed over a closed oriented surface it is the enclosed volume
// (divergence theorem). Measuring from a point near the mesh instead of the origin keeps the terms small, so far
// from the origin the result does not lose digits to cancellation.
inline double tet_volume(const TriMesh& m, const int32_t* t, Vec r) {
    const Vec a = sub(vertex(m, t[0]), r), b = sub(vertex(m, t[1]), r), c = sub(vertex(m, t[2]), r);
    const double v = dot(a, cross(b, c)) / 6.0;
    return std::isfinite(v) ? v : 0.0;
}

}  // namespace

MeshQuality assess_quality(const TriMesh& mesh, int threads, double scale_length, double raw_mean_edge) {
    MeshQuality q;
    q.check = check_mesh(mesh);  // validates the arrays too
    threads = resolve_threads(threads);
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    q.vertices = static_cast<std::size_t>(nv);
    q.triangles = static_cast<std::size_t>(nt);
    if (nv == 0) return q;
    const int32_t* tris = mesh.triangles.data();

    // Reference point: centre of the bounding box of the finite vertices.
    Vec lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < nv; ++v) {
        const Vec p = vertex(mesh, static_cast<int32_t>(v));
        if (!std::isfinite(p.x + p.y + p.z)) continue;
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const Vec ref = lo.x <= hi.x ? Vec{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)} : Vec{0, 0, 0};

    q.volume = deterministic_sum(nt, threads, [&](int64_t t) { return tet_volume(mesh, tris + 3 * t, ref); });
    q.area = deterministic_sum(nt, threads, [&](int64_t t) {
        const int32_t* c = tris + 3 * t;
        const Vec a = vertex(mesh, c[0]);
        const double area = 0.5 * length(cross(sub(vertex(mesh, c[1]), a), sub(vertex(mesh, c[2]), a)));
        return std::isfinite(area) ? area : 0.0;
    });

    // Connected components by shared vertices (volume.h: labels follow each component's smallest vertex, so they do
    // not depend on the triangle order). Components without triangles (unreferenced vertices) are left out.
    {
        int32_t count = 0;
        const std::vector<int32_t> labels = component_labels(mesh, &count);
        std::vector<int32_t> slot(static_cast<std::size_t>(count), -1);
        std::vector<int32_t> first_label;
        for (int64_t t = 0; t < nt; ++t) {
            const int32_t label = labels[tris[3 * t]];
            if (slot[label] < 0) {
                slot[label] = static_cast<int32_t>(q.components.size());
                q.components.emplace_back();
                first_label.push_back(label);
            }
            ComponentQuality& c = q.components[slot[label]];
            ++c.triangles;
            c.volume += tet_volume(mesh, tris + 3 * t, ref);
        }
        std::vector<std::size_t> order(q.components.size());
        std::iota(order.begin(), order.end(), 0);
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            const ComponentQuality &ca = q.components[a], &cb = q.components[b];
            if (ca.volume != cb.volume) return ca.volume > cb.volume;
            if (ca.triangles != cb.triangles) return ca.triangles > cb.triangles;
            return first_label[a] < first_label[b];
        });
        std::vector<ComponentQuality> sorted;
        sorted.reserve(order.size());
        for (std::size_t i : order) sorted.push_back(q.components[i]);
        q.components.swap(sorted);
    }

    const MeshAdjacency adj = build_adjacency(mesh, threads);

    // Bumpiness: distance of each vertex to its own position in a Taubin low-pass copy (uniform umbrella,
    // lambda = 0.5 / mu = -0.53, 60 pairs). The lambda|mu pair removes high frequencies while (almost) keeping
    // the shape, so what moves is the bumps; averaged over the referenced vertices.
    {
        std::vector<float> a(mesh.vertices), b(mesh.vertices.size());
        for (int pair = 0; pair < 60; ++pair) {
            umbrella_step(adj.vertex_neighbours, a.data(), b.data(), nullptr, 0.5, threads);
            umbrella_step(adj.vertex_neighbours, b.data(), a.data(), nullptr, -0.53, threads);
        }
        int64_t used = 0;
        for (int64_t v = 0; v < nv; ++v) used += adj.valence(v) > 0 ? 1 : 0;
        const double total = deterministic_sum(nv, threads, [&](int64_t v) {
            if (adj.valence(v) == 0) return 0.0;
            const double d = length(sub(vertex(mesh, static_cast<int32_t>(v)), Vec{a[3 * v], a[3 * v + 1], a[3 * v + 2]}));
            return std::isfinite(d) ? d : 0.0;
        });
        q.bumpiness = used > 0 ? total / double(used) : 0.0;
    }

    q.mean_edge_length = mean_edge_length(mesh, adj, threads);
    if (scale_length > 0.0) {
        q.scale_length = scale_length;
        q.hfl_passes = hfl_passes(scale_length, raw_mean_edge > 0.0 ? raw_mean_edge : q.mean_edge_length);
        q.hfl = taubin_distance(mesh, adj, q.hfl_passes, threads);
        q.heat_bumpiness = heat_distance(mesh, adj, scale_length, threads);
    }

    // Mean dihedral deviation: angle between the normals of the two triangles of every manifold edge.
    {
        auto face_normal = [&](int32_t t) {
            const int32_t* c = tris + 3 * static_cast<int64_t>(t);
            const Vec a = vertex(mesh, c[0]);
            return cross(sub(vertex(mesh, c[1]), a), sub(vertex(mesh, c[2]), a));
        };
        // Per block of vertices: sum of angles and number of edges measured (each edge at its smaller vertex;
        // boundary, non-manifold and degenerate-neighbour edges have no angle).
        const int64_t blocks = (nv + kSumBlock - 1) / kSumBlock;
        std::vector<std::pair<double, double>> partial(static_cast<std::size_t>(blocks));
        parallel_for(blocks, threads, [&](int64_t b) {
            std::vector<EdgeIncidence> incidences;
            double sum = 0.0, count = 0.0;
            for (int64_t v = b * kSumBlock; v < std::min(nv, (b + 1) * kSumBlock); ++v) {
                upper_edge_incidences(mesh, adj.vertex_triangles, static_cast<int32_t>(v), incidences);
                for (std::size_t i = 0; i < incidences.size();) {
                    std::size_t j = i;
                    while (j < incidences.size() && incidences[j].other == incidences[i].other) ++j;
                    if (j - i == 2) {
                        const Vec n1 = face_normal(incidences[i].triangle), n2 = face_normal(incidences[i + 1].triangle);
                        const double sn = length(cross(n1, n2)), cs = dot(n1, n2);
                        if ((sn != 0.0 || cs != 0.0) && std::isfinite(sn + cs)) {
                            sum += std::atan2(sn, cs) * (180.0 / kPi);  // accurate for nearly parallel normals
                            count += 1.0;
                        }
                    }
                    i = j;
                }
            }
            partial[b] = {sum, count};
        });
        double sum = 0.0, count = 0.0;
        for (const auto& p : partial) sum += p.first, count += p.second;
        q.mean_normal_angle_deg = count > 0.0 ? sum / count : 0.0;
    }

    int32_t max_valence = 0;
    for (int64_t v = 0; v < nv; ++v) max_valence = std::max(max_valence, adj.valence(v));
    q.valence_histogram.assign(static_cast<std::size_t>(max_valence) + 1, 0);
    for (int64_t v = 0; v < nv; ++v) ++q.valence_histogram[adj.valence(v)];

    q.single_vertex_configurations = count_single_vertex_configurations(adj, threads);
    q.double_vertex_configurations = count_double_vertex_configurations(adj, threads);
    return q;
}

}  // namespace meniscus
