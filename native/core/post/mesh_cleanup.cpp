#include "post/mesh_cleanup.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "base/errors.h"
#include "base/parallel.h"
#include "post/collapse.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

// Merge rounds at most. A round visits the active vertices tile by tile (two tilings) and then all of them
// sequentially, so it makes every merge that is legal at that moment; a later round only retries the few collapses
// refused before that neighbouring merges made legal. Fewer rounds than decimation's detection passes suffice:
// nothing is deferred on purpose here.
constexpr int kMaxMergeRounds = 5;

// Tiles of 2^kTileShift = 16 lattice points per axis: fans span 1-2 points, so few collapses straddle a border.
constexpr int kTileShift = 4;

// Nearest lattice point (in units of the cube edge).
struct LatticeKey {
    int32_t k[3] = {0, 0, 0};
    bool operator==(const LatticeKey& o) const { return k[0] == o.k[0] && k[1] == o.k[1] && k[2] == o.k[2]; }
};

// Every vertex's nearest lattice point and whether the vertex takes part. A merged vertex sits at the mean of
// vertices sharing its lattice point, which lies in the same lattice cell (and within the same snap ball), so keys
// and eligibility never need updating.
struct LatticePoints {
    std::vector<LatticeKey> key;
    std::vector<uint8_t> eligible;

    bool merge_partners(int32_t u, int32_t v) const { return eligible[u] && eligible[v] && key[u] == key[v]; }
};

LatticePoints nearest_lattice_points(const std::vector<float>& positions, double cube_edge, double snap_distance, int threads,
                                     const std::vector<uint8_t>* pinned) {
    const int64_t nv = static_cast<int64_t>(positions.size() / 3);
    LatticePoints lattice;
    lattice.key.resize(static_cast<std::size_t>(nv));
    lattice.eligible.assign(static_cast<std::size_t>(nv), 0);
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            double d2 = 0.0;
            bool usable = true;
            for (int k = 0; k < 3; ++k) {
                const double x = positions[3 * v + k] / cube_edge;
                usable = usable && std::isfinite(x) && std::fabs(x) < 1e9;  // lattice index must fit in 32 bits
                const double r = usable ? std::nearbyint(x) : 0.0;
                lattice.key[v].k[k] = static_cast<int32_t>(r);
                d2 += (x - r) * (x - r);
            }
            lattice.eligible[v] = usable && (snap_distance < 0.0 || std::sqrt(d2) <= snap_distance) && !(pinned && (*pinned)[v]);
        }
    });
    return lattice;
}

// The vertices with a merge partner among their neighbours, ascending. Only they can ever merge: merging never
// creates a same-key pair that was not already adjacent to one of the merged vertices.
std::vector<int32_t> active_vertices(const MeshAdjacency& adj, const LatticePoints& lattice, int threads) {
    const int64_t nv = static_cast<int64_t>(adj.vertex_neighbours.rows());
    std::vector<uint8_t> flag(static_cast<std::size_t>(nv), 0);
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            if (!lattice.eligible[v]) continue;
            for (int64_t k = adj.vertex_neighbours.begin(v); k < adj.vertex_neighbours.end(v); ++k)
                if (lattice.merge_partners(adj.vertex_neighbours.items[k], static_cast<int32_t>(v))) {
                    flag[v] = 1;
                    break;
                }
        }
    });
    std::vector<int32_t> active;
    for (int64_t v = 0; v < nv; ++v)
        if (flag[v]) active.push_back(static_cast<int32_t>(v));
    return active;
}

// The lattice tiled into blocks of tiles, shifted by `offset` lattice points; the active vertices grouped by tile.
struct Tiling {
    int32_t offset;
    std::vector<int32_t> order;                     // active vertices grouped by tile, index order within
    std::vector<std::pair<int64_t, int64_t>> runs;  // [begin, end) in order per tile
};

// Arithmetic shift floors negative coordinates too; packing may alias far-apart tiles, which only merges their
// work into one task (still isolated from all other tasks).
uint64_t tile_of(const LatticeKey& key, int32_t offset) {
    uint64_t code = 0;
    for (int k = 0; k < 3; ++k) code = (code << 21) | (static_cast<uint64_t>((static_cast<int64_t>(key.k[k]) + offset) >> kTileShift) & 0x1FFFFFu);
    return code;
}

Tiling make_tiling(const std::vector<int32_t>& active, const LatticePoints& lattice, int32_t offset, int threads) {
    Tiling tiling{offset, {}, {}};
    std::vector<std::pair<uint64_t, int32_t>> items(active.size());
    parallel_blocks(static_cast<int64_t>(active.size()), threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) items[i] = {tile_of(lattice.key[active[i]], offset), active[i]};
    });
    std::sort(items.begin(), items.end());
    tiling.order.resize(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
        tiling.order[i] = items[i].second;
        if (i == 0 || items[i].first != items[i - 1].first) tiling.runs.emplace_back(static_cast<int64_t>(i), 0);
        tiling.runs.back().second = static_cast<int64_t>(i + 1);
    }
    return tiling;
}

// Incremental merging around vertices: collapse a same-key neighbour u into v with v moving to the mean of
// everything merged into either so far, then rescan v's (changed) ring. `pending` marks the vertices that still
// have a same-key neighbour they could not merge (refused, or outside the current tile); only those are visited
// again.
class LatticeMerger {
public:
    LatticeMerger(CollapseMesh& work, const LatticePoints& lattice, const std::vector<float>& positions,
                  const std::vector<int32_t>& active, const std::vector<uint8_t>& removed)
        : work_(work), lattice_(lattice), removed_(removed), sum_(positions.begin(), positions.end()),
          count_(positions.size() / 3, 1), pending_(positions.size() / 3, 0) {
        for (int32_t v : active) pending_[v] = 1;
    }

