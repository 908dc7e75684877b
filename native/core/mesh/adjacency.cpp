#include "mesh/adjacency.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <utility>

#include "base/errors.h"
#include "base/parallel.h"
#include "base/short_sort.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

constexpr int64_t kScanBlock = int64_t{1} << 16;

// offsets[0] == 0 and offsets[r + 1] holds the count of row r: turned into row starts. Fixed blocks: their totals in
// parallel, the totals scanned, then each block's running sum from its start (integer sums: exact in any order).
void exclusive_scan_in_place(UninitializedVector<int64_t>& offsets, int threads) {
    const int64_t rows = static_cast<int64_t>(offsets.size()) - 1;
    const int64_t blocks = (rows + kScanBlock - 1) / kScanBlock;
    std::vector<int64_t> start(static_cast<std::size_t>(blocks) + 1, 0);
    parallel_for(blocks, threads, [&](int64_t b) {
        int64_t sum = 0;
        for (int64_t r = b * kScanBlock, end = std::min(rows, r + kScanBlock); r < end; ++r) sum += offsets[r + 1];
        start[b + 1] = sum;
    });
    for (int64_t b = 0; b < blocks; ++b) start[b + 1] += start[b];
    parallel_for(blocks, threads, [&](int64_t b) {
        int64_t run = start[b];
        for (int64_t r = b * kScanBlock, end = std::min(rows, r + kScanBlock); r < end; ++r) offsets[r + 1] = run += offsets[r + 1];
    });
}

}  // namespace

void require_row_per_vertex(const CsrList& list, std::size_t vertex_count, const std::string& where) {
    if (list.rows() != vertex_count) throw InputError(where + ": the adjacency does not belong to this mesh");
}

namespace {

// The distinct vertices of triangle c (a repeated index listed once), in corner order.
template <class F>
inline void for_distinct_corners(const int32_t* c, F&& f) {
    f(c[0]);
    if (c[1] != c[0]) f(c[1]);
    if (c[2] != c[0] && c[2] != c[1]) f(c[2]);
}

// Items 0 .. n-1 grouped by their keys (keys_of(i, emit) calls emit(key) once per key of item i, each in
// [0, groups)), ascending within a group: a counting sort. One thread visits the items in order, which leaves every
// row sorted. Several count and fill with atomic counters (slots in a row go to items in whatever order the threads
// reach them), then sort every row, so the rows are the serial ones bit for bit.
template <class KeysOf>
CsrList counting_sort_by_keys(int64_t n, int64_t groups, int threads, const KeysOf& keys_of) {
    CsrList list;
    if (threads == 1) {
        list.offsets.assign(static_cast<std::size_t>(groups) + 1, 0);
        int64_t* counts = list.offsets.data() + 1;
        for (int64_t i = 0; i < n; ++i) keys_of(i, [&](int32_t key) { ++counts[key]; });
        exclusive_scan_in_place(list.offsets, 1);
        list.items.resize(static_cast<std::size_t>(list.offsets.back()));
        std::vector<int64_t> cursor(list.offsets.begin(), list.offsets.end() - 1);
        int32_t* items = list.items.data();
        for (int64_t i = 0; i < n; ++i) keys_of(i, [&](int32_t key) { items[cursor[key]++] = static_cast<int32_t>(i); });
        return list;
    }
    // Counters zeroed in parallel (a vector of atomics would zero them on this thread, taking all its page faults).
    std::unique_ptr<std::atomic<int32_t>[]> counts(new std::atomic<int32_t>[static_cast<std::size_t>(groups)]);
    parallel_blocks(groups, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t g = begin; g < end; ++g) counts[g].store(0, std::memory_order_relaxed);
    });
    parallel_blocks(n, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) keys_of(i, [&](int32_t key) { counts[key].fetch_add(1, std::memory_order_relaxed); });
    });
    list.offsets.resize(static_cast<std::size_t>(groups) + 1);
    list.offsets[0] = 0;
    parallel_blocks(groups, threads, kBlock, [&](int64_t begin, int64_t end) {  // the counters become the rows' cursors
        for (int64_t g = begin; g < end; ++g) list.offsets[g + 1] = counts[g].exchange(0, std::memory_order_relaxed);
    });
    exclusive_scan_in_place(list.offsets, threads);
    list.items.resize(static_cast<std::size_t>(list.offsets.back()));
    int32_t* items = list.items.data();
    parallel_blocks(n, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i)
            keys_of(i, [&](int32_t key) {
                items[list.offsets[key] + counts[key].fetch_add(1, std::memory_order_relaxed)] = static_cast<int32_t>(i);
            });
    });
    parallel_blocks(groups, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t g = begin; g < end; ++g) sort_short(items + list.offsets[g], items + list.offsets[g + 1]);
    });
    return list;
}

