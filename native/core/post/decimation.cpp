#include "post/decimation.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "base/compaction.h"
#include "base/greedy_selection.h"
#include "base/parallel.h"
#include "base/parallel_move.h"
#include "base/uninitialized_vector.h"
#include "post/collapse.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

// Detection passes at most. A pass collapses only configurations whose two-rings are disjoint; one too close to an
// earlier one waits for the next pass, whose detection sees the collapses already made. A few passes reach the
// fixed point on marching-cubes output; the cap bounds the work on pathological input.
constexpr int kMaxDetectionPasses = 10;

constexpr int64_t kRowBlock = int64_t{1} << 14;

// Drops the rows of `list` whose new_index is negative and moves the kept rows down, in place and in parallel over
// fixed blocks of rows. A block's kept items go right after the earlier blocks' (destinations only lie at or below
// sources), so a block may overwrite the end of an earlier block's source: each block first saves that end (the part
// below its own and later blocks' destinations is never written by them), then all move at once, reading the saved
// end where it lies. Within a block the copy runs forwards, writes never ahead of reads.
void drop_rows(CsrList& list, const UninitializedVector<int32_t>& new_index, int threads) {
    const int64_t nv = static_cast<int64_t>(list.rows());
    const int64_t blocks = (nv + kRowBlock - 1) / kRowBlock;
    auto block_rows = [&](int64_t b) { return std::make_pair(b * kRowBlock, std::min(nv, (b + 1) * kRowBlock)); };
    // dst[b]: where block b's kept items go; rows_before[b]: kept rows before block b.
    std::vector<int64_t> dst(static_cast<std::size_t>(blocks) + 1, 0), rows_before(static_cast<std::size_t>(blocks) + 1, 0);
    parallel_for(blocks, threads, [&](int64_t b) {
        int64_t items = 0, rows = 0;
        for (int64_t v = block_rows(b).first; v < block_rows(b).second; ++v)
            if (new_index[v] >= 0) items += list.offsets[v + 1] - list.offsets[v], ++rows;
        dst[b + 1] = items, rows_before[b + 1] = rows;
    });
    for (int64_t b = 0; b < blocks; ++b) dst[b + 1] += dst[b], rows_before[b + 1] += rows_before[b];
    // The saved ends: block b's source items at or above the next block's destination.
    std::vector<int64_t> saved_from(static_cast<std::size_t>(blocks)), saved_at(static_cast<std::size_t>(blocks) + 1, 0);
    for (int64_t b = 0; b < blocks; ++b) {
        const int64_t src_begin = list.offsets[block_rows(b).first], src_end = list.offsets[block_rows(b).second];
        saved_from[b] = std::min(src_end, std::max(src_begin, dst[b + 1]));
        saved_at[b + 1] = saved_at[b] + (src_end - saved_from[b]);
    }
    UninitializedVector<int32_t> saved(static_cast<std::size_t>(saved_at[blocks]));
    parallel_for(blocks, threads, [&](int64_t b) {
        std::copy(list.items.begin() + saved_from[b], list.items.begin() + list.offsets[block_rows(b).second], saved.begin() + saved_at[b]);
    });
    UninitializedVector<int64_t> offsets(static_cast<std::size_t>(rows_before[blocks]) + 1);  // every entry written below
    parallel_for(blocks, threads, [&](int64_t b) {
        int64_t write = dst[b], row = rows_before[b];
        const int64_t end_from_list = saved_from[b], saved_shift = saved_at[b] - saved_from[b];  // source position -> saved
        for (int64_t v = block_rows(b).first; v < block_rows(b).second; ++v) {
            if (new_index[v] < 0) continue;
            offsets[row++] = write;
            const int64_t begin = list.offsets[v], end = list.offsets[v + 1], split = std::max(begin, std::min(end, end_from_list));
            if (split > begin && write != begin)
                std::memmove(list.items.data() + write, list.items.data() + begin, static_cast<std::size_t>(split - begin) * sizeof(int32_t));
            write += split - begin;
            for (int64_t k = split; k < end; ++k) list.items[write++] = saved[k + saved_shift];
        }
    });
    offsets.back() = dst[blocks];
    list.offsets.swap(offsets);
    list.items.resize(static_cast<std::size_t>(dst[blocks]));
}

