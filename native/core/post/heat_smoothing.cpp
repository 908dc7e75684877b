#include "post/heat_smoothing.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "base/bounding_box.h"
#include "base/errors.h"
#include "base/numbers.h"
#include "base/parallel.h"
#include "base/uninitialized_vector.h"
#include "mesh/adjacency.h"
#include "post/container.h"
#include "post/normals.h"
#include "post/surface_aggregates.h"
#include "post/volume.h"
#include "post/wall_constraints.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;
// Cap of a filter's equivalent explicit iterations: the coefficients cost O(N), the applications O(sqrt N); no real
// scene comes near (c = 0.25: N ~ 1100 for the return on the mesh).
constexpr double kMaxIterations = 1.0e5;

double seconds_since(std::chrono::steady_clock::time_point& mark) {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return s;
}

// A filter exp(N (Y - I)) as it is applied: its Chebyshev series (about 4 sqrt(N) terms), or, where that is longer, N
// explicit steps. For the short filters of the coarse cube sizes' many parts (c = 1.0: N = 4.4 per part, a series of
// 7 terms against 5 steps) and of the returns' blend (N ~ 1-2: 3-5 terms against 1-2 steps), ceil(N) steps of
// Y_b = I + b w (mean - I), b = N / ceil(N) <= 1, are the same heat time for fewer applications: their response
// (1 - b l)^ceil(N) matches exp(-N l) at the low frequencies l that shape the surface and still damps the high ones
// (|1 - b l| < 1 on a triangle mesh's spectrum).
struct HeatPolynomial {
    std::vector<double> chebyshev;  // the series' coefficients when explicit_steps == 0
    int explicit_steps = 0;
    float step_size = 1.0f;  // b
    int applications() const { return explicit_steps > 0 ? explicit_steps : static_cast<int>(chebyshev.size()) - 1; }
};

HeatPolynomial heat_polynomial(double n, double tolerance, bool allow_explicit) {
    HeatPolynomial p;
    p.chebyshev = heat_coefficients(n, tolerance);
    const double steps = std::ceil(n);
    if (allow_explicit && n > 0.0 && steps < static_cast<double>(p.chebyshev.size()) - 1.0) {
        p.chebyshev.clear();
        p.explicit_steps = static_cast<int>(steps);
        p.step_size = static_cast<float>(n / steps);
    }
    return p;
}

// The Chebyshev recurrence's three vectors, kept across the filters of one smoothing (a few tens of MB each at a
// million vertices: allocated once, their pages are not faulted in again by every filter), in one buffer that the
// returns' normals borrow between filters for their per-triangle cross products (so those add nothing to the memory
// peak). Left unwritten by its resize: the parallel loops touch it first (zero-filled on one thread, the first filter
// took 0.15 s more than the others at 1 M particles, 2 threads).
struct HeatFilterWorkspace {
    UninitializedVector<float> storage;
    // At least n floats; a buffer already large enough is kept as it is (its contents are scratch).
    float* scratch(std::size_t n) {
        if (storage.size() < n) storage = UninitializedVector<float>(n);
        return storage.data();
    }
    // The polynomial of each (n, tolerance) a smoothing's filters ask for, made once: every part's filters ask for the
    // same few (~1000 cosines each, serial, while the other threads wait).
    const HeatPolynomial& polynomial(double n, double tolerance, bool allow_explicit) {
        for (const Known& known : cache)
            if (known.n == n && known.tolerance == tolerance && known.allow_explicit == allow_explicit) return known.polynomial;
        cache.push_back({n, tolerance, allow_explicit, heat_polynomial(n, tolerance, allow_explicit)});
        return cache.back().polynomial;
    }
    struct Known {
        double n, tolerance;
        bool allow_explicit;
        HeatPolynomial polynomial;
    };
    std::deque<Known> cache;  // a deque: references to its elements stay valid as it grows
    // The point positions are taken relative to (a smoothing's parts: its bounding box's centre, found once; a filter
    // alone finds its own).
    bool has_centre = false;
    float centre[3] = {0.0f, 0.0f, 0.0f};
};

// The operator's rows at a fixed width, kRowWidth columns per vertex, so the inner loop has no data-dependent trip
// count (a varying valence costs a mispredicted branch per vertex; 0.55 -> 0.44 s for the flow at 1 M particles,
// c = 0.5). A shorter row is padded with the vertex itself (x_i - x_i adds an exact zero); a longer one holds its
// first kRowWidth - 1 neighbours and, last, ~k with overflow[k] = the count of the rest, then the rest. The rows keep
// their order, so the sums have the bits of the CSR rows'.
constexpr int kRowWidth = 8;
struct UmbrellaRows {
    UninitializedVector<int32_t> columns;  // every column written by umbrella_rows' threads (their first touch)
    std::vector<int32_t> overflow;
};

UmbrellaRows umbrella_rows(const CsrList& nb, int threads) {
    const int64_t nv = static_cast<int64_t>(nb.rows());
    UmbrellaRows rows;
    rows.columns.resize(static_cast<std::size_t>(nv) * kRowWidth);
    const bool any_long = parallel_count(nv, threads, [&](int64_t i) { return nb.size(i) > kRowWidth; }) > 0;
    for (int64_t i = 0; any_long && i < nv; ++i)  // the rare long rows' rests, in vertex order; their other columns below
        if (nb.size(i) > kRowWidth) {
            rows.columns[kRowWidth * i + kRowWidth - 1] = ~static_cast<int32_t>(rows.overflow.size());
            rows.overflow.push_back(nb.size(i) - (kRowWidth - 1));
            rows.overflow.insert(rows.overflow.end(), nb.row(i) + (kRowWidth - 1), nb.row(i) + nb.size(i));
        }
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            const int32_t m = nb.size(i);
            const int32_t* row = nb.row(i);
            int32_t* out = rows.columns.data() + kRowWidth * i;
            if (m > kRowWidth) std::copy(row, row + (kRowWidth - 1), out);
            else
                for (int k = 0; k < kRowWidth; ++k) out[k] = k < m ? row[k] : static_cast<int32_t>(i);
        }
    });
    return rows;
}