// The smallest and largest vertex each block of kSpanBlock triangles uses (empty blocks: lo > hi).
constexpr int64_t kSpanBlock = 4096;
struct VertexSpan {
    int32_t lo, hi;
};
std::vector<VertexSpan> block_vertex_spans(const int32_t* tris, int64_t nt, int threads) {
    std::vector<VertexSpan> spans(static_cast<std::size_t>((nt + kSpanBlock - 1) / kSpanBlock));
    parallel_for(static_cast<int64_t>(spans.size()), threads, [&](int64_t b) {
        VertexSpan span{INT32_MAX, INT32_MIN};
        for (int64_t k = 3 * b * kSpanBlock, end = 3 * std::min(nt, (b + 1) * kSpanBlock); k < end; ++k)
            span.lo = std::min(span.lo, tris[k]), span.hi = std::max(span.hi, tris[k]);
        spans[static_cast<std::size_t>(b)] = span;
    });
    return spans;
}

// Each thread owns a range of vertices and runs the counting sort above for its own vertices only, over the blocks of
// triangles that use any of them. No atomics and no sort (rows fill in triangle order). Marching cubes numbers
// vertices and triangles brick by brick, so a block uses a narrow range of vertices: at 1 M particles a block's
// vertices span ~5 % of all, and a block is read by 1.1 / 1.3 / 1.7 owners at 4 / 8 / 16 threads.
CsrList owned_vertex_triangles(const TriMesh& mesh, const std::vector<VertexSpan>& spans, int threads) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    const int32_t* tris = mesh.triangles.data();
    auto owned = [&](int64_t r) { return std::make_pair(r * nv / threads, (r + 1) * nv / threads); };
    CsrList list;
    list.offsets.resize(static_cast<std::size_t>(nv) + 1);
    list.offsets[0] = 0;
    int64_t* counts = list.offsets.data() + 1;
    // Calls visit(t) for the triangles of the blocks that use a vertex of [first, first + span), in order.
    auto for_owned_blocks = [&](int64_t first, int64_t span, auto&& visit) {
        for (std::size_t b = 0; b < spans.size(); ++b) {
            if (spans[b].hi < first || spans[b].lo >= first + span) continue;
            for (int64_t t = static_cast<int64_t>(b) * kSpanBlock, end = std::min(nt, t + kSpanBlock); t < end; ++t) visit(t);
        }
    };
    parallel_for(threads, threads, [&](int64_t r) {
        const int64_t first = owned(r).first, span = owned(r).second - first;
        std::fill(counts + first, counts + first + span, 0);
        for_owned_blocks(first, span, [&](int64_t t) {
            for_distinct_corners(tris + 3 * t, [&](int32_t v) {
                if (static_cast<uint64_t>(v - first) < static_cast<uint64_t>(span)) ++counts[v];
            });
        });
    });
    exclusive_scan_in_place(list.offsets, threads);
    list.items.resize(static_cast<std::size_t>(list.offsets.back()));
    int32_t* items = list.items.data();
    int64_t* starts = list.offsets.data();
    parallel_for(threads, threads, [&](int64_t r) {  // each row's start serves as its cursor (no copy of the starts)
        const int64_t first = owned(r).first, span = owned(r).second - first;
        for_owned_blocks(first, span, [&](int64_t t) {
            const int32_t id = static_cast<int32_t>(t);
            for_distinct_corners(tris + 3 * t, [&](int32_t v) {
                if (static_cast<uint64_t>(v - first) < static_cast<uint64_t>(span)) items[starts[v]++] = id;
            });
        });
    });
    // Every row start now holds the next row's: moved back by one row, a range's first row taking the value its
    // predecessor's last row holds (row 0 starts at 0).
    std::vector<int64_t> range_start(static_cast<std::size_t>(threads));
    int64_t carry = 0;
    for (int r = 0; r < threads; ++r) {
        range_start[static_cast<std::size_t>(r)] = carry;
        if (owned(r).second > owned(r).first) carry = starts[owned(r).second - 1];
    }
    parallel_for(threads, threads, [&](int64_t r) {
        const int64_t first = owned(r).first, last = owned(r).second;
        if (last == first) return;
        for (int64_t v = last - 1; v > first; --v) starts[v] = starts[v - 1];
        starts[first] = range_start[static_cast<std::size_t>(r)];
    });
    return list;
}

