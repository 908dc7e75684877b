#include "post/surface_aggregates.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "base/bounding_box.h"
#include "base/compaction.h"
#include "base/concurrent_disjoint_sets.h"
#include "base/errors.h"
#include "base/parallel.h"
#include "base/short_sort.h"
#include "base/uninitialized_vector.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

// The other aggregates the members of `a` have mesh edges to, ascending, each with the number of those edges. An
// aggregate touches a handful of others, so a linear search of the ones found so far beats sorting one entry per
// crossing edge (the coarse graph's build: 0.083 -> 0.068 s at 1 M particles, 2 threads).
void crossing_aggregates(const SurfaceAggregates& g, const CsrList& vertex_neighbours, int64_t a, std::vector<std::pair<int32_t, float>>& out) {
    out.clear();
    for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k) {
        const int32_t v = g.members.items[k];
        for (int64_t e = vertex_neighbours.begin(v); e < vertex_neighbours.end(v); ++e) {
            const int32_t other = g.of_vertex[vertex_neighbours.items[e]];
            if (other == a) continue;
            auto found = std::find_if(out.begin(), out.end(), [&](const std::pair<int32_t, float>& entry) { return entry.first == other; });
            if (found != out.end()) found->second += 1.0f;
            else out.emplace_back(other, 1.0f);
        }
    }
    sort_short(out.begin(), out.end(), [](const std::pair<int32_t, float>& p, const std::pair<int32_t, float>& q) { return p.first < q.first; });
}

}  // namespace

SurfaceAggregates aggregate_surface(const TriMesh& mesh, const MeshAdjacency& adjacency, double cell, int threads) {
    const CsrList& nb = adjacency.vertex_neighbours;
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    require_row_per_vertex(nb, mesh.num_vertices(), "aggregate_surface");
    if (!(cell > 0.0) || !std::isfinite(cell)) throw InputError("aggregate_surface: the cell size must be a positive number");
    SurfaceAggregates g;
    if (nv == 0) return g;

    const FloatBox box = bounding_box(mesh.vertices.data(), nv, threads);
    const double lo[3] = {box.lo[0], box.lo[1], box.lo[2]}, hi[3] = {box.hi[0], box.hi[1], box.hi[2]};
    for (int k = 0; k < 3; ++k)
        if (!((hi[k] - lo[k]) / cell < 2097151.0)) return g;  // beyond the keys' 21 bits (or not finite)
    // Cell coordinates packed in one integer, 21 bits each.
    UninitializedVector<int64_t> key(static_cast<std::size_t>(nv));  // written by the threads first
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            int64_t packed = 0;
            for (int k = 0; k < 3; ++k) {
                const double u = std::floor((double(mesh.vertices[3 * i + k]) - lo[k]) / cell);
                packed = (packed << 21) | (static_cast<int64_t>(std::min(std::max(u, 0.0), 2097151.0)));
            }
            key[i] = packed;
        }
    });
    // The pieces: connected vertices of one cell, united in parallel; each ends rooted at its smallest vertex
    // (base/concurrent_disjoint_sets.h) and they are numbered in that vertex's order, at any thread count.
    ConcurrentDisjointSets pieces(static_cast<std::size_t>(nv), threads);
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i)
            for (int64_t e = nb.begin(i); e < nb.end(i); ++e) {
                const int32_t j = nb.items[e];
                if (j > i && key[j] == key[i]) pieces.unite(static_cast<int32_t>(i), j);
            }
    });
    UninitializedVector<int32_t> root(static_cast<std::size_t>(nv));
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) root[i] = pieces.find(static_cast<int32_t>(i));
    });
    g.of_vertex.resize(static_cast<std::size_t>(nv));
    const int32_t count = static_cast<int32_t>(number_kept(nv, threads, [&](int64_t i) { return root[i] == i; }, g.of_vertex.data()));
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i)
            if (root[i] != i) g.of_vertex[i] = g.of_vertex[root[i]];
    });
    root = UninitializedVector<int32_t>();
    g.members = group_by_key(g.of_vertex.data(), nv, count, threads);

    // The coarse graph, built per block of aggregates (each row from its own members only) and joined in block order.
    constexpr int64_t kRowsPerBlock = 256;
    const int64_t blocks = (count + kRowsPerBlock - 1) / kRowsPerBlock;
    std::vector<std::vector<int32_t>> block_items(static_cast<std::size_t>(blocks));
    std::vector<std::vector<float>> block_coupling(static_cast<std::size_t>(blocks));
    g.neighbours.offsets.assign(static_cast<std::size_t>(count) + 1, 0);
    parallel_for(blocks, threads, [&](int64_t b) {
        std::vector<std::pair<int32_t, float>> crossing;
        for (int64_t a = b * kRowsPerBlock; a < std::min<int64_t>(count, (b + 1) * kRowsPerBlock); ++a) {
            crossing_aggregates(g, nb, a, crossing);
            for (const auto& [other, edges] : crossing) {
                block_items[b].push_back(other);
                block_coupling[b].push_back(edges);
            }
            g.neighbours.offsets[a + 1] = static_cast<int64_t>(crossing.size());
        }
    });
    for (int32_t a = 0; a < count; ++a) g.neighbours.offsets[a + 1] += g.neighbours.offsets[a];
    g.neighbours.items.resize(static_cast<std::size_t>(g.neighbours.offsets.back()));
    g.coupling.resize(g.neighbours.items.size());
    parallel_for(blocks, threads, [&](int64_t b) {
        const int64_t first = g.neighbours.offsets[b * kRowsPerBlock];
        std::copy(block_items[b].begin(), block_items[b].end(), g.neighbours.items.begin() + first);
        std::copy(block_coupling[b].begin(), block_coupling[b].end(), g.coupling.begin() + first);
    });
    return g;
}