// Per vertex w_i / m_i: the step of Y = I + w (mean - I). 0 (weight 0, no neighbours): the vertex keeps its bits.
std::vector<float> umbrella_steps(const CsrList& nb, const std::vector<float>& weights, int threads) {
    const int64_t nv = static_cast<int64_t>(nb.rows());
    std::vector<float> steps(static_cast<std::size_t>(nv));
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            const int32_t m = nb.size(i);
            steps[i] = m > 0 ? (weights.empty() ? 1.0f : weights[i]) / static_cast<float>(m) : 0.0f;
        }
    });
    return steps;
}

// Three coordinates as one 4-lane vector (the fourth lane reads the next value and is dropped): one load, subtraction
// and addition per neighbour instead of three, the same IEEE single-precision operations lane by lane, so the same
// bits (0.44 -> 0.34 s for the flow at 1 M particles). GCC and clang (every platform we build for); others use the
// scalar loop.
#if defined(__GNUC__)
#define MENISCUS_FLOAT4 1
typedef float Float4 __attribute__((vector_size(16)));
inline Float4 load_float4(const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
#endif

// The umbrella sum over row i, s = sum_j (x_j - x_i), in row order.
template <int D>
inline void umbrella_sum(const UmbrellaRows& rows, int64_t i, const float* in, float* s) {
    const int32_t* row = rows.columns.data() + kRowWidth * i;
    const int32_t last = row[kRowWidth - 1];
    const int32_t* rest = last < 0 ? rows.overflow.data() + ~static_cast<int64_t>(last) : nullptr;
    const float* xi = in + D * i;
#ifdef MENISCUS_FLOAT4
    if (D == 3) {
        const Float4 x = load_float4(xi);
        Float4 sum = {0.0f, 0.0f, 0.0f, 0.0f};
        for (int k = 0; k < kRowWidth - 1; ++k) sum += load_float4(in + D * static_cast<int64_t>(row[k])) - x;
        if (!rest) sum += load_float4(in + D * static_cast<int64_t>(last)) - x;
        else
            for (int32_t k = 1; k <= rest[0]; ++k) sum += load_float4(in + D * static_cast<int64_t>(rest[k])) - x;
        for (int d = 0; d < D; ++d) s[d] = sum[d];
        return;
    }
#endif
    for (int d = 0; d < D; ++d) s[d] = 0.0f;
    auto add = [&](int32_t j) {
        const float* xj = in + D * static_cast<int64_t>(j);
        for (int d = 0; d < D; ++d) s[d] += xj[d] - xi[d];
    };
    for (int k = 0; k < kRowWidth - 1; ++k) add(row[k]);
    if (!rest) add(last);
    else
        for (int32_t k = 1; k <= rest[0]; ++k) add(rest[k]);
}

// One Chebyshev term on vertices [begin, end): t_out = 2 Y t_in - t_older (the first: t_out = Y t_in), written over
// t_older (read first). Y = I + w (mean - I) per vertex; coordinates set in `frozen` are left as they are
// (y = t_in). With ACC the two newest terms go into the sum at once, acc += c_in t_in + c_out t_out (t_in is loaded
// for the stencil anyway): the accumulator is read and written every second term only.
template <int D, bool FIRST, bool FROZEN, bool ACC>
void chebyshev_term(const UmbrellaRows& rows, const float* steps, const uint8_t* frozen, const float* in, float* older_out, float* acc,
                    float c_in, float c_out, int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) {
        const float* xi = in + D * i;
        float s[D];
        umbrella_sum<D>(rows, i, in, s);
        for (int d = 0; d < D; ++d) {
            float y = xi[d] + steps[i] * s[d];  // (Y t_in)_i
            if (FROZEN && (frozen[i] >> d & 1u)) y = xi[d];
            const float value = FIRST ? y : 2.0f * y - older_out[D * i + d];
            older_out[D * i + d] = value;
            if (ACC) acc[D * i + d] += c_in * xi[d] + c_out * value;
        }
    }
}

template <int D, bool FIRST, bool FROZEN>
void chebyshev_term(bool accumulate, const UmbrellaRows& rows, const float* steps, const uint8_t* frozen, const float* in, float* older_out,
                    float* acc, float c_in, float c_out, int64_t begin, int64_t end) {
    if (accumulate)
        chebyshev_term<D, FIRST, FROZEN, true>(rows, steps, frozen, in, older_out, acc, c_in, c_out, begin, end);
    else
        chebyshev_term<D, FIRST, FROZEN, false>(rows, steps, frozen, in, older_out, acc, c_in, c_out, begin, end);
}

// One explicit step on vertices [begin, end): out = Y_b in, Y_b = I + b w (mean - I) per vertex; coordinates set in
// `frozen` are left as they are. With b = 1 the arithmetic of the series' Y.
template <int D, bool FROZEN>
void explicit_step(const UmbrellaRows& rows, const float* steps, const uint8_t* frozen, float step_size, const float* in, float* out,
                   int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) {
        const float* xi = in + D * i;
        float s[D];
        umbrella_sum<D>(rows, i, in, s);
        const float step = step_size * steps[i];
        for (int d = 0; d < D; ++d) out[D * i + d] = FROZEN && (frozen[i] >> d & 1u) ? xi[d] : xi[d] + step * s[d];
    }
}

// The centre of the bounding box of 3 floats per vertex.
void bounding_box_centre(const std::vector<float>& x, int threads, float centre[3]) {
    const FloatBox box = bounding_box(x.data(), static_cast<int64_t>(x.size() / 3), threads);
    for (int d = 0; d < 3; ++d) centre[d] = 0.5f * box.lo[d] + 0.5f * box.hi[d];
}