    struct Buffers {
        CollapseScratch s;
        std::vector<int32_t> fan, ring;
    };

    // Merges around list[0 .. n) in order, every collapse confined to `region` (see CollapseMesh::try_collapse).
    // Returns the number of collapses.
    template <class Region>
    std::size_t merge_around(const int32_t* list, std::size_t n, Buffers& b, const Region& region) {
        std::size_t merged_here = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const int32_t v = list[i];
            if (removed_[v] || !pending_[v]) continue;
            bool merged = true, refused = false;
            while (merged) {
                merged = refused = false;
                work_.fan(v, b.fan);
                work_.neighbours(v, b.fan, b.ring);
                for (int32_t u : b.ring) {
                    // Same key implies same tile, so u's state belongs to this task too.
                    if (!lattice_.eligible[u] || !(lattice_.key[u] == lattice_.key[v])) continue;
                    if (!merge(u, v, b.s, region)) {
                        refused = true;
                        continue;
                    }
                    ++merged_here;
                    merged = true;
                    break;
                }
            }
            pending_[v] = refused ? 1 : 0;
        }
        return merged_here;
    }

private:
    template <class Region>
    bool merge(int32_t u, int32_t v, CollapseScratch& s, const Region& region) {
        const double total = double(count_[v]) + double(count_[u]);
        const float target[3] = {static_cast<float>((sum_[3 * v] + sum_[3 * u]) / total),
                                 static_cast<float>((sum_[3 * v + 1] + sum_[3 * u + 1]) / total),
                                 static_cast<float>((sum_[3 * v + 2] + sum_[3 * u + 2]) / total)};
        if (!work_.try_collapse(u, v, target, s, region)) return false;
        for (int k = 0; k < 3; ++k) sum_[3 * v + k] += sum_[3 * u + k];
        count_[v] += count_[u];
        return true;
    }

    CollapseMesh& work_;
    const LatticePoints& lattice_;
    const std::vector<uint8_t>& removed_;
    std::vector<double> sum_;      // sum of the original positions merged into each vertex
    std::vector<int32_t> count_;   // and their number, for the running average
    std::vector<uint8_t> pending_;
};

// One round: every tile's active vertices as one parallel task, collapses confined to the tile, so tiles are
// independent and the result does not depend on the thread count; collapses that straddle a tile border are
// retried with the tiling shifted by half a tile, and whatever still straddles is done sequentially.
std::size_t merge_round(LatticeMerger& merger, const std::vector<Tiling>& tilings, const LatticePoints& lattice,
                        const std::vector<int32_t>& active, int threads) {
    std::size_t merged = 0;
    for (const Tiling& tiling : tilings) {
        std::vector<std::size_t> per_run(tiling.runs.size(), 0);
        parallel_blocks(static_cast<int64_t>(tiling.runs.size()), threads, 1, [&](int64_t begin, int64_t end) {
            LatticeMerger::Buffers b;
            for (int64_t r = begin; r < end; ++r) {
                const auto run = tiling.runs[r];
                const uint64_t tile = tile_of(lattice.key[tiling.order[run.first]], tiling.offset);
                const auto in_tile = [&](int32_t w) { return tile_of(lattice.key[w], tiling.offset) == tile; };
                per_run[r] = merger.merge_around(tiling.order.data() + run.first, static_cast<std::size_t>(run.second - run.first), b, in_tile);
            }
        });
        for (std::size_t n : per_run) merged += n;
    }
    LatticeMerger::Buffers b;
    return merged + merger.merge_around(active.data(), active.size(), b, anywhere);
}

}  // namespace

std::size_t mesh_cleanup(TriMesh& mesh, double cube_edge, double snap_distance, int threads, const std::vector<uint8_t>* pinned) {
    validate_mesh_arrays(mesh, "mesh_cleanup", threads);
    if (!(cube_edge > 0.0) || !std::isfinite(cube_edge))
        throw InputError("mesh_cleanup: cube_edge must be positive and finite, got " + std::to_string(cube_edge));
    if (!std::isfinite(snap_distance))
        throw InputError("mesh_cleanup: snap_distance must be finite (negative for no limit), got " + std::to_string(snap_distance));
    threads = resolve_threads(threads);
    if (mesh.num_vertices() == 0 || mesh.triangles.empty()) return 0;

    std::vector<int32_t> triangles = mesh.triangles;
    std::vector<float> positions = mesh.vertices;
    std::vector<uint8_t> removed(mesh.num_vertices(), 0);
    const LatticePoints lattice = nearest_lattice_points(positions, cube_edge, snap_distance, threads, pinned);
    const MeshAdjacency adj = working_adjacency(triangles, positions, threads);
    const std::vector<int32_t> active = active_vertices(adj, lattice, threads);

    CollapseMesh work(triangles, positions, adj.vertex_triangles, removed);
    LatticeMerger merger(work, lattice, positions, active, removed);
    const std::vector<Tiling> tilings = {make_tiling(active, lattice, 0, threads), make_tiling(active, lattice, 1 << (kTileShift - 1), threads)};
    std::size_t collapsed = 0;
    for (int round = 0; round < kMaxMergeRounds; ++round) {
        const std::size_t merged = merge_round(merger, tilings, lattice, active, threads);
        collapsed += merged;
        if (merged == 0) break;
    }
    if (collapsed == 0) return 0;
    drop_deleted_triangles(triangles, work.deleted_triangles(), threads);
    compact_into(mesh, triangles, positions, removed, &work.group_next(), threads);
    return collapsed;
}

}  // namespace meniscus