// The owned ranges above while a block of triangles is read by at most this many owners on average; beyond it the
// atomic counting below (~2.3x the serial work in all, spread over every thread). An owned range costs its thread
// the serial work times (owners per block) / threads: 2.3 / threads against about that, so they break even near
// 2.3 owners per block; a mesh in no particular order (every block spanning every range) stays atomic.
constexpr double kMostOwnersPerBlock = 2.0;

// The average number of owned ranges a block of triangles touches.
double owners_per_block(const std::vector<VertexSpan>& spans, int64_t nv, int threads) {
    if (spans.empty() || nv == 0) return 0.0;
    int64_t touched = 0;
    for (const VertexSpan& s : spans)
        if (s.lo <= s.hi) touched += (int64_t{s.hi} * threads) / nv - (int64_t{s.lo} * threads) / nv + 1;
    return static_cast<double>(touched) / static_cast<double>(spans.size());
}

}  // namespace

CsrList group_by_key(const int32_t* keys, int64_t n, int32_t groups, int threads) {
    return counting_sort_by_keys(n, groups, resolve_threads(threads), [&](int64_t i, auto&& emit) { emit(keys[i]); });
}

CsrList build_vertex_triangles(const TriMesh& mesh, int threads) {
    threads = resolve_threads(threads);
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    const int32_t* tris = mesh.triangles.data();
    auto corners = [&](int64_t t, auto&& emit) { for_distinct_corners(tris + 3 * t, emit); };
    if (threads > 1) {
        const std::vector<VertexSpan> spans = block_vertex_spans(tris, nt, threads);
        if (owners_per_block(spans, nv, threads) <= kMostOwnersPerBlock) return owned_vertex_triangles(mesh, spans, threads);
    }
    // One thread, or triangles in no particular order: the counting sort, with atomic counters on several threads.
    // (Its serial sweeps over the triangles were most of decimation's time at 16 threads, ~0.2 s at 1 M particles.)
    return counting_sort_by_keys(nt, nv, threads, corners);
}

int32_t collect_vertex_neighbours(const int32_t* tris, int32_t v, const int32_t* fan, int32_t fan_size, int32_t* out) {
    // In a closed manifold fan the vertices following v in its triangles are already all neighbours, each once:
    // sort just those, then add any preceding vertex not among them (open or non-manifold fans only), which
    // halves the sorting work in the common case.
    int32_t* const first = out;
    for (int32_t k = 0; k < fan_size; ++k) {
        const int32_t* t = tris + 3 * static_cast<int64_t>(fan[k]);
        const int corner = corner_of(t, v);
        if (t[(corner + 1) % 3] != v) *out++ = t[(corner + 1) % 3];
    }
    sort_short(first, out);
    out = std::unique(first, out);
    int32_t* const sorted_end = out;
    for (int32_t k = 0; k < fan_size; ++k) {
        const int32_t* t = tris + 3 * static_cast<int64_t>(fan[k]);
        const int corner = corner_of(t, v);
        const int32_t prev = t[(corner + 2) % 3];
        if (prev != v && !std::binary_search(first, sorted_end, prev)) *out++ = prev;
    }
    if (out != sorted_end) {
        sort_short(first, out);
        out = std::unique(first, out);
    }
    return static_cast<int32_t>(out - first);
}