// The values a filter starts from and what it does with its result, per vertex and coordinate: by default x's own,
// written back to x; a return starts from its prolonged values and moves the vertices by its result in the same
// parallel region (each region's start and barrier count where other programs hold cores).
struct ReadValues {
    const float* x;
    float operator()(int64_t i, int d, int dims) const { return x[dims * i + d]; }
};
// x's own values, each also copied to `kept` as it is read (a part's start, for its return: no pass of its own).
struct ReadAndKeepValues {
    const float* x;
    float* kept;
    float operator()(int64_t i, int d, int dims) const { return kept[dims * i + d] = x[dims * i + d]; }
};
struct WriteValues {
    float* x;
    void operator()(int64_t i, int d, int dims, float value) const { x[dims * i + d] = value; }
};

template <int D, bool FROZEN, class Start = ReadValues, class Finish = WriteValues>
int apply_heat_polynomial(std::vector<float>& x, const UmbrellaRows& rows, const std::vector<float>& steps, const uint8_t* frozen,
                          const HeatPolynomial& polynomial, int threads, HeatFilterWorkspace& workspace, Start start = Start{nullptr},
                          Finish finish = Finish{nullptr}) {
    if constexpr (std::is_same<Start, ReadValues>::value) start.x = x.data();
    if constexpr (std::is_same<Finish, WriteValues>::value) finish.x = x.data();
    const int64_t nv = static_cast<int64_t>(steps.size());
    const std::vector<double>& c = polynomial.chebyshev;
    const int explicit_steps = polynomial.explicit_steps;
    const int degree = explicit_steps > 0 ? 0 : static_cast<int>(c.size()) - 1;
    // Positions relative to the centre of their bounding box (small numbers wherever the mesh lies); the result is a
    // convex combination of the terms (the heat kernel's coefficients are positive), accumulated directly: no stream
    // of the start values is needed inside the loop.
    float centre[D];
    for (int d = 0; d < D; ++d) centre[d] = 0.0f;
    if (D == 3) {
        float box_centre[3];
        if (workspace.has_centre) std::copy(workspace.centre, workspace.centre + 3, box_centre);
        else bounding_box_centre(x, threads, box_centre);
        for (int d = 0; d < D; ++d) centre[d] = box_centre[d];
    }
    // Every element of the three is written before it is read: resizing a reused buffer needs no clearing. One float
    // more in the two the stencil reads, for the last vertex's 4-lane load (load_float4): set to zero here, never
    // written by the terms, and its lane is dropped.
    const std::size_t stride = x.size() + 1;
    float* const older = workspace.scratch(3 * stride);
    float* const current = older + stride;
    float* const acc = current + stride;
    older[x.size()] = 0.0f, current[x.size()] = 0.0f;
    const float c0 = degree > 0 ? static_cast<float>(c[0]) : 1.0f;
    auto coefficient = [&](int k) { return static_cast<float>(c[static_cast<std::size_t>(k)]); };
    // All terms in one parallel region, a loop over fixed blocks per term: the barrier closing each loop (a term
    // reads its neighbours' previous terms) is all the synchronisation, instead of a region started and joined per
    // term, which counts on a machine whose other programs hold some cores. Every vertex's arithmetic is that of
    // the serial loop, so the bits do not depend on the threads. Nothing in here throws.
    const int64_t blocks = (nv + kBlock - 1) / kBlock;
    const float* const centre_of = centre;
    parallel_region(threads, [&] {
        // Each thread swaps its own copies of the two term pointers after every term, so all agree.
        float* t_older = older;
        float* t_current = current;
#pragma omp for schedule(dynamic, 1)
        for (int64_t b = 0; b < blocks; ++b)
            for (int64_t i = b * kBlock, end = std::min(nv, (b + 1) * kBlock); i < end; ++i)
                for (int d = 0; d < D; ++d) {
                    const float t = start(i, d, D) - centre_of[d];
                    t_older[D * i + d] = t;
                    if (explicit_steps == 0) acc[D * i + d] = c0 * t;
                }
        // The result of each block as soon as its last term is in: a vertex's result reads only its own sum (and the
        // terms read no x), so this needs no barrier of its own.
        auto finish_block = [&](const float* result, int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) {
                if (steps[i] == 0.0f) {  // not moved: keeps its bits
                    if constexpr (!std::is_same<Start, ReadValues>::value)
                        for (int d = 0; d < D; ++d) finish(i, d, D, start(i, d, D));
                    continue;
                }
                for (int d = 0; d < D; ++d) finish(i, d, D, centre_of[d] + result[D * i + d]);
            }
        };
        for (int k = 1; k <= explicit_steps; ++k) {
#pragma omp for schedule(dynamic, 1)
            for (int64_t b = 0; b < blocks; ++b) {
                const int64_t begin = b * kBlock, end = std::min(nv, (b + 1) * kBlock);
                explicit_step<D, FROZEN>(rows, steps.data(), frozen, polynomial.step_size, t_older, t_current, begin, end);
                if (k == explicit_steps) finish_block(t_current, begin, end);
            }
            std::swap(t_older, t_current);
        }
        // Term k is added together with term k - 1 when k is even, alone when it is the last and odd.
        if (degree > 0) {
#pragma omp for schedule(dynamic, 1)
            for (int64_t b = 0; b < blocks; ++b) {
                const int64_t begin = b * kBlock, end = std::min(nv, (b + 1) * kBlock);
                chebyshev_term<D, true, FROZEN>(degree == 1, rows, steps.data(), frozen, t_older, t_current, acc, 0.0f, coefficient(1), begin, end);
                if (degree == 1) finish_block(acc, begin, end);
            }
            for (int k = 2; k <= degree; ++k) {
                const bool even = k % 2 == 0;
#pragma omp for schedule(dynamic, 1)
                for (int64_t b = 0; b < blocks; ++b) {
                    const int64_t begin = b * kBlock, end = std::min(nv, (b + 1) * kBlock);
                    chebyshev_term<D, false, FROZEN>(even || k == degree, rows, steps.data(), frozen, t_current, t_older, acc,
                                                     even ? coefficient(k - 1) : 0.0f, coefficient(k), begin, end);
                    if (k == degree) finish_block(acc, begin, end);
                }
                std::swap(t_older, t_current);
            }
        }
    });
    return polynomial.applications();
}