std::vector<double> restrict_to_aggregates(const SurfaceAggregates& g, const std::vector<float>& vertex_weights, const float* values,
                                           int dims, int threads) {
    const int64_t count = static_cast<int64_t>(g.size());
    if (dims < 1 || dims > 3) throw InputError("restrict_to_aggregates: 1 to 3 values per vertex expected");
    if (vertex_weights.size() != g.of_vertex.size())
        throw InputError("restrict_to_aggregates: got " + std::to_string(vertex_weights.size()) + " weights for " +
                         std::to_string(g.of_vertex.size()) + " vertices");
    std::vector<double> out(static_cast<std::size_t>(count) * dims, 0.0);
    parallel_blocks(count, threads, 256, [&](int64_t begin, int64_t end) {
        for (int64_t a = begin; a < end; ++a) {
            double sum[3] = {0.0, 0.0, 0.0}, weight = 0.0;
            for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k) {
                const int64_t v = g.members.items[k];
                const double w = vertex_weights[v];
                weight += w;
                for (int d = 0; d < dims; ++d) sum[d] += w * values[dims * v + d];
            }
            if (!(weight > 0.0)) {  // degenerate pieces: the plain mean
                weight = static_cast<double>(g.members.size(a));
                for (int d = 0; d < dims; ++d) sum[d] = 0.0;
                for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k)
                    for (int d = 0; d < dims; ++d) sum[d] += values[dims * static_cast<int64_t>(g.members.items[k]) + d];
            }
            for (int d = 0; d < dims; ++d) out[dims * a + d] = weight > 0.0 ? sum[d] / weight : 0.0;
        }
    });
    return out;
}

double rms_coupled_distance(const SurfaceAggregates& g, const std::vector<double>& points, int threads) {
    const int64_t count = static_cast<int64_t>(g.size());
    if (points.size() != 3 * g.size()) throw InputError("rms_coupled_distance: 3 coordinates per aggregate expected");
    struct Sums {
        double squared = 0.0, weight = 0.0;
    };
    const Sums total = ordered_block_reduce(
        count, threads, kBlock, Sums{},
        [&](int64_t begin, int64_t end, Sums& s) {
            for (int64_t a = begin; a < end; ++a)
                for (int64_t k = g.neighbours.begin(a); k < g.neighbours.end(a); ++k) {
                    const int64_t b = g.neighbours.items[k];
                    double d2 = 0.0;
                    for (int d = 0; d < 3; ++d) d2 += (points[3 * b + d] - points[3 * a + d]) * (points[3 * b + d] - points[3 * a + d]);
                    s.squared += g.coupling[k] * d2;
                    s.weight += g.coupling[k];
                }
        },
        [](Sums& t, const Sums& s) { t.squared += s.squared, t.weight += s.weight; });
    return total.weight > 0.0 ? std::sqrt(total.squared / total.weight) : 0.0;
}