// Turns the adjacency of the working mesh into the one of the compacted mesh (same triangles, in the same order),
// in place: rows of removed vertices dropped and neighbour indices renumbered, both in parallel. The renumbering
// keeps the order, so rows stay sorted. No rebuild, and no second copy of the lists.
void renumber_adjacency(MeshAdjacency& adjacency, const UninitializedVector<int32_t>& new_index, int threads) {
    CsrList& neighbours = adjacency.vertex_neighbours;
    parallel_blocks(static_cast<int64_t>(neighbours.rows()), threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v)
            if (new_index[v] >= 0)
                for (int64_t k = neighbours.offsets[v]; k < neighbours.offsets[v + 1]; ++k) neighbours.items[k] = new_index[neighbours.items[k]];
    });
    drop_rows(adjacency.vertex_triangles, new_index, threads);
    drop_rows(neighbours, new_index, threads);
}

// Replaces the rows of the claimed vertices (ascending in `touched`) by `fresh` and renumbers the other rows' items
// through `renumber` (may be null), in place. Between two touched rows every row moves by the same shift, so the
// rows move as a few long segments, each in parallel chunks; segments moving down go first, in vertex order, then
// those moving up, in reverse order: neither overwrites a segment not yet moved (their final places are disjoint
// and keep the order). In place,
// because a copy of both lists is ~160 MB of fresh pages at a million particles, for a pass that touched a few
// hundred rows.
void replace_rows(CsrList& list, const std::vector<int32_t>& touched, const std::vector<std::vector<int32_t>>& fresh,
                  const std::vector<uint8_t>& claimed, const int32_t* renumber, int threads) {
    const int64_t nv = static_cast<int64_t>(list.rows());
    if (renumber)
        parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t v = begin; v < end; ++v)
                if (!claimed[v])
                    for (int64_t k = list.begin(v); k < list.end(v); ++k) list.items[k] = renumber[list.items[k]];
        });
    struct Segment {
        int64_t first_row, end_row;   // rows [first_row, end_row): those after a touched row, up to the next one (or nv)
        int64_t old_begin, old_end;   // their items before the move
        int64_t shift;
    };
    std::vector<Segment> segments;
    int64_t shift = 0;
    for (std::size_t i = 0; i < touched.size(); ++i) {
        const int64_t t = touched[i];
        shift += static_cast<int64_t>(fresh[i].size()) - list.size(static_cast<std::size_t>(t));
        const int64_t end_row = i + 1 < touched.size() ? touched[i + 1] : nv;
        segments.push_back({t + 1, end_row, list.offsets[t + 1], list.offsets[end_row], shift});
    }
    const int64_t old_total = list.offsets[nv];
    if (old_total + shift > old_total) list.items.resize(static_cast<std::size_t>(old_total + shift));
    auto move = [&](const Segment& g) { move_in_parallel(list.items.data(), g.old_begin, g.old_begin + g.shift, g.old_end - g.old_begin, threads); };
    for (const Segment& g : segments)
        if (g.shift < 0) move(g);
    for (auto g = segments.rbegin(); g != segments.rend(); ++g)
        if (g->shift > 0) move(*g);
    // New row starts: a segment's rows and the touched row after it (or the end) start `shift` later.
    parallel_for(static_cast<int64_t>(segments.size()), threads, [&](int64_t i) {  // disjoint rows
        const Segment& g = segments[static_cast<std::size_t>(i)];
        for (int64_t v = g.first_row; v <= g.end_row; ++v) list.offsets[v] += g.shift;
    }, 64);
    for (std::size_t i = 0; i < touched.size(); ++i) std::copy(fresh[i].begin(), fresh[i].end(), list.items.data() + list.offsets[touched[i]]);
    list.items.resize(static_cast<std::size_t>(list.offsets[nv]));
}