// heat_filter on rows and steps made once for several filters; allow_explicit: explicit steps where they are shorter
// than the series (HeatPolynomial). kept: when given, receives x as it was (dims floats per vertex).
int heat_filter_on_rows(std::vector<float>& x, int dims, const UmbrellaRows& rows, const std::vector<float>& steps, double n,
                        double tolerance, bool allow_explicit, int threads, const uint8_t* frozen, HeatFilterWorkspace& workspace,
                        float* kept = nullptr) {
    const HeatPolynomial& p = workspace.polynomial(n, tolerance, allow_explicit);
    if (p.applications() < 1 || steps.empty()) {
        if (kept) std::copy(x.begin(), x.end(), kept);
        return 0;
    }
    if (kept) {
        const ReadAndKeepValues start{x.data(), kept};
        if (dims == 3)
            return frozen ? apply_heat_polynomial<3, true>(x, rows, steps, frozen, p, threads, workspace, start)
                          : apply_heat_polynomial<3, false>(x, rows, steps, nullptr, p, threads, workspace, start);
        return frozen ? apply_heat_polynomial<1, true>(x, rows, steps, frozen, p, threads, workspace, start)
                      : apply_heat_polynomial<1, false>(x, rows, steps, nullptr, p, threads, workspace, start);
    }
    if (dims == 3)
        return frozen ? apply_heat_polynomial<3, true>(x, rows, steps, frozen, p, threads, workspace)
                      : apply_heat_polynomial<3, false>(x, rows, steps, nullptr, p, threads, workspace);
    return frozen ? apply_heat_polynomial<1, true>(x, rows, steps, frozen, p, threads, workspace)
                  : apply_heat_polynomial<1, false>(x, rows, steps, nullptr, p, threads, workspace);
}

// Most parts the flow may run in (each a filter and a return over the whole mesh).
constexpr int kMaxParts = 10000;

void apply_walls(const WallConstraints* walls, TriMesh& mesh) {
    if (walls && !walls->empty()) walls->apply(mesh.vertices.data(), mesh.num_vertices());
}

void require_valid_walls(const WallConstraints& walls, std::size_t vertex_count) {
    if (walls.mask.size() != vertex_count) throw InputError("heat_smooth: the wall mask does not belong to this mesh");
    static const char* const kFaces[6] = {"min x", "max x", "min y", "max y", "min z", "max z"};
    for (int f = 0; f < 6; ++f)
        if (!std::isfinite(walls.planes[static_cast<std::size_t>(f)]))
            throw InputError(std::string("heat_smooth: the container's ") + kFaces[f] + " wall is not a finite number");
}

// Unit area-weighted vertex normals and, when `areas` is given, vertex areas (a third of the incident triangles'
// areas). Every part's return needs them: float cross products (the normals only set the return's direction, and the
// edges of one triangle are of one size), each triangle's once into the workspace (free between the filters), then
// gathered per vertex in its vertex -> triangle row's order (crossing per corner read three vertices three times
// for every triangle: ~0.057 -> ~0.03 s per return at 1 M particles, 2 threads).
void vertex_normals(const TriMesh& mesh, const MeshAdjacency& adjacency, std::vector<float>& normals, std::vector<float>* areas,
                    HeatFilterWorkspace& workspace, int threads, const float* before = nullptr, std::vector<float>* offset = nullptr) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    const CsrList& vt = adjacency.vertex_triangles;
    normals.resize(mesh.vertices.size());
    if (areas) areas->resize(static_cast<std::size_t>(nv));
    float* const face_cross = workspace.scratch(static_cast<std::size_t>(3 * nt));
    const float* x = mesh.vertices.data();
    // One parallel region for both loops (nothing in them throws): the returns run once per part, and at coarse cube
    // sizes (15 parts on small meshes) each region's start counts where other programs hold cores.
    const int64_t face_blocks = (nt + kBlock - 1) / kBlock, vertex_blocks = (nv + kBlock - 1) / kBlock;
    parallel_region(threads, [&] {
#pragma omp for schedule(dynamic, 1)
        for (int64_t block = 0; block < face_blocks; ++block)
            for (int64_t f = block * kBlock, end = std::min(nt, (block + 1) * kBlock); f < end; ++f) {
                const int32_t* t = mesh.triangles.data() + 3 * f;
                const float *a = x + 3 * static_cast<int64_t>(t[0]), *b = x + 3 * static_cast<int64_t>(t[1]), *c = x + 3 * static_cast<int64_t>(t[2]);
                const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
                const float w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
                float* n = face_cross + 3 * f;
                n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
                if (!std::isfinite(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])) n[0] = n[1] = n[2] = 0.0f;
            }
#pragma omp for schedule(dynamic, 1)
        for (int64_t block = 0; block < vertex_blocks; ++block)
            for (int64_t v = block * kBlock, end = std::min(nv, (block + 1) * kBlock); v < end; ++v) {
                double sum[3] = {0.0, 0.0, 0.0}, area = 0.0;
                for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
                    const float* n = face_cross + 3 * static_cast<int64_t>(vt.items[k]);
                    sum[0] += n[0], sum[1] += n[1], sum[2] += n[2];
                    if (areas) area += std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]) / 6.0;
                }
                double l = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
                if (!(l > 0.0)) {  // opposite faces cancel (a sheet folded onto itself): the largest incident face's
                    double largest_norm = 0.0;
                    sum[0] = 0.0, sum[1] = 0.0, sum[2] = 1.0;
                    for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
                        const float* n = face_cross + 3 * static_cast<int64_t>(vt.items[k]);
                        const double norm2 = double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2];
                        if (norm2 > largest_norm) largest_norm = norm2, sum[0] = n[0], sum[1] = n[1], sum[2] = n[2];
                    }
                    l = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
                }
                for (int k = 0; k < 3; ++k) normals[3 * v + k] = static_cast<float>(sum[k] / l);
                if (areas) (*areas)[v] = static_cast<float>(area);
                if (offset) {  // the normal component of the move from `before`, while the normal is at hand
                    float d = 0.0f;
                    for (int k = 0; k < 3; ++k) d += (mesh.vertices[3 * v + k] - before[3 * v + k]) * normals[3 * v + k];
                    (*offset)[v] = d;
                }
            }
    });
}

