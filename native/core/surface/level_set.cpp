#include "surface/level_set.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>

#if defined(__SSE2__) || defined(_M_X64)
#include <immintrin.h>
#endif

#include "base/compaction.h"
#include "base/parallel.h"

namespace meniscus {

namespace {

// Adds factor * W-shape(q) to row[0 .. n) with q = sqrt(dyz + dx2[i]) / H, in the branch-free spelling of the
// spline (sph/kernel.h). Written with SSE intrinsics where available because the compiler turns the max into four
// instructions (a blend, for NaN semantics the values here cannot have); the scalar tail does the same operations
// in the same order, so every point gets the same bits either way.
#if defined(__SSE2__) || defined(_M_X64)
inline __m128 splat_shape4(__m128 d2, __m128 inverse4, __m128 factor4) {
    const __m128 one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f), zero = _mm_setzero_ps();
    const __m128 q = _mm_mul_ps(_mm_sqrt_ps(d2), inverse4);
    const __m128 a = _mm_max_ps(_mm_sub_ps(one, q), zero);
    const __m128 b = _mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(two, q)), zero);
    const __m128 shape = _mm_sub_ps(_mm_mul_ps(_mm_mul_ps(_mm_mul_ps(two, a), a), a), _mm_mul_ps(_mm_mul_ps(b, b), b));
    return _mm_mul_ps(factor4, shape);
}
#endif

inline void splat_row(float* row, const float* dx2, int n, float dyz, float inverse_support, float factor) {
    int i = 0;
#if defined(__SSE2__) || defined(_M_X64)
    const __m128 dyz4 = _mm_set1_ps(dyz), inverse4 = _mm_set1_ps(inverse_support), factor4 = _mm_set1_ps(factor);
    for (; i + 4 <= n; i += 4)
        _mm_storeu_ps(row + i, _mm_add_ps(_mm_loadu_ps(row + i), splat_shape4(_mm_add_ps(dyz4, _mm_loadu_ps(dx2 + i)), inverse4, factor4)));
#endif
    for (; i < n; ++i) row[i] += factor * CubicSplineKernel::shape_branch_free(std::sqrt(dyz + dx2[i]) * inverse_support);
}

// A row sixteen points at a time with AVX-512, chosen at run time (the build targets baseline x86-64): rows are
// about 16 points long, so a row is one vector operation (its end masked) instead of four with SSE, and this loop is
// most of the reconstruction's time (1 M particles, c = 0.5: the stage takes 1.41 s instead of 2.47 s). An AVX
// (8-wide) path was measured too and was no faster than SSE here (2.66 s), so there is none. No fused multiply-add
// (-ffp-contract=off): each lane does the operations of splat_row in the same order with the same rounding, so
// the bits do not depend on the path (tests/python/test_mesh_pins.py runs both).
#if (defined(__GNUC__) || defined(__clang__)) && !defined(_MSC_VER) && !defined(_WIN32) && \
    (defined(__x86_64__) || defined(__i386__)) && defined(__SSE2__)
#define MENISCUS_SPLAT_AVX512 1
// The zero-masking forms stand in for the plain sqrt and max, which GCC 12's
// headers spell with an "undefined" operand that -Wmaybe-uninitialized flags; on the active lanes they compute the
// same thing, and the inactive ones are never stored.
inline __attribute__((target("avx512f"))) void splat_row_avx512(float* row, const float* dx2, int n, float dyz, float inverse_support,
                                                                float factor) {
    const __m512 dyz16 = _mm512_set1_ps(dyz), inverse16 = _mm512_set1_ps(inverse_support), factor16 = _mm512_set1_ps(factor);
    const __m512 one = _mm512_set1_ps(1.0f), two = _mm512_set1_ps(2.0f), zero = _mm512_setzero_ps();
    for (int i = 0; i < n; i += 16) {
        const __mmask16 lanes = n - i >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << (n - i)) - 1u);
        const __m512 d2 = _mm512_add_ps(dyz16, _mm512_maskz_loadu_ps(lanes, dx2 + i));
        const __m512 q = _mm512_mul_ps(_mm512_maskz_sqrt_ps(lanes, d2), inverse16);
        const __m512 a = _mm512_maskz_max_ps(lanes, _mm512_sub_ps(one, q), zero);
        const __m512 b = _mm512_maskz_max_ps(lanes, _mm512_sub_ps(one, _mm512_mul_ps(two, q)), zero);
        const __m512 shape =
            _mm512_sub_ps(_mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(two, a), a), a), _mm512_mul_ps(_mm512_mul_ps(b, b), b));
        _mm512_mask_storeu_ps(row + i, lanes, _mm512_add_ps(_mm512_maskz_loadu_ps(lanes, row + i), _mm512_mul_ps(factor16, shape)));
    }
}