// The working mesh's adjacency after a pass (deleted triangles dropped), patched from the one before it. Every
// triangle a collapse rewrote or deleted has all its corners in the pass's claimed regions (a collapse n -> c only
// touches triangles around n, whose corners are neighbours of n), so a vertex outside them keeps its neighbours
// and its triangles, which only get their new numbers; rows of claimed vertices are recomputed from their current
// fans. The same lists as a rebuild.
void patch_adjacency(MeshAdjacency& adjacency, const CollapseMesh& work, const std::vector<int32_t>& triangles,
                     const std::vector<uint8_t>& claimed, int threads) {
    const UninitializedVector<uint8_t>& deleted = work.deleted_triangles();
    UninitializedVector<int32_t> new_id(deleted.size());  // every entry numbered below
    number_kept(static_cast<int64_t>(deleted.size()), threads, [&](int64_t t) { return !deleted[t]; }, new_id.data());
    const int64_t nv = static_cast<int64_t>(claimed.size());
    // Claimed vertices: current triangles (new numbers, ascending) and neighbours, from the fans `work` reads in the
    // lists as they are (before they change below).
    const std::vector<int32_t> touched = kept_indices(nv, threads, [&](int64_t v) { return claimed[v] != 0; });
    std::vector<std::vector<int32_t>> fans(touched.size()), rings(touched.size());
    parallel_blocks(static_cast<int64_t>(touched.size()), threads, 64, [&](int64_t begin, int64_t end) {
        std::vector<int32_t> fan;
        for (int64_t i = begin; i < end; ++i) {
            const int32_t v = touched[i];
            work.fan(v, fan);
            std::vector<int32_t>& row = fans[i];
            for (int32_t t : fan) {
                const int32_t* c = triangles.data() + 3 * static_cast<int64_t>(new_id[t]);
                if (c[0] == v || c[1] == v || c[2] == v) row.push_back(new_id[t]);
            }
            std::sort(row.begin(), row.end());
            row.erase(std::unique(row.begin(), row.end()), row.end());
            rings[i].resize(2 * row.size() + 1);
            rings[i].resize(static_cast<std::size_t>(
                collect_vertex_neighbours(triangles.data(), v, row.data(), static_cast<int32_t>(row.size()), rings[i].data())));
        }
    });
    replace_rows(adjacency.vertex_triangles, touched, fans, claimed, new_id.data(), threads);
    replace_rows(adjacency.vertex_neighbours, touched, rings, claimed, nullptr, threads);
}


// ---- barnacle detection ------------------------------------------------------------------------------------

bool is_single_centre(const MeshAdjacency& adj, int32_t v) {
    if (adj.valence(v) != 4) return false;
    int32_t sum = 0;
    const int32_t* row = adj.vertex_neighbours.row(v);
    for (int k = 0; k < 4; ++k) {
        const int32_t w = adj.valence(row[k]);
        if (w < 4 || w > 6) return false;
        sum += w;
    }
    return sum == 20;
}

// Centres c and d (adjacent, both valence 5): exactly two shared neighbours, both valence 6, and each centre's
// two remaining neighbours of valence 5 (each centre's neighbour valences are [5, 5, 5, 6, 6]).
bool is_double_pair(const MeshAdjacency& adj, int32_t c, int32_t d) {
    if (adj.valence(c) != 5 || adj.valence(d) != 5) return false;
    const int32_t* rc = adj.vertex_neighbours.row(c);
    const int32_t* rd = adj.vertex_neighbours.row(d);
    int shared = 0;
    for (int i = 0; i < 5; ++i) {
        if (rc[i] == d) continue;
        const bool in_d = std::binary_search(rd, rd + 5, rc[i]);
        const int32_t w = adj.valence(rc[i]);
        if (in_d) {
            if (w != 6) return false;
            ++shared;
        } else if (w != 5) {
            return false;
        }
    }
    if (shared != 2) return false;
    for (int i = 0; i < 5; ++i) {
        if (rd[i] == c || std::binary_search(rc, rc + 5, rd[i])) continue;
        if (adj.valence(rd[i]) != 5) return false;
    }
    return true;
}