// The surface's aggregates (post/surface_aggregates.h) with what the return's low-pass needs of them, built once per
// smoothing. The mesh's umbrella low-pass keeps sum(valence x), so the aggregates' one is made to keep it too (and
// then returns what the mesh's would): values are restricted as valence-weighted means, and filtered as a normalised
// convolution of the density mass / coupling (mass: the members' valences). The coupling-weighted mean alone keeps
// sum(coupling x) (a random walk's stationary weights): a small corner piece has much border for its size and would
// draw the returned displacement to itself (hilbert2 at c = 0.5 kept 0.977 of its volume before the final
// correction, the mesh's low-pass 1.010). f(P)(rho x) / f(P)(rho) is f(P^T) on the mass-weighted field.
struct ReturnAggregates {
    SurfaceAggregates aggregates;
    std::vector<float> valence;   // per vertex
    std::vector<double> density;  // per aggregate: mass / coupling (0 when coupled to nothing)
    std::vector<double> filtered_density;  // per aggregate: the density low-passed (the same for every part's return)
    std::vector<double> centre;   // per aggregate: area-weighted centroid of the surface they were built from
    double coarse_edge = 0.0;     // RMS coupled distance between the centres
};

ReturnAggregates return_aggregates(const TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& areas, double cell,
                                   int threads) {
    ReturnAggregates r;
    r.aggregates = aggregate_surface(mesh, adjacency, cell, threads);
    const SurfaceAggregates& g = r.aggregates;
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    r.valence.resize(static_cast<std::size_t>(nv));
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) r.valence[i] = static_cast<float>(adjacency.vertex_neighbours.size(i));
    });
    r.density.resize(g.size());
    parallel_blocks(static_cast<int64_t>(g.size()), threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t a = begin; a < end; ++a) {
            double mass = 0.0, degree = 0.0;
            for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k) mass += r.valence[g.members.items[k]];
            for (int64_t k = g.neighbours.begin(a); k < g.neighbours.end(a); ++k) degree += g.coupling[k];
            r.density[a] = degree > 0.0 ? mass / degree : 0.0;
        }
    });
    if (g.size() == 0) return r;  // the scene spans too many cells for the keys: the return low-passes on the mesh
    r.centre = restrict_to_aggregates(g, areas, mesh.vertices.data(), 3, threads);
    r.coarse_edge = rms_coupled_distance(g, r.centre, threads);
    return r;
}

// Values per aggregate (restricted as ReturnAggregates says) low-passed in place over `reach` on the aggregate graph:
// the same heat kernel as the mesh's (its N from the aggregates' own coupled distance), as a normalised convolution.
void coarse_low_pass(std::vector<double>& coarse, ReturnAggregates& coarse_surface, double reach, double tolerance, int threads,
                     HeatSmoothingReport& report, HeatFilterWorkspace& workspace) {
    // A low-pass stays within the values it averages; the truncated series could overshoot where the denominator
    // below is small.
    double lowest = 0.0, highest = 0.0;
    if (!coarse.empty()) {
        const auto range = std::minmax_element(coarse.begin(), coarse.end());
        lowest = *range.first, highest = *range.second;
    }
    const SurfaceAggregates& aggregates = coarse_surface.aggregates;
    const double coarse_edge = coarse_surface.coarse_edge;
    report.coarse_edge = coarse_edge;
    if (!(coarse_edge > 0.0)) return;
    const int64_t na = static_cast<int64_t>(aggregates.size());
    const std::vector<double>& c = workspace.polynomial(std::min(std::pow(reach / coarse_edge, 2.0), kMaxIterations), tolerance, false).chebyshev;
    // The filtered density is the same every part: filtered once, on the first return.
    if (coarse_surface.filtered_density.empty()) {
        coarse_surface.filtered_density = coarse_surface.density;
        report.coarse_applications += aggregate_chebyshev(coarse_surface.filtered_density, 1, aggregates, {}, c, threads);
    }
    std::vector<double> mass(static_cast<std::size_t>(na));  // rho x per aggregate
    for (int64_t a = 0; a < na; ++a) mass[a] = coarse_surface.density[a] * coarse[a];
    report.coarse_applications += aggregate_chebyshev(mass, 1, aggregates, {}, c, threads);
    for (int64_t a = 0; a < na; ++a)
        if (coarse_surface.filtered_density[a] > 0.0)
            coarse[a] = std::min(std::max(mass[a] / coarse_surface.filtered_density[a], lowest), highest);
}

// The value of the aggregates at vertex i: a distance-weighted mean over the vertex's aggregate and the ones coupled to
// it (no steps at aggregate borders), (1 - d^2 / (2 cell)^2)^2: smooth, zero two cells away, and the same bits with any
// maths library.
float prolonged_value(const std::vector<double>& coarse, const TriMesh& mesh, const ReturnAggregates& coarse_surface, double cell, int64_t i) {
    const SurfaceAggregates& aggregates = coarse_surface.aggregates;
    const std::vector<double>& centre = coarse_surface.centre;
    const double falloff = 1.0 / (4.0 * cell * cell);
    const int32_t own = aggregates.of_vertex[i];
    double sum = 0.0, total = 0.0;
    auto add = [&](int64_t a) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) d2 += (centre[3 * a + k] - mesh.vertices[3 * i + k]) * (centre[3 * a + k] - mesh.vertices[3 * i + k]);
        const double fall = std::max(0.0, 1.0 - d2 * falloff), phi = fall * fall;
        sum += phi * coarse[a];
        total += phi;
    };
    add(own);
    for (int64_t k = aggregates.neighbours.begin(own); k < aggregates.neighbours.end(own); ++k) add(aggregates.neighbours.items[k]);
    return static_cast<float>(total > 0.0 ? sum / total : coarse[own]);
}