CsrList build_vertex_neighbours(const TriMesh& mesh, const CsrList& vt, int threads) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int32_t* tris = mesh.triangles.data();
    CsrList list;
    // In a closed manifold mesh (marching cubes') a vertex has as many neighbours as triangles: the rows go straight
    // into the triangle rows' layout. A vertex on a border or a non-manifold edge breaks that; then the general
    // path below runs.
    list.items.resize(vt.items.size());
    std::atomic<bool> closed_manifold{true};
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        if (!closed_manifold.load(std::memory_order_relaxed)) return;
        std::vector<int32_t> row;
        for (int64_t v = begin; v < end; ++v) {
            row.resize(2 * static_cast<std::size_t>(vt.size(v)) + 1);
            const int32_t count = collect_vertex_neighbours(tris, static_cast<int32_t>(v), vt.row(v), vt.size(v), row.data());
            if (count != vt.size(v)) {
                closed_manifold.store(false, std::memory_order_relaxed);
                return;
            }
            std::copy(row.begin(), row.begin() + count, list.items.begin() + vt.begin(v));
        }
    });
    if (closed_manifold.load()) {
        copy_in_parallel(vt.offsets.data(), vt.offsets.size(), list.offsets, threads);
        return list;
    }
    list.items = UninitializedVector<int32_t>();  // not held beside the scratch array below
    list.offsets.resize(static_cast<std::size_t>(nv) + 1);  // [v + 1] written for every v below
    list.offsets[0] = 0;
    // Every triangle around v offers two candidates: gather them into v's slice of a scratch array (twice the
    // size of v's triangle row), sort and deduplicate in place, then compact all rows into the result.
    std::unique_ptr<int32_t[]> raw(new int32_t[2 * vt.items.size() + 1]);  // uninitialised: every slot used is written
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v)
            list.offsets[v + 1] = collect_vertex_neighbours(tris, static_cast<int32_t>(v), vt.row(v), vt.size(v), raw.get() + 2 * vt.begin(v));
    });
    exclusive_scan_in_place(list.offsets, threads);
    list.items.resize(static_cast<std::size_t>(list.offsets.back()));
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v)
            std::copy(raw.get() + 2 * vt.begin(v), raw.get() + 2 * vt.begin(v) + (list.offsets[v + 1] - list.offsets[v]),
                      list.items.begin() + list.offsets[v]);
    });
    return list;
}

MeshAdjacency build_adjacency(const TriMesh& mesh, int threads) {
    MeshAdjacency adjacency;
    adjacency.vertex_triangles = build_vertex_triangles(mesh, threads);
    adjacency.vertex_neighbours = build_vertex_neighbours(mesh, adjacency.vertex_triangles, threads);
    return adjacency;
}

void upper_edge_incidences(const TriMesh& mesh, const CsrList& vt, int32_t v, std::vector<EdgeIncidence>& out) {
    out.clear();
    const int32_t* tris = mesh.triangles.data();
    for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
        const int32_t t = vt.items[k];
        const int32_t* c = tris + 3 * static_cast<int64_t>(t);
        if (has_repeated_index(c)) continue;
        const int corner = corner_of(c, v);
        const int32_t next = c[(corner + 1) % 3], prev = c[(corner + 2) % 3];
        if (next > v) out.push_back({next, t, 1});
        if (prev > v) out.push_back({prev, t, -1});
    }
    sort_short(out.begin(), out.end(), [](const EdgeIncidence& a, const EdgeIncidence& b) {
        return a.other != b.other ? a.other < b.other : a.triangle < b.triangle;
    });
}

}  // namespace meniscus