// Double pairs are reported at their smaller centre; -1 when v is not the smaller centre of a pair.
int32_t double_partner(const MeshAdjacency& adj, int32_t v) {
    if (adj.valence(v) != 5) return -1;
    const int32_t* row = adj.vertex_neighbours.row(v);
    for (int k = 0; k < 5; ++k)
        if (row[k] > v && is_double_pair(adj, v, row[k])) return row[k];
    return -1;
}

struct Candidate {
    int32_t centre = -1, partner = -1;  // partner = -1 for a single-vertex configuration
};

// Whether a configuration's centres or one-rings hold a pinned vertex.
bool touches_pinned(const MeshAdjacency& adj, const Candidate& cand, const std::vector<uint8_t>& pinned) {
    for (int32_t c : {cand.centre, cand.partner}) {
        if (c < 0) continue;
        if (pinned[c]) return true;
        for (int64_t k = adj.vertex_neighbours.begin(c); k < adj.vertex_neighbours.end(c); ++k)
            if (pinned[adj.vertex_neighbours.items[k]]) return true;
    }
    return false;
}

std::vector<Candidate> find_candidates(const MeshAdjacency& adj, int threads, const std::vector<uint8_t>* pinned) {
    const int64_t nv = static_cast<int64_t>(adj.vertex_neighbours.rows());
    UninitializedVector<int32_t> kind(static_cast<std::size_t>(nv));  // -2 none, -1 single, >= 0 double partner
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            kind[v] = -2;
            if (is_single_centre(adj, static_cast<int32_t>(v))) {
                kind[v] = -1;
            } else {
                const int32_t partner = double_partner(adj, static_cast<int32_t>(v));
                if (partner >= 0) kind[v] = partner;
            }
        }
    });
    auto candidate = [&](int64_t v) { return Candidate{static_cast<int32_t>(v), kind[v] >= 0 ? kind[v] : -1}; };
    const std::vector<int32_t> centres = kept_indices(nv, threads, [&](int64_t v) {
        return kind[v] != -2 && (!pinned || !touches_pinned(adj, candidate(v), *pinned));
    });
    std::vector<Candidate> out(centres.size());
    for (std::size_t i = 0; i < centres.size(); ++i) out[i] = candidate(centres[i]);
    return out;
}

// Vertices whose state a candidate's collapses read or write: centres, their one-rings and those rings'
// neighbours. Candidates with disjoint sets cannot influence each other, so they run in parallel and the result
// does not depend on the order or thread count.
void closed_two_ring(const MeshAdjacency& adj, const Candidate& cand, std::vector<int32_t>& out) {
    out.clear();
    const int32_t centres[2] = {cand.centre, cand.partner};
    for (int32_t c : centres) {
        if (c < 0) continue;
        out.push_back(c);
        for (int64_t k = adj.vertex_neighbours.begin(c); k < adj.vertex_neighbours.end(c); ++k) {
            const int32_t u = adj.vertex_neighbours.items[k];
            out.push_back(u);
            for (int64_t m = adj.vertex_neighbours.begin(u); m < adj.vertex_neighbours.end(u); ++m)
                out.push_back(adj.vertex_neighbours.items[m]);
        }
    }
}