int aggregate_chebyshev(std::vector<double>& x, int dims, const SurfaceAggregates& g, const std::vector<double>& weights,
                        const std::vector<double>& c, int threads) {
    const int64_t count = static_cast<int64_t>(g.size());
    if (dims < 1 || dims > 3 || x.size() != static_cast<std::size_t>(count) * dims)
        throw InputError("aggregate_chebyshev: 1 to 3 values per aggregate expected");
    if (!weights.empty() && weights.size() != g.size()) throw InputError("aggregate_chebyshev: one weight per aggregate expected");
    const int degree = static_cast<int>(c.size()) - 1;
    if (degree < 0 || count == 0) return 0;
    if (degree == 0) {
        for (double& v : x) v *= c[0];
        return 0;
    }
    // y = Y t_in; FIRST: t_out = y, else t_out = 2 y - t_out (the older term, read first); acc += c_k t_out.
    // DIMS a compile-time count: the inner loops unroll (the same operations in the same order as a runtime count).
    auto term = [&](auto dims_constant, const double* in, double* older_out, double* acc, double ck, bool first, int64_t begin, int64_t end) {
        constexpr int DIMS = decltype(dims_constant)::value;
        for (int64_t a = begin; a < end; ++a) {
            double s[DIMS] = {}, total = 0.0;
            for (int64_t k = g.neighbours.begin(a); k < g.neighbours.end(a); ++k) {
                const int64_t b = g.neighbours.items[k];
                total += g.coupling[k];
                for (int d = 0; d < DIMS; ++d) s[d] += g.coupling[k] * in[DIMS * b + d];
            }
            const double w = total > 0.0 ? (weights.empty() ? 1.0 : weights[a]) : 0.0;
            for (int d = 0; d < DIMS; ++d) {
                const double own = in[DIMS * a + d];
                const double y = w > 0.0 ? own + w * (s[d] / total - own) : own;
                const double value = first ? y : 2.0 * y - older_out[DIMS * a + d];
                older_out[DIMS * a + d] = value;
                acc[DIMS * a + d] += ck * value;
            }
        }
    };
    auto term_block = [&](const double* in, double* older_out, double* acc, double ck, bool first, int64_t begin, int64_t end) {
        if (dims == 1) term(std::integral_constant<int, 1>{}, in, older_out, acc, ck, first, begin, end);
        else if (dims == 2) term(std::integral_constant<int, 2>{}, in, older_out, acc, ck, first, begin, end);
        else term(std::integral_constant<int, 3>{}, in, older_out, acc, ck, first, begin, end);
    };
    std::vector<double> older = x, current(x.size()), acc(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) acc[i] = c[0] * x[i];
    // All terms in one parallel region, a loop over fixed blocks per term (its closing barrier is all the
    // synchronisation a term needs), as the mesh's filter does: a region per term counts where other programs hold
    // cores. A few thousand aggregates (coarse meshes, small frames) take less than a barrier: one thread.
    constexpr int64_t kTermBlock = 1024;
    const int64_t blocks = (count + kTermBlock - 1) / kTermBlock;
    parallel_region(count > 4096 ? threads : 1, [&] {
        double* t_older = older.data();
        double* t_current = current.data();
#pragma omp for schedule(dynamic, 1)
        for (int64_t b = 0; b < blocks; ++b)
            term_block(t_older, t_current, acc.data(), c[1], true, b * kTermBlock, std::min(count, (b + 1) * kTermBlock));
        for (int k = 2; k <= degree; ++k) {
#pragma omp for schedule(dynamic, 1)
            for (int64_t b = 0; b < blocks; ++b)
                term_block(t_current, t_older, acc.data(), c[static_cast<std::size_t>(k)], false, b * kTermBlock,
                           std::min(count, (b + 1) * kTermBlock));
            std::swap(t_older, t_current);
        }
    });
    x.swap(acc);
    return degree;
}

}  // namespace meniscus