// The low-pass of the returned displacement on the aggregates instead of the mesh: the field is smooth at the
// return's reach (9 r), many cells wide, so the aggregates carry it whole, and the ~(9 r / e)^2 equivalent iterations
// run on a graph (cell / e)^2 times smaller. Restricted, filtered (coarse_low_pass), prolonged, then blended by a fine
// low-pass of half a cell, whose last pass moves the vertices back along their normals. Measured against the mesh's
// own low-pass (c = 0.25 and 0.5): hfL, volume and droplets the same to the third digit, with a third of the
// applications.
int aggregate_return(std::vector<float>& offset, TriMesh& mesh, const std::vector<float>& normals, const UmbrellaRows& rows,
                     const std::vector<float>& steps, ReturnAggregates& coarse_surface, double cell, double reach, double tolerance,
                     double edge, int threads, HeatSmoothingReport& report, HeatFilterWorkspace& workspace) {
    std::vector<double> coarse = restrict_to_aggregates(coarse_surface.aggregates, coarse_surface.valence, offset.data(), 1, threads);
    coarse_low_pass(coarse, coarse_surface, reach, tolerance, threads, report, workspace);
    const HeatPolynomial& blend = workspace.polynomial(std::min(std::pow(0.5 * cell / edge, 2.0), kMaxIterations), tolerance, true);
    struct Prolonged {
        const std::vector<double>* coarse;
        const TriMesh* mesh;
        const ReturnAggregates* surface;
        double cell;
        float operator()(int64_t i, int, int) const { return prolonged_value(*coarse, *mesh, *surface, cell, i); }
    };
    struct MoveBack {
        float* vertices;
        const float* normals;
        void operator()(int64_t i, int, int, float back) const {
            if (back == 0.0f) return;
            for (int k = 0; k < 3; ++k) vertices[3 * i + k] -= back * normals[3 * i + k];
        }
    };
    // offset only sizes the filter from here on: Prolonged and MoveBack are its values.
    return apply_heat_polynomial<1, false>(offset, rows, steps, nullptr, blend, threads, workspace, Prolonged{&coarse, &mesh, &coarse_surface, cell},
                                     MoveBack{mesh.vertices.data(), normals.data()});
}

}  // namespace

double smoothing_reach_at(double reach, double cube_size) {
    if (!(reach > 0.0)) return 0.0;
    return reach * std::max(1.0, cube_size / kReferenceCube);
}

double rms_edge_length(const TriMesh& mesh, const MeshAdjacency& adjacency, int threads) {
    const CsrList& nb = adjacency.vertex_neighbours;
    const int64_t nv = static_cast<int64_t>(nb.rows());
    const int64_t blocks = (nv + kBlock - 1) / kBlock;
    std::vector<double> sum(static_cast<std::size_t>(std::max<int64_t>(blocks, 0)), 0.0), count(sum.size(), 0.0);
    parallel_for(blocks, threads, [&](int64_t b) {
        double s = 0.0, c = 0.0;
        for (int64_t i = b * kBlock; i < std::min(nv, (b + 1) * kBlock); ++i) {
            const float* xi = &mesh.vertices[3 * i];
            for (int64_t k = nb.begin(i); k < nb.end(i); ++k) {
                const int32_t j = nb.items[k];
                if (j <= i) continue;  // each edge once
                const float* xj = &mesh.vertices[3 * static_cast<int64_t>(j)];
                const double dx = double(xj[0]) - xi[0], dy = double(xj[1]) - xi[1], dz = double(xj[2]) - xi[2];
                s += dx * dx + dy * dy + dz * dz;
                c += 1.0;
            }
        }
        sum[b] = s, count[b] = c;
    });
    double s = 0.0, c = 0.0;
    for (int64_t b = 0; b < blocks; ++b) s += sum[b], c += count[b];
    return c > 0.0 ? std::sqrt(s / c) : 0.0;
}

std::vector<double> heat_coefficients(double n, double tolerance) {
    if (std::isnan(n) || n > kMaxIterations) {  // the coefficients cost O(N) time and memory
        char text[128];
        std::snprintf(text, sizeof text, "heat filter: %g equivalent iterations, more than the %g it runs", n, kMaxIterations);
        throw InputError(text);
    }
    if (!(n > 0.0)) return {1.0};
    // The coefficients of exp(N (y - 1)) (2 e^-N I_k(N), positive) decay like exp(-k^2 / (2 N)).
    const int max_degree = static_cast<int>(std::ceil(std::sqrt(2.0 * n * 12.0))) + 8;
    const int nodes = 2 * max_degree + 16;
    std::vector<double> f(static_cast<std::size_t>(nodes));
    for (int j = 0; j < nodes; ++j) f[j] = std::exp(n * (std::cos(kPi * (j + 0.5) / nodes) - 1.0));
    std::vector<double> c(static_cast<std::size_t>(max_degree) + 1, 0.0);
    for (int k = 0; k <= max_degree; ++k) {
        double s = 0.0;
        for (int j = 0; j < nodes; ++j) s += f[j] * std::cos(kPi * k * (j + 0.5) / nodes);
        c[k] = (k == 0 ? 1.0 : 2.0) * s / nodes;
    }
    int degree = max_degree;
    double tail = 0.0;
    while (degree > 1 && tail + std::fabs(c[degree]) < tolerance) tail += std::fabs(c[degree--]);
    c.resize(static_cast<std::size_t>(degree) + 1);
    double rest = 0.0;
    for (int k = 1; k <= degree; ++k) rest += c[k];
    c[0] = 1.0 - rest;  // f(1) = sum c_k T_k(1) = 1: constants exact
    return c;
}