// The candidates a greedy pass in candidate order takes (one is taken when no vertex of its closed two-ring was
// claimed by one taken before it), selected in parallel with the same result; their two-rings get claim[v] = pass.
std::vector<Candidate> select_disjoint(const MeshAdjacency& adj, const std::vector<Candidate>& candidates, UninitializedVector<int32_t>& claim,
                                       int32_t pass, UninitializedVector<std::atomic<int32_t>>& lowest, int threads) {
    std::vector<std::vector<int32_t>> regions(candidates.size());
    parallel_for(static_cast<int64_t>(candidates.size()), threads, [&](int64_t i) { closed_two_ring(adj, candidates[i], regions[i]); }, 16);
    const std::vector<uint8_t> taken = select_greedy_disjoint(regions, claim, pass, lowest, threads);
    std::vector<Candidate> selected;
    for (std::size_t i = 0; i < candidates.size(); ++i)
        if (taken[i]) selected.push_back(candidates[i]);
    return selected;
}

// The collapses that remove a configuration, as (vertex to remove, centre): the one-ring of the centre; for a
// double configuration the shared neighbours go to the first centre and the rest of each ring to its own centre.
void ring_collapses(const MeshAdjacency& adj, const Candidate& cand, std::vector<std::pair<int32_t, int32_t>>& out) {
    out.clear();
    const int32_t* rc = adj.vertex_neighbours.row(cand.centre);
    const int32_t nc = adj.valence(cand.centre);
    for (int32_t k = 0; k < nc; ++k)
        if (rc[k] != cand.partner) out.emplace_back(rc[k], cand.centre);
    if (cand.partner < 0) return;
    const int32_t* rd = adj.vertex_neighbours.row(cand.partner);
    for (int32_t k = 0; k < adj.valence(cand.partner); ++k)
        if (rd[k] != cand.centre && !std::binary_search(rc, rc + nc, rd[k])) out.emplace_back(rd[k], cand.partner);
}

struct PassOutcome {
    std::size_t removed_configurations = 0;  // configurations whose every ring vertex went
    bool changed = false;                    // any collapse at all
};

// Collapses the rings of the selected configurations, in parallel (their two-rings are disjoint, so the result does
// not depend on the order or the thread count). A collapse refused now may become legal after its neighbours
// went: retried while progressing.
PassOutcome collapse_selected(const MeshAdjacency& adj, const std::vector<Candidate>& selected, CollapseMesh& work, int threads) {
    std::vector<uint8_t> complete(selected.size(), 0), any(selected.size(), 0);
    parallel_blocks(static_cast<int64_t>(selected.size()), threads, 16, [&](int64_t begin, int64_t end) {
        CollapseScratch s;
        std::vector<std::pair<int32_t, int32_t>> pending;
        for (int64_t i = begin; i < end; ++i) {
            ring_collapses(adj, selected[i], pending);
            bool progress = true;
            while (!pending.empty() && progress) {
                progress = false;
                std::size_t keep = 0;
                for (const auto& job : pending) {
                    if (work.try_collapse(job.first, job.second, nullptr, s, anywhere)) progress = true;
                    else pending[keep++] = job;
                }
                pending.resize(keep);
                if (progress) any[i] = 1;
            }
            complete[i] = pending.empty() ? 1 : 0;
        }
    });
    PassOutcome outcome;
    for (std::size_t i = 0; i < selected.size(); ++i) {
        outcome.removed_configurations += complete[i];
        outcome.changed = outcome.changed || any[i];
    }
    return outcome;
}

std::vector<uint8_t> claimed_in(const UninitializedVector<int32_t>& claim, int32_t pass, int threads) {
    std::vector<uint8_t> claimed(claim.size());
    parallel_blocks(static_cast<int64_t>(claim.size()), threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) claimed[v] = claim[v] == pass;
    });
    return claimed;
}

}  // namespace

std::size_t count_single_vertex_configurations(const MeshAdjacency& adj, int threads) {
    return parallel_count(static_cast<int64_t>(adj.vertex_neighbours.rows()), threads,
                          [&](int64_t v) { return is_single_centre(adj, static_cast<int32_t>(v)); });
}