// One particle's rows of the brick, the loop of ColourFieldSampler spelled out inside the AVX-512 target: a function
// of another target is not inlined into the sampler, and a call per row costs about as much as the row.
__attribute__((target("avx512f"))) void splat_particle_avx512(float* values, const float* dx2, const float* dy2, const float* dz2, int nx,
                                                              int ny, int nz, int ox, int oy, int oz, float support_squared,
                                                              float inverse_support, float factor) {
    for (int iz = 0; iz < nz; ++iz)
        for (int iy = 0; iy < ny; ++iy) {
            const float dyz = dz2[iz] + dy2[iy];
            if (dyz >= support_squared) continue;
            splat_row_avx512(values + point_index(ox, oy + iy, oz + iz), dx2, nx, dyz, inverse_support, factor);
        }
}

// MENISCUS_SIMD=sse keeps the SSE path (the test that both paths give the same bits; also a way out should a CPU
// misreport its features).
bool use_avx512() {
    static const bool avx512 = [] {
        const char* cap = std::getenv("MENISCUS_SIMD");
        if (cap != nullptr && std::string(cap) == "sse") return false;
        return __builtin_cpu_supports("avx512f") != 0;  // also checks that the OS saves the AVX-512 registers
    }();
    return avx512;
}
#endif

// Colour field (Eq. 1) at a brick's (kBrick + 1)^3 points: every particle near the brick splats its kernel onto
// the points within its support, row by row.
class ColourFieldSampler {
public:
    ColourFieldSampler(const SphField& field, double cube_edge, double threshold)
        : field_(field), cube_(cube_edge), threshold_(static_cast<float>(threshold)) {}

    bool operator()(const LatticeCoords& base, BrickScratch& s) const {
        const ParticleGrid& grid = field_.grid;
        const CubicSplineKernel& kernel = field_.kernel;
        std::fill(s.values.begin(), s.values.end(), 0.0f);
        const double support = kernel.support();
        const float support_squared = kernel.support_squared();
        const double cell = grid.cell_size();
        LatticeCoords lo, hi;
        for (int k = 0; k < 3; ++k) {
            // One extra cell on each side: rounding of a particle's cell must not drop it from the gather.
            lo[k] = static_cast<int64_t>(std::floor((double(base[k]) * cube_ - support) / cell)) - 1;
            hi[k] = static_cast<int64_t>(std::floor((double(base[k] + kBrick) * cube_ + support) / cell)) + 1;
        }
        const float inverse_support = 1.0f / kernel.support();
#ifdef MENISCUS_SPLAT_AVX512
        const bool avx512 = use_avx512();
#endif
        grid.for_each_cell_in_box(lo, hi, [&](std::size_t c) {
            for (std::size_t j = grid.cell_begin(c); j < grid.cell_end(c); ++j) {
                const float* x = grid.position(j);
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
                const float factor = field_.volumes[j] * kernel.value(0.0f);  // V_j * 8/(pi H^3)
                const int nx = static_cast<int>(s.dx2.size()), ny = static_cast<int>(s.dy2.size()), nz = static_cast<int>(s.dz2.size());
                const int ox = static_cast<int>(first[0] - base[0]), oy = static_cast<int>(first[1] - base[1]), oz = static_cast<int>(first[2] - base[2]);
#ifdef MENISCUS_SPLAT_AVX512
                if (avx512) {
                    splat_particle_avx512(s.values.data(), s.dx2.data(), s.dy2.data(), s.dz2.data(), nx, ny, nz, ox, oy, oz,
                                          support_squared, inverse_support, factor);
                    continue;
                }
#endif
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

    SphField field_;
    double cube_;
    float threshold_;
};

}  // namespace

namespace {

// Bricks a cell's particles reach (with their kernel support and one cube, for the cubes' edges), [lo, hi] per axis.
// Non-decreasing in the cell's coordinates.
void bricks_of_cell(const std::array<int64_t, 3>& c, double cell, double margin, double cube_edge, LatticeCoords& lo, LatticeCoords& hi) {
    for (int k = 0; k < 3; ++k) {
        lo[k] = floor_div(static_cast<int64_t>(std::floor((double(c[k]) * cell - margin) / cube_edge)), kBrick);
        hi[k] = floor_div(static_cast<int64_t>(std::ceil((double(c[k] + 1) * cell + margin) / cube_edge)), kBrick);
    }
}

// Bricks per occupied cell, beyond which a flag per brick of the bricks' bounding box costs more than sorting the
// bricks each cell lists (sparse frames: spray far from the bulk).
constexpr int64_t kDenseBricksPerCell = 32;
constexpr int64_t kDenseBricksAlways = int64_t{1} << 20;

// The bricks of the listed cells as the flags of their bounding box: every cell marks its bricks (the same flag
// from several threads: relaxed atomic stores), then the marked ones in the box's (z, y, x) order, which is
// coords_less order, each once.
std::vector<LatticeCoords> marked_bricks(const ParticleGrid& grid, double margin, double cube_edge, const LatticeCoords& box_lo,
                                         const LatticeCoords& box_hi, int threads) {
    const int64_t nx = box_hi[0] - box_lo[0] + 1, ny = box_hi[1] - box_lo[1] + 1, nz = box_hi[2] - box_lo[2] + 1;
    const int64_t box = nx * ny * nz;
    std::unique_ptr<std::atomic<uint8_t>[]> marked(new std::atomic<uint8_t>[static_cast<std::size_t>(box)]);
    parallel_blocks(box, threads, int64_t{1} << 16, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) marked[i].store(0, std::memory_order_relaxed);
    });
    parallel_blocks(static_cast<int64_t>(grid.num_cells()), threads, 1024, [&](int64_t begin, int64_t end) {
        LatticeCoords lo, hi;
        for (int64_t cell_index = begin; cell_index < end; ++cell_index) {
            bricks_of_cell(grid.cell_coords(static_cast<std::size_t>(cell_index)), grid.cell_size(), margin, cube_edge, lo, hi);
            for (int64_t z = lo[2]; z <= hi[2]; ++z)
                for (int64_t y = lo[1]; y <= hi[1]; ++y)
                    for (int64_t x = lo[0]; x <= hi[0]; ++x)
                        marked[((z - box_lo[2]) * ny + (y - box_lo[1])) * nx + (x - box_lo[0])].store(1, std::memory_order_relaxed);
        }
    });
    const std::vector<int64_t> flat = kept_indices<int64_t>(box, threads, [&](int64_t i) { return marked[i].load(std::memory_order_relaxed) != 0; });
    std::vector<LatticeCoords> bricks(flat.size());
    parallel_blocks(static_cast<int64_t>(flat.size()), threads, 4096, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i)
            bricks[i] = {box_lo[0] + flat[i] % nx, box_lo[1] + flat[i] / nx % ny, box_lo[2] + flat[i] / (nx * ny)};
    });
    return bricks;
}