int heat_filter(std::vector<float>& x, int dims, const MeshAdjacency& adjacency, const std::vector<float>& weights, double n,
                double tolerance, int threads, const std::vector<uint8_t>* frozen, bool allow_explicit) {
    const CsrList& nb = adjacency.vertex_neighbours;
    const std::size_t nv = nb.rows();
    if (dims != 1 && dims != 3) throw InputError("heat_filter: 1 or 3 values per vertex");
    if (x.size() != static_cast<std::size_t>(dims) * nv) throw InputError("heat_filter: the adjacency does not belong to these values");
    if (!weights.empty() && weights.size() != nv) throw InputError("heat_filter: one weight per vertex expected");
    if (frozen && !frozen->empty() && frozen->size() != nv) throw InputError("heat_filter: one wall mask per vertex expected");
    if (heat_coefficients(n, tolerance).size() < 2 || nv == 0) return 0;
    HeatFilterWorkspace workspace;
    return heat_filter_on_rows(x, dims, umbrella_rows(nb, threads), umbrella_steps(nb, weights, threads), n, tolerance, allow_explicit,
                               threads, frozen && !frozen->empty() ? frozen->data() : nullptr, workspace);
}

HeatSmoothingReport heat_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights_in,
                                const HeatSmoothingSettings& settings, const UnsmoothedSurface& unsmoothed, int threads) {
    validate_mesh_arrays(mesh, "heat_smooth", threads);
    HeatSmoothingReport report;
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    if (adjacency.vertex_neighbours.rows() != mesh.num_vertices()) throw InputError("heat_smooth: the adjacency does not belong to this mesh");
    require_row_per_vertex(adjacency.vertex_triangles, mesh.num_vertices(), "heat_smooth");  // the returns' normals read them
    if (!weights_in.empty() && weights_in.size() != mesh.num_vertices())
        throw InputError("heat_smooth: got " + std::to_string(weights_in.size()) + " weights for " + std::to_string(nv) + " vertices");
    if (!(settings.reach > 0.0) || nv == 0) return report;
    const double radius = settings.particle_radius > 0.0 ? settings.particle_radius : settings.reach / 4.0;
    if (parallel_count(static_cast<int64_t>(mesh.vertices.size()), threads, [&](int64_t i) { return !std::isfinite(mesh.vertices[i]); }))
        throw InputError("heat_smooth: the mesh has a non-finite vertex coordinate");
    // Weights are documented as [0, 1]: clamp rounding (1.0000001) so no step overshoots; NaN would spread everywhere.
    const int64_t weight_count = static_cast<int64_t>(weights_in.size());
    if (parallel_count(weight_count, threads, [&](int64_t i) { return std::isnan(weights_in[i]); })) {
        const auto nan = std::find_if(weights_in.begin(), weights_in.end(), [](float w) { return std::isnan(w); });
        throw InputError("heat_smooth: weight of vertex " + std::to_string(nan - weights_in.begin()) + " is NaN");
    }
    std::vector<float> weights(weights_in.size());
    parallel_blocks(weight_count, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) weights[i] = std::fmin(1.0f, std::fmax(0.0f, weights_in[i]));
    });
    const WallConstraints* walls = settings.walls && !settings.walls->empty() ? settings.walls : nullptr;
    std::vector<uint8_t> frozen;
    // Capped, the flow smooths the contact line along itself, as the iterations do (post/container.h): the cap below
    // it would otherwise pull it down the wall.
    MeshAdjacency along_walls;
    if (walls) {
        require_valid_walls(*walls, mesh.num_vertices());
        along_walls.vertex_neighbours = smoothing_neighbours_at_walls(*walls, adjacency.vertex_neighbours);
        frozen.resize(walls->mask.size());
        for (std::size_t v = 0; v < frozen.size(); ++v) {
            uint8_t bits = 0;
            for (int f = 0; f < 6; ++f)
                if (walls->mask[v] >> f & 1u) bits |= static_cast<uint8_t>(1u << (f / 2));
            frozen[v] = bits;
        }
        apply_walls(walls, mesh);
    }

    report.edge = rms_edge_length(mesh, adjacency, threads);
    if (!(report.edge > 0.0)) return report;
    report.iterations = std::min((settings.reach / report.edge) * (settings.reach / report.edge), kMaxIterations);
    const double time = 0.25 * settings.reach * settings.reach;
    const double part_time = settings.part_time > 0.0 ? settings.part_time : kPartTime;
    // Up to 5 % over part_time in one part: a heat time just above a multiple of it does not add a part.
    const double automatic_parts = std::ceil(time / (part_time * radius * radius) - 0.05);
    // Each part runs a filter and a return over the whole mesh: a reach far beyond the particles (the pipeline's grows
    // with the cube size above kReferenceCube) or a tiny part time would run for hours (and overflow the count).
    if (settings.parts > kMaxParts || (settings.parts <= 0 && !(automatic_parts <= kMaxParts))) {
        char text[256];
        if (settings.parts > 0)
            std::snprintf(text, sizeof text, "heat_smooth: %d parts asked for, more than %d", settings.parts, kMaxParts);
        else if (settings.part_time > 0.0)
            std::snprintf(text, sizeof text, "heat_smooth: part_time %g r^2 splits the heat time %g r^2 into more than %d parts",
                          settings.part_time, time / (radius * radius), kMaxParts);
        else
            std::snprintf(text, sizeof text,
                          "heat_smooth: a reach of %g r (heat time %g r^2) splits the flow into more than %d parts of %g r^2; use a "
                          "shorter smoothing reach (it grows with the cube size above %g r)",
                          settings.reach / radius, time / (radius * radius), kMaxParts, part_time, kReferenceCube);
        throw InputError(text);
    }
    report.parts = settings.parts > 0 ? settings.parts : std::max(1, static_cast<int>(automatic_parts));

    auto mark = std::chrono::steady_clock::now();
    if (settings.volume_correction && unsmoothed.labels.size() != mesh.num_vertices())
        throw InputError("heat_smooth: the unsmoothed surface does not belong to this mesh");

    const double local_scale = (settings.local_scale > 0.0 ? settings.local_scale : kLocalScale) * radius;
    const double return_iterations = std::min(std::pow(local_scale / report.edge, 2.0), kMaxIterations);
    const double tolerance = settings.return_tolerance > 0.0 ? settings.return_tolerance : kReturnTolerance;
    std::vector<float> offset, normals, areas;
    UninitializedVector<float> before;  // each part's start, written by its filter
    if (settings.local_return) offset.resize(static_cast<std::size_t>(nv)), before.resize(mesh.vertices.size());
    // Aggregates for the return's low-pass (built once, from the first part's surface: the parts move vertices by a
    // fraction of a cell).
    const double aggregate_size = settings.aggregate_size >= 0.0 ? settings.aggregate_size : kAggregateCell;
    const double cell = std::max(aggregate_size * radius, 2.0 * report.edge);
    bool coarse_return = aggregate_size > 0.0;
    ReturnAggregates aggregates;
    // Shared by every filter below: the rows, the steps (the flow's weighted, the return's plain) and the buffers.
    const CsrList& flow_neighbours = walls ? along_walls.vertex_neighbours : adjacency.vertex_neighbours;
    UmbrellaRows flow_rows = umbrella_rows(flow_neighbours, threads), return_rows_at_walls;
    if (walls && settings.local_return) return_rows_at_walls = umbrella_rows(adjacency.vertex_neighbours, threads);
    const UmbrellaRows& return_rows = walls ? return_rows_at_walls : flow_rows;
    std::vector<float> flow_steps = umbrella_steps(flow_neighbours, weights, threads), return_steps;
    if (settings.local_return) return_steps = umbrella_steps(adjacency.vertex_neighbours, {}, threads);
    HeatFilterWorkspace workspace;
    // Sized once for the largest use: the flow's three terms or the normals' cross products.
    workspace.scratch(std::max(3 * (mesh.vertices.size() + 1), 3 * mesh.num_triangles()));
    bounding_box_centre(mesh.vertices, threads, workspace.centre);  // the parts move the surface by a fraction of it
    workspace.has_centre = true;
    for (int part = 0; part < report.parts; ++part) {
        report.applications += heat_filter_on_rows(mesh.vertices, 3, flow_rows, flow_steps, report.iterations / report.parts, kPositionTolerance,
                                                   true, threads, walls ? frozen.data() : nullptr, workspace,
                                                settings.local_return ? before.data() : nullptr);
        apply_walls(walls, mesh);
        report.seconds_flow += seconds_since(mark);
        if (!settings.local_return) continue;
        // The part's normal displacement, low-passed over the surface, goes back along the normals.
        // Of a smoothed surface: smooth enough as they are. The areas only for the aggregates' centres (built once).
        const bool build_aggregates = coarse_return && part == 0;
        vertex_normals(mesh, adjacency, normals, build_aggregates ? &areas : nullptr, workspace, threads, before.data(), &offset);
        if (build_aggregates) {
            aggregates = return_aggregates(mesh, adjacency, areas, cell, threads);
            areas = std::vector<float>();
            report.aggregates = aggregates.aggregates.size();
            coarse_return = report.aggregates > 0;  // none: the scene spans too many cells for the keys
        }
        if (coarse_return) {
            report.applications += aggregate_return(offset, mesh, normals, return_rows, return_steps, aggregates, cell, local_scale, tolerance,
                                                    report.edge, threads, report, workspace);
        } else {
            report.applications += heat_filter_on_rows(offset, 1, return_rows, return_steps, return_iterations, tolerance, true, threads, nullptr,
                                                       workspace);
            parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
                for (int64_t i = begin; i < end; ++i) {
                    const float back = offset[i];
                    if (back == 0.0f) continue;
                    for (int k = 0; k < 3; ++k) mesh.vertices[3 * i + k] -= back * normals[3 * i + k];
                }
            });
        }
        apply_walls(walls, mesh);
        report.seconds_return += seconds_since(mark);
    }

    // Their ~200 MB per million vertices are not needed by the correction.
    workspace = HeatFilterWorkspace{};
    flow_rows = UmbrellaRows{}, return_rows_at_walls = UmbrellaRows{};
    flow_steps = std::vector<float>(), return_steps = std::vector<float>();
    before = UninitializedVector<float>();
    if (settings.volume_correction) {
        // Along smoothed normals (offsets along raw vertex normals would print the triangulation's noise back in);
        // the offsets are tiny, so these normals are the output's normals too.
        report.normals = restore_component_volumes(mesh, adjacency, unsmoothed, weights,
                                                   settings.max_offset > 0.0 ? settings.max_offset : 4.0 * radius,
                                                   settings.normal_iterations, threads, walls, 4);
    }
    report.seconds_correction += seconds_since(mark);
    return report;
}

HeatSmoothingReport heat_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights,
                                const HeatSmoothingSettings& settings, int threads) {
    // On its walls before it is recorded: a component the guard reverts goes back onto them.
    if (settings.walls && !settings.walls->empty()) {
        require_valid_walls(*settings.walls, mesh.num_vertices());
        apply_walls(settings.walls, mesh);
    }
    const UnsmoothedSurface unsmoothed = record_unsmoothed_surface(mesh, threads);
    HeatSmoothingReport report = heat_smooth(mesh, adjacency, weights, settings, unsmoothed, threads);
    report.reverted_components = revert_collapsed_components(mesh, unsmoothed, threads);
    if (report.reverted_components) report.normals = SmoothedNormals{};
    return report;
}

}  // namespace meniscus