std::size_t count_double_vertex_configurations(const MeshAdjacency& adj, int threads) {
    return parallel_count(static_cast<int64_t>(adj.vertex_neighbours.rows()), threads, [&](int64_t v) {
        int pairs = 0;
        if (adj.valence(v) != 5) return pairs;
        const int32_t* row = adj.vertex_neighbours.row(v);
        for (int k = 0; k < 5; ++k)  // each pair once, at its smaller centre
            if (row[k] > v && is_double_pair(adj, static_cast<int32_t>(v), row[k])) ++pairs;
        return pairs;
    });
}

std::size_t count_single_vertex_configurations(const TriMesh& mesh) {
    validate_mesh_arrays(mesh, "count_single_vertex_configurations");
    return count_single_vertex_configurations(build_adjacency(mesh, 0), 0);
}

std::size_t count_double_vertex_configurations(const TriMesh& mesh) {
    validate_mesh_arrays(mesh, "count_double_vertex_configurations");
    return count_double_vertex_configurations(build_adjacency(mesh, 0), 0);
}


std::size_t decimate_barnacles(TriMesh& mesh, int threads, MeshAdjacency* final_adjacency, const std::vector<uint8_t>* pinned) {
    validate_mesh_arrays(mesh, "decimate_barnacles", threads);
    if (final_adjacency) *final_adjacency = MeshAdjacency{};
    threads = resolve_threads(threads);
    // The working arrays take the mesh's own (a copy was ~0.1 s of serial page faults at 1 M particles): compact_into
    // writes the result back; with nothing collapsed they go back as they are.
    const std::size_t nv = mesh.num_vertices();
    std::vector<int32_t> triangles = std::move(mesh.triangles);
    std::vector<float> positions = std::move(mesh.vertices);
    std::vector<uint8_t> removed(nv, 0);
    UninitializedVector<int32_t> claim;  // the pass whose selection claimed the vertex
    fill_in_parallel(claim, nv, int32_t{-1}, threads);
    UninitializedVector<std::atomic<int32_t>> lowest;  // select_disjoint's scratch (written before read), made when there are candidates
    std::size_t removed_configurations = 0;
    bool changed = false;

    MeshAdjacency adj = working_adjacency(triangles, positions, threads);
    bool adjacency_is_current = true;  // adj describes the working triangles as they are now
    for (int pass = 0; pass < kMaxDetectionPasses; ++pass) {
        const std::vector<Candidate> candidates = find_candidates(adj, threads, pinned);
        if (candidates.empty()) break;
        if (lowest.empty()) lowest = UninitializedVector<std::atomic<int32_t>>(nv);
        const std::vector<Candidate> selected = select_disjoint(adj, candidates, claim, pass, lowest, threads);
        CollapseMesh work(triangles, positions, adj.vertex_triangles, removed, threads);
        const PassOutcome outcome = collapse_selected(adj, selected, work, threads);
        removed_configurations += outcome.removed_configurations;
        drop_deleted_triangles(triangles, work.deleted_triangles(), threads);
        changed = changed || outcome.changed;
        if (!outcome.changed) break;
        adjacency_is_current = pass + 1 < kMaxDetectionPasses;  // the last pass's collapses are not patched in
        if (adjacency_is_current) patch_adjacency(adj, work, triangles, claimed_in(claim, pass, threads), threads);
    }
    if (changed) {
        claim = UninitializedVector<int32_t>();
        const UninitializedVector<int32_t> new_index = compact_into(mesh, triangles, positions, removed, nullptr, threads);
        if (final_adjacency && adjacency_is_current) renumber_adjacency(adj, new_index, threads);
    } else {
        mesh.triangles = std::move(triangles);
        mesh.vertices = std::move(positions);
    }
    if (final_adjacency && adjacency_is_current) *final_adjacency = std::move(adj);
    return removed_configurations;
}

}  // namespace meniscus