// The same bricks by listing them per cell and sorting, for boxes too sparse to flag.
std::vector<LatticeCoords> listed_bricks(const ParticleGrid& grid, double margin, double cube_edge, int threads) {
    std::vector<std::vector<LatticeCoords>> per_thread(static_cast<std::size_t>(threads));
    ParallelErrors errors;
    parallel_region(threads, [&] {
        int thread = 0;
#ifdef _OPENMP
        thread = omp_get_thread_num();
#endif
        std::vector<LatticeCoords>& mine = per_thread[static_cast<std::size_t>(thread)];
#pragma omp for schedule(static)
        for (int64_t cell_index = 0; cell_index < static_cast<int64_t>(grid.num_cells()); ++cell_index)
            errors.run([&] {
                LatticeCoords lo, hi;
                bricks_of_cell(grid.cell_coords(static_cast<std::size_t>(cell_index)), grid.cell_size(), margin, cube_edge, lo, hi);
                for (int64_t z = lo[2]; z <= hi[2]; ++z)
                    for (int64_t y = lo[1]; y <= hi[1]; ++y)
                        for (int64_t x = lo[0]; x <= hi[0]; ++x) mine.push_back({x, y, z});
            });
        // Neighbouring cells list the same bricks many times over: each thread drops its own repeats first, so the
        // serial sort below sees each brick about once per thread instead of once per cell near it.
        errors.run([&] {
            std::sort(mine.begin(), mine.end(), coords_less);
            mine.erase(std::unique(mine.begin(), mine.end()), mine.end());
        });
    });
    errors.rethrow();
    std::vector<LatticeCoords> bricks;
    for (auto& list : per_thread) bricks.insert(bricks.end(), list.begin(), list.end());
    std::sort(bricks.begin(), bricks.end(), coords_less);
    bricks.erase(std::unique(bricks.begin(), bricks.end()), bricks.end());
    return bricks;
}

}  // namespace

std::vector<LatticeCoords> bricks_near_particles(const ParticleGrid& grid, double compact_support, double cube_edge, int threads) {
    if (grid.num_cells() == 0) return {};
    const double margin = compact_support + cube_edge;
    // The bricks' bounding box, from the corner cells of the occupied box (bricks_of_cell is monotonic).
    const std::array<int64_t, 3>& origin = grid.cell_origin();
    const std::array<int64_t, 3>& extent = grid.cell_extent();
    const std::array<int64_t, 3> last{origin[0] + extent[0] - 1, origin[1] + extent[1] - 1, origin[2] + extent[2] - 1};
    LatticeCoords box_lo, box_hi, unused;
    bricks_of_cell(origin, grid.cell_size(), margin, cube_edge, box_lo, unused);
    bricks_of_cell(last, grid.cell_size(), margin, cube_edge, unused, box_hi);
    double box = 1.0;
    for (int k = 0; k < 3; ++k) box *= double(box_hi[k] - box_lo[k] + 1);
    const double dense_limit = std::max(double(kDenseBricksAlways), double(kDenseBricksPerCell) * double(grid.num_cells()));
    return box <= dense_limit ? marked_bricks(grid, margin, cube_edge, box_lo, box_hi, threads) : listed_bricks(grid, margin, cube_edge, threads);
}

BrickSampler colour_field_sampler(const SphField& field, double cube_edge, double threshold) {
    return ColourFieldSampler(field, cube_edge, threshold);
}

}  // namespace meniscus
