// Specialized decimation of marching-cubes "barnacle" configurations and the grid-point "mesh cleanup" (paper
// Sec. 3.3). Both are sequences of half-edge collapses n -> c (vertex n disappears, its triangles are re-attached
// to c, the two triangles of edge (n, c) are deleted), each allowed only when it is legal:
//   - n and c each have a closed disk fan and the edge (n, c) has exactly two triangles of opposite direction
//     (so non-manifold or open input is left alone where it is broken, never made worse);
//   - link condition: n and c share exactly the two neighbours opposite the edge (no fold-over, no duplicate
//     triangles, the mesh stays a closed 2-manifold);
//   - no vertex drops below valence 3 (this also refuses to collapse a tetrahedron);
//   - no re-attached triangle becomes degenerate (zero area) or turns its normal by 90 degrees or more.
//
// The mesh is edited in a working copy: triangles are rewritten in place and flagged when deleted; a vertex's
// current fan is the union of the static CSR rows of the vertices merged into it (a singly linked "group"
// list), so no per-vertex containers are allocated and a collapse costs O(fan sizes).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "base/errors.h"
#include "mesh/adjacency.h"
#include "post/postprocess.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

struct Scratch {
    std::vector<int32_t> fan_n, fan_c, nbr_n, nbr_c, fan_tmp, nbr_tmp, succ;
};

void sort_unique(std::vector<int32_t>& v) {
    // Rows are short: insertion sort (std::sort for a pathological fan), then drop repeats.
    if (v.size() > 32) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
        return;
    }
    for (std::size_t i = 1; i < v.size(); ++i) {
        const int32_t value = v[i];
        std::size_t j = i;
        for (; j > 0 && v[j - 1] > value; --j) v[j] = v[j - 1];
        v[j] = value;
    }
    v.erase(std::unique(v.begin(), v.end()), v.end());
}

// Normal (unnormalised) of the triangle with corners p0, p1, p2 in double.
inline void triangle_normal(const float* p0, const float* p1, const float* p2, double n[3]) {
    const double e1[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
    const double e2[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

// Region predicate that accepts every vertex (sequential or otherwise isolated work).
struct Anywhere {
    bool operator()(int32_t) const { return true; }
};
constexpr Anywhere anywhere{};

class CollapseMesh {
public:
    // `triangles` and `positions` are the working arrays (edited in place); `vt` is the vertex -> triangle CSR of
    // `triangles` at construction; `removed` flags vertices already collapsed away (kept across rebuilds).
    CollapseMesh(std::vector<int32_t>& triangles, std::vector<float>& positions, const CsrList& vt,
                 std::vector<uint8_t>& removed)
        : tris_(triangles), pos_(positions), vt_(vt), removed_(removed) {
        const std::size_t nv = positions.size() / 3;
        deleted_.assign(triangles.size() / 3, 0);
        next_.assign(nv, -1);
        tail_.resize(nv);
        for (std::size_t v = 0; v < nv; ++v) tail_[v] = static_cast<int32_t>(v);
    }

    const std::vector<uint8_t>& deleted_triangles() const { return deleted_; }
    const std::vector<int32_t>& group_next() const { return next_; }

    // Current triangles around v.
    void fan(int32_t v, std::vector<int32_t>& out) const {
        out.clear();
        for (int32_t u = v; u != -1; u = next_[u])
            for (int64_t k = vt_.begin(u); k < vt_.end(u); ++k)
                if (!deleted_[vt_.items[k]]) out.push_back(vt_.items[k]);
    }

    // Distinct other vertices of the triangles in `fan` (around v), ascending.
    void neighbours(int32_t v, const std::vector<int32_t>& fan, std::vector<int32_t>& out) const {
        out.clear();
        for (int32_t t : fan)
            for (int k = 0; k < 3; ++k)
                if (tri(t)[k] != v) out.push_back(tri(t)[k]);
        sort_unique(out);
    }

    int32_t valence(int32_t v, Scratch& s) const {
        fan(v, s.fan_tmp);
        neighbours(v, s.fan_tmp, s.nbr_tmp);
        return static_cast<int32_t>(s.nbr_tmp.size());
    }

    // Half-edge collapse n -> c; c moves to `target` when given. Returns false (and changes nothing) when the
    // collapse is not legal. With a `region` predicate, the collapse is also refused unless n, c and every
    // vertex of their fans belong to the region: the collapse then reads and writes only triangles whose corners
    // are all in the region and vertices of the region, so disjoint regions can be processed concurrently
    // (n and c must be known to be in the region before the call: their flags are read first).
    template <class Region>
    bool try_collapse(int32_t n, int32_t c, const float* target, Scratch& s, const Region& region) {
        if (n == c || removed_[n] || removed_[c]) return false;
        fan(n, s.fan_n);
        fan(c, s.fan_c);
        for (const std::vector<int32_t>* f : {&s.fan_n, &s.fan_c})
            for (int32_t t : *f)
                for (int k = 0; k < 3; ++k)
                    if (!region(tri(t)[k])) return false;
        int32_t edge_tris[2] = {-1, -1}, opposite[2] = {-1, -1};
        int count = 0, direction = 0;
        for (int32_t t : s.fan_n) {
            const int32_t* p = tri(t);
            if (p[0] == p[1] || p[1] == p[2] || p[2] == p[0]) return false;
            int kn = 0;
            while (p[kn] != n) ++kn;
            const int32_t next = p[(kn + 1) % 3], prev = p[(kn + 2) % 3];
            if (next != c && prev != c) continue;
            if (count == 2) return false;  // non-manifold edge
            edge_tris[count] = t;
            opposite[count] = next == c ? prev : next;
            direction += next == c ? 1 : -1;
            ++count;
        }
        if (count != 2 || direction != 0 || opposite[0] == opposite[1]) return false;
        neighbours(n, s.fan_n, s.nbr_n);
        neighbours(c, s.fan_c, s.nbr_c);
        if (!closed_disk(n, s.fan_n, s.nbr_n, s) || !closed_disk(c, s.fan_c, s.nbr_c, s)) return false;
        // Link condition: the common neighbours are exactly the two opposite vertices (both are common).
        std::size_t common = 0;
        for (std::size_t i = 0, j = 0; i < s.nbr_n.size() && j < s.nbr_c.size();) {
            if (s.nbr_n[i] < s.nbr_c[j]) ++i;
            else if (s.nbr_c[j] < s.nbr_n[i]) ++j;
            else { ++common; ++i; ++j; }
        }
        if (common != 2) return false;
        // Valences afterwards: c gets the union of both rings minus {n, c}; each opposite vertex loses n.
        if (static_cast<int64_t>(s.nbr_n.size() + s.nbr_c.size()) - 4 < 3) return false;
        for (int32_t x : opposite)
            if (valence(x, s) < 4) return false;

        const float* p = target ? target : position(c);
        for (int32_t t : s.fan_n)
            if (t != edge_tris[0] && t != edge_tris[1] && !moves_well(t, n, p)) return false;
        const bool c_moves = target && (p[0] != position(c)[0] || p[1] != position(c)[1] || p[2] != position(c)[2]);
        if (c_moves)
            for (int32_t t : s.fan_c)
                if (t != edge_tris[0] && t != edge_tris[1] && !moves_well(t, c, p)) return false;

        deleted_[edge_tris[0]] = deleted_[edge_tris[1]] = 1;
        for (int32_t t : s.fan_n) {
            if (deleted_[t]) continue;
            int32_t* q = tri(t);
            for (int k = 0; k < 3; ++k)
                if (q[k] == n) q[k] = c;
        }
        next_[tail_[c]] = n;
        tail_[c] = tail_[n];
        removed_[n] = 1;
        if (c_moves) {
            float* pc = pos_.data() + 3 * static_cast<int64_t>(c);
            pc[0] = p[0], pc[1] = p[1], pc[2] = p[2];
        }
        return true;
    }

private:
    const int32_t* tri(int32_t t) const { return tris_.data() + 3 * static_cast<int64_t>(t); }
    int32_t* tri(int32_t t) { return tris_.data() + 3 * static_cast<int64_t>(t); }
    const float* position(int32_t v) const { return pos_.data() + 3 * static_cast<int64_t>(v); }

    // The fan of v is a closed disk: as many triangles as neighbours, and the link edges next(v) -> prev(v)
    // form one cycle through all neighbours.
    bool closed_disk(int32_t v, const std::vector<int32_t>& fan, const std::vector<int32_t>& nbrs, Scratch& s) const {
        const std::size_t k = nbrs.size();
        if (fan.size() != k || k < 3) return false;
        s.succ.assign(k, -1);
        auto local = [&](int32_t u) { return static_cast<int32_t>(std::lower_bound(nbrs.begin(), nbrs.end(), u) - nbrs.begin()); };
        for (int32_t t : fan) {
            const int32_t* p = tri(t);
            if (p[0] == p[1] || p[1] == p[2] || p[2] == p[0]) return false;
            int kv = 0;
            while (p[kv] != v) ++kv;
            const int32_t a = local(p[(kv + 1) % 3]);
            if (s.succ[a] != -1) return false;
            s.succ[a] = local(p[(kv + 2) % 3]);
        }
        int32_t cur = 0;
        for (std::size_t i = 1; i <= k; ++i) {
            cur = s.succ[cur];
            if (cur == 0) return i == k;
        }
        return false;
    }

    // Triangle t with vertex v moved to p keeps a non-zero area and does not turn its normal by >= 90 degrees.
    bool moves_well(int32_t t, int32_t v, const float* p) const {
        const int32_t* q = tri(t);
        const float* before[3] = {position(q[0]), position(q[1]), position(q[2])};
        const float* after[3] = {before[0], before[1], before[2]};
        for (int k = 0; k < 3; ++k)
            if (q[k] == v) after[k] = p;
        double n0[3], n1[3];
        triangle_normal(before[0], before[1], before[2], n0);
        triangle_normal(after[0], after[1], after[2], n1);
        if (n1[0] == 0.0 && n1[1] == 0.0 && n1[2] == 0.0) return false;
        if (!std::isfinite(n1[0] + n1[1] + n1[2])) return false;
        if (n0[0] == 0.0 && n0[1] == 0.0 && n0[2] == 0.0) return true;  // was degenerate: no orientation to keep
        return n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] > 0.0;
    }

    std::vector<int32_t>& tris_;
    std::vector<float>& pos_;
    const CsrList& vt_;
    std::vector<uint8_t>& removed_;
    std::vector<uint8_t> deleted_;
    std::vector<int32_t> next_, tail_;  // group lists: vertices merged into a vertex, in merge order
};

// Drops deleted triangles from the working triangle array.
void drop_deleted_triangles(std::vector<int32_t>& triangles, const std::vector<uint8_t>& deleted) {
    std::size_t out = 0;
    for (std::size_t t = 0; t < deleted.size(); ++t) {
        if (deleted[t]) continue;
        for (int k = 0; k < 3; ++k) triangles[3 * out + k] = triangles[3 * t + k];
        ++out;
    }
    triangles.resize(3 * out);
}

// Writes the working arrays back into mesh without the removed vertices. With group lists (cleanup), every
// surviving vertex's normal and attributes become the mean over the original vertices merged into it, like its
// position; without them (barnacles: the centre stays where it is) the survivor keeps its own values.
// Returns the new index of every old vertex (-1: removed).
std::vector<int32_t> compact_into(TriMesh& mesh, std::vector<int32_t>& triangles, const std::vector<float>& positions,
                                  const std::vector<uint8_t>& removed, const std::vector<int32_t>* group_next, int threads) {
    const int64_t nv = static_cast<int64_t>(removed.size());
    std::vector<int32_t> new_index(static_cast<std::size_t>(nv), -1);
    std::vector<int32_t> survivors;
    survivors.reserve(static_cast<std::size_t>(nv));
    for (int64_t v = 0; v < nv; ++v)
        if (!removed[v]) {
            new_index[v] = static_cast<int32_t>(survivors.size());
            survivors.push_back(static_cast<int32_t>(v));
        }
    const int64_t ns = static_cast<int64_t>(survivors.size());
    parallel_blocks(static_cast<int64_t>(triangles.size()), threads, 16 * kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) triangles[i] = new_index[triangles[i]];
    });
    std::vector<float> vertices(3 * static_cast<std::size_t>(ns));
    parallel_blocks(ns, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i)
            for (int k = 0; k < 3; ++k) vertices[3 * i + k] = positions[3 * static_cast<int64_t>(survivors[i]) + k];
    });
    auto gather = [&](std::vector<float>& values, int components, bool renormalise) {
        std::vector<float> out(static_cast<std::size_t>(ns) * components);
        parallel_blocks(ns, threads, kBlock, [&](int64_t begin, int64_t end) {
            std::vector<double> sum(static_cast<std::size_t>(components));
            for (int64_t i = begin; i < end; ++i) {
                const int64_t v = survivors[i];
                float* dst = out.data() + i * components;
                const float* own = values.data() + v * components;
                if (!group_next || (*group_next)[v] == -1) {
                    std::copy(own, own + components, dst);
                    continue;
                }
                std::fill(sum.begin(), sum.end(), 0.0);
                int64_t count = 0;
                for (int32_t u = static_cast<int32_t>(v); u != -1; u = (*group_next)[u], ++count)
                    for (int k = 0; k < components; ++k) sum[k] += values[static_cast<int64_t>(u) * components + k];
                double length = 0.0;
                for (int k = 0; k < components; ++k) length += sum[k] * sum[k];
                if (renormalise) {
                    length = std::sqrt(length);
                    if (!(length > 0.0) || !std::isfinite(length)) {
                        std::copy(own, own + components, dst);
                        continue;
                    }
                    for (int k = 0; k < components; ++k) dst[k] = static_cast<float>(sum[k] / length);
                } else {
                    for (int k = 0; k < components; ++k) dst[k] = static_cast<float>(sum[k] / double(count));
                }
            }
        });
        values.swap(out);
    };
    if (!mesh.normals.empty()) gather(mesh.normals, 3, true);
    for (Attribute& a : mesh.attributes) gather(a.values, a.components, false);
    mesh.vertices.swap(vertices);
    mesh.triangles.swap(triangles);
    return new_index;
}

// Turns the adjacency of the working mesh into the one of the compacted mesh (same triangles, in the same order),
// in place: rows of removed vertices (which have no triangles left) dropped and neighbour indices renumbered. New
// row starts never lie after old ones, so moving rows down in vertex order overwrites nothing still needed, and the
// renumbering keeps the order, so rows stay sorted. A linear pass instead of a rebuild, without a second copy.
void renumber_adjacency(MeshAdjacency& adjacency, const std::vector<int32_t>& new_index) {
    auto renumber_rows = [&](CsrList& list, bool renumber_items) {
        const int64_t nv = static_cast<int64_t>(list.rows());
        int64_t write = 0, row = 0;
        for (int64_t v = 0; v < nv; ++v) {
            const int64_t begin = list.offsets[v], end = list.offsets[v + 1];  // offsets[v] is not yet overwritten
            if (new_index[v] < 0) continue;
            list.offsets[row] = write;
            for (int64_t k = begin; k < end; ++k) list.items[write++] = renumber_items ? new_index[list.items[k]] : list.items[k];
            ++row;
        }
        list.offsets[row] = write;
        list.offsets.resize(static_cast<std::size_t>(row) + 1);
        list.items.resize(static_cast<std::size_t>(write));
    };
    renumber_rows(adjacency.vertex_triangles, false);
    renumber_rows(adjacency.vertex_neighbours, true);
}

// The adjacency of the working mesh after a pass (deleted triangles dropped), from the one before it. Every
// triangle a collapse rewrote or deleted has all its corners in the pass's claimed regions (a collapse n -> c only
// touches triangles around n, whose corners are neighbours of n), so a vertex outside them keeps its neighbours
// and its triangles, which only get their new numbers; rows of claimed vertices are recomputed from their current
// fans. The same lists as a rebuild, in one linear pass.
MeshAdjacency patch_adjacency(const MeshAdjacency& before, const CollapseMesh& work, const std::vector<int32_t>& triangles,
                              const std::vector<uint8_t>& claimed, int threads) {
    const std::vector<uint8_t>& deleted = work.deleted_triangles();
    std::vector<int32_t> new_id(deleted.size(), -1);
    int32_t next_id = 0;
    for (std::size_t t = 0; t < deleted.size(); ++t)
        if (!deleted[t]) new_id[t] = next_id++;
    const int64_t nv = static_cast<int64_t>(claimed.size());
    // Claimed vertices: current triangles (new numbers, ascending) and neighbours.
    std::vector<int32_t> touched;
    for (int64_t v = 0; v < nv; ++v)
        if (claimed[v]) touched.push_back(static_cast<int32_t>(v));
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
    std::vector<int32_t> slot(static_cast<std::size_t>(nv), -1);
    for (std::size_t i = 0; i < touched.size(); ++i) slot[touched[i]] = static_cast<int32_t>(i);
    MeshAdjacency after;
    auto assemble = [&](const CsrList& old, const std::vector<std::vector<int32_t>>& fresh, bool renumber, CsrList& out) {
        out.offsets.assign(static_cast<std::size_t>(nv) + 1, 0);
        for (int64_t v = 0; v < nv; ++v)
            out.offsets[v + 1] = out.offsets[v] + (slot[v] >= 0 ? static_cast<int64_t>(fresh[slot[v]].size()) : old.size(v));
        out.items.resize(static_cast<std::size_t>(out.offsets.back()));
        parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t v = begin; v < end; ++v) {
                int32_t* dst = out.items.data() + out.offsets[v];
                if (slot[v] >= 0) std::copy(fresh[slot[v]].begin(), fresh[slot[v]].end(), dst);
                else
                    for (int64_t k = old.begin(v); k < old.end(v); ++k) *dst++ = renumber ? new_id[old.items[k]] : old.items[k];
            }
        });
    };
    assemble(before.vertex_triangles, fans, true, after.vertex_triangles);
    assemble(before.vertex_neighbours, rings, false, after.vertex_neighbours);
    return after;
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

// Nearest lattice point (in units of the cube edge).
struct LatticeKey {
    int32_t k[3] = {0, 0, 0};
    bool operator==(const LatticeKey& o) const { return k[0] == o.k[0] && k[1] == o.k[1] && k[2] == o.k[2]; }
};

struct Candidate {
    int32_t centre = -1, partner = -1;  // partner = -1 for a single-vertex configuration
};

std::vector<Candidate> find_candidates(const MeshAdjacency& adj, int threads) {
    const int64_t nv = static_cast<int64_t>(adj.vertex_neighbours.rows());
    std::vector<int32_t> kind(static_cast<std::size_t>(nv), -2);  // -2 none, -1 single, >= 0 double partner
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            if (is_single_centre(adj, static_cast<int32_t>(v))) {
                kind[v] = -1;
            } else {
                const int32_t partner = double_partner(adj, static_cast<int32_t>(v));
                if (partner >= 0) kind[v] = partner;
            }
        }
    });
    std::vector<Candidate> out;
    for (int64_t v = 0; v < nv; ++v)
        if (kind[v] != -2) out.push_back({static_cast<int32_t>(v), kind[v] >= 0 ? kind[v] : -1});
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

}  // namespace

std::size_t count_single_vertex_configurations(const MeshAdjacency& adj, int threads) {
    const int64_t nv = static_cast<int64_t>(adj.vertex_neighbours.rows());
    std::size_t count = 0;
#pragma omp parallel for reduction(+ : count) schedule(static) num_threads(resolve_threads(threads))
    for (int64_t v = 0; v < nv; ++v) count += is_single_centre(adj, static_cast<int32_t>(v)) ? 1 : 0;
    return count;
}

std::size_t count_double_vertex_configurations(const MeshAdjacency& adj, int threads) {
    const int64_t nv = static_cast<int64_t>(adj.vertex_neighbours.rows());
    std::size_t count = 0;
#pragma omp parallel for reduction(+ : count) schedule(static) num_threads(resolve_threads(threads))
    for (int64_t v = 0; v < nv; ++v) {
        if (adj.valence(v) != 5) continue;
        const int32_t* row = adj.vertex_neighbours.row(v);
        for (int k = 0; k < 5; ++k)  // each pair once, at its smaller centre
            if (row[k] > v && is_double_pair(adj, static_cast<int32_t>(v), row[k])) ++count;
    }
    return count;
}

std::size_t count_single_vertex_configurations(const TriMesh& mesh) {
    validate_mesh_arrays(mesh, "count_single_vertex_configurations");
    return count_single_vertex_configurations(build_adjacency(mesh, 0), 0);
}

std::size_t count_double_vertex_configurations(const TriMesh& mesh) {
    validate_mesh_arrays(mesh, "count_double_vertex_configurations");
    return count_double_vertex_configurations(build_adjacency(mesh, 0), 0);
}

std::size_t decimate_barnacles(TriMesh& mesh, int threads, MeshAdjacency* final_adjacency) {
    validate_mesh_arrays(mesh, "decimate_barnacles");
    if (final_adjacency) *final_adjacency = MeshAdjacency{};
    threads = resolve_threads(threads);
    std::vector<int32_t> triangles = mesh.triangles;
    std::vector<float> positions = mesh.vertices;
    std::vector<uint8_t> removed(mesh.num_vertices(), 0);
    std::vector<int32_t> claim(mesh.num_vertices(), -1);
    std::size_t removed_configurations = 0;
    bool changed = false;
    int32_t claim_stamp = 0;

    // Candidates too close to an earlier one are deferred to the next pass, where the mesh (and so the detection)
    // reflects the collapses already made; a few passes reach the fixed point.
    constexpr int kMaxPasses = 10;
    MeshAdjacency adj;
    {
        TriMesh view;  // adjacency of the working triangles (removed vertices simply have no triangles)
        view.vertices.swap(positions);
        view.triangles.swap(triangles);
        adj = build_adjacency(view, threads);
        positions.swap(view.vertices);
        triangles.swap(view.triangles);
    }
    bool adjacency_is_current = true;  // adj describes the working triangles as they are now
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        const std::vector<Candidate> candidates = find_candidates(adj, threads);
        if (candidates.empty()) break;

        // Greedy selection in index order: sequential, O(candidates x two-ring size).
        std::vector<Candidate> selected;
        std::vector<int32_t> region;
        const int32_t pass_first_stamp = claim_stamp;
        for (const Candidate& cand : candidates) {
            closed_two_ring(adj, cand, region);
            bool free = true;
            for (int32_t v : region)
                if (claim[v] >= pass_first_stamp) { free = false; break; }
            if (!free) continue;
            for (int32_t v : region) claim[v] = claim_stamp;
            ++claim_stamp;
            selected.push_back(cand);
        }

        CollapseMesh work(triangles, positions, adj.vertex_triangles, removed);
        std::vector<uint8_t> complete(selected.size(), 0), any(selected.size(), 0);
        parallel_blocks(static_cast<int64_t>(selected.size()), threads, 16, [&](int64_t begin, int64_t end) {
            Scratch s;
            std::vector<std::pair<int32_t, int32_t>> pending;  // (vertex to remove, centre)
            for (int64_t i = begin; i < end; ++i) {
                const Candidate& cand = selected[i];
                pending.clear();
                // The one-ring of the centre; for a double configuration the shared neighbours go to the first
                // centre and the rest of each ring to its own centre.
                const int32_t* rc = adj.vertex_neighbours.row(cand.centre);
                const int32_t nc = adj.valence(cand.centre);
                for (int32_t k = 0; k < nc; ++k)
                    if (rc[k] != cand.partner) pending.emplace_back(rc[k], cand.centre);
                if (cand.partner >= 0) {
                    const int32_t* rd = adj.vertex_neighbours.row(cand.partner);
                    for (int32_t k = 0; k < adj.valence(cand.partner); ++k)
                        if (rd[k] != cand.centre && !std::binary_search(rc, rc + nc, rd[k]))
                            pending.emplace_back(rd[k], cand.partner);
                }
                // A collapse refused now may become legal after its neighbours went: retry while progressing.
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
        bool pass_changed = false;
        for (std::size_t i = 0; i < selected.size(); ++i) {
            removed_configurations += complete[i];
            pass_changed = pass_changed || any[i];
        }
        drop_deleted_triangles(triangles, work.deleted_triangles());
        changed = changed || pass_changed;
        if (!pass_changed) break;
        adjacency_is_current = pass + 1 < kMaxPasses;  // the last pass's collapses are not patched in
        if (adjacency_is_current) {
            std::vector<uint8_t> claimed(claim.size());
            for (std::size_t v = 0; v < claim.size(); ++v) claimed[v] = claim[v] >= pass_first_stamp;
            adj = patch_adjacency(adj, work, triangles, claimed, threads);
        }
    }
    if (changed) {
        claim = std::vector<int32_t>();
        // compact_into replaces the mesh's positions and triangles without reading them: release them first, so
        // that the working arrays and the adjacency handed over do not raise the memory peak.
        mesh.vertices = std::vector<float>();
        mesh.triangles = std::vector<int32_t>();
        const std::vector<int32_t> new_index = compact_into(mesh, triangles, positions, removed, nullptr, threads);
        if (final_adjacency && adjacency_is_current) renumber_adjacency(adj, new_index);
    }
    if (final_adjacency && adjacency_is_current) *final_adjacency = std::move(adj);
    return removed_configurations;
}

std::size_t mesh_cleanup(TriMesh& mesh, double cube_edge, double snap_distance, int threads) {
    validate_mesh_arrays(mesh, "mesh_cleanup");
    if (!(cube_edge > 0.0) || !std::isfinite(cube_edge))
        throw InputError("mesh_cleanup: cube_edge must be positive and finite, got " + std::to_string(cube_edge));
    if (!std::isfinite(snap_distance))
        throw InputError("mesh_cleanup: snap_distance must be finite (negative for no limit), got " + std::to_string(snap_distance));
    threads = resolve_threads(threads);
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    if (nv == 0 || mesh.triangles.empty()) return 0;

    std::vector<int32_t> triangles = mesh.triangles;
    std::vector<float> positions = mesh.vertices;
    std::vector<uint8_t> removed(static_cast<std::size_t>(nv), 0);

    // Nearest lattice point of every vertex (lattice of spacing cube_edge anchored at the origin) and whether the
    // vertex takes part. A merged vertex sits at the mean of vertices sharing its lattice point, which lies in the
    // same lattice cell (and within the same snap ball), so keys and eligibility never need updating.
    std::vector<LatticeKey> key(static_cast<std::size_t>(nv));
    std::vector<uint8_t> eligible(static_cast<std::size_t>(nv), 0);
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            double d2 = 0.0;
            bool usable = true;
            for (int k = 0; k < 3; ++k) {
                const double x = positions[3 * v + k] / cube_edge;
                usable = usable && std::isfinite(x) && std::fabs(x) < 1e9;  // lattice index must fit in 32 bits
                const double r = usable ? std::nearbyint(x) : 0.0;
                key[v].k[k] = static_cast<int32_t>(r);
                d2 += (x - r) * (x - r);
            }
            eligible[v] = usable && (snap_distance < 0.0 || std::sqrt(d2) <= snap_distance);
        }
    });

    TriMesh view;
    view.vertices.swap(positions);
    view.triangles.swap(triangles);
    const MeshAdjacency adj = build_adjacency(view, threads);
    positions.swap(view.vertices);
    triangles.swap(view.triangles);

    // Only vertices with an eligible neighbour on the same lattice point can ever merge (merging never creates
    // a new same-key pair that was not already adjacent to one of the merged vertices).
    std::vector<int32_t> active;
    {
        std::vector<uint8_t> flag(static_cast<std::size_t>(nv), 0);
        parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t v = begin; v < end; ++v) {
                if (!eligible[v]) continue;
                for (int64_t k = adj.vertex_neighbours.begin(v); k < adj.vertex_neighbours.end(v); ++k) {
                    const int32_t u = adj.vertex_neighbours.items[k];
                    if (eligible[u] && key[u] == key[v]) { flag[v] = 1; break; }
                }
            }
        });
        for (int64_t v = 0; v < nv; ++v)
            if (flag[v]) active.push_back(static_cast<int32_t>(v));
    }

    CollapseMesh work(triangles, positions, adj.vertex_triangles, removed);
    // Sum of the original positions merged into each vertex (and their count), for the running average.
    std::vector<double> sum(3 * static_cast<std::size_t>(nv));
    std::vector<int32_t> count(static_cast<std::size_t>(nv), 1);
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] = positions[i];

    // Incremental merging around each active vertex v, in index order: collapse a same-key neighbour u into v
    // with v moving to the mean of everything merged so far, then rescan v's (changed) ring. `pending` marks the
    // vertices that still have a same-key neighbour they could not merge (refused, or outside the current tile);
    // only those are visited again.
    std::vector<uint8_t> pending(static_cast<std::size_t>(nv), 0);
    for (int32_t v : active) pending[v] = 1;
    struct Buffers {
        Scratch s;
        std::vector<int32_t> fan, ring;
    };
    auto merge_around = [&](const int32_t* list, std::size_t n, Buffers& b, const auto& region) {
        std::size_t merged_here = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const int32_t v = list[i];
            if (removed[v] || !pending[v]) continue;
            bool merged = true, refused = false;
            while (merged) {
                merged = refused = false;
                work.fan(v, b.fan);
                work.neighbours(v, b.fan, b.ring);
                for (int32_t u : b.ring) {
                    // Same key implies same tile, so u's state belongs to this task too.
                    if (!eligible[u] || !(key[u] == key[v])) continue;
                    const double total = double(count[v]) + double(count[u]);
                    const float target[3] = {static_cast<float>((sum[3 * v] + sum[3 * u]) / total),
                                             static_cast<float>((sum[3 * v + 1] + sum[3 * u + 1]) / total),
                                             static_cast<float>((sum[3 * v + 2] + sum[3 * u + 2]) / total)};
                    if (!work.try_collapse(u, v, target, b.s, region)) {
                        refused = true;
                        continue;
                    }
                    for (int k = 0; k < 3; ++k) sum[3 * v + k] += sum[3 * u + k];
                    count[v] += count[u];
                    ++merged_here;
                    merged = true;
                    break;
                }
            }
            pending[v] = refused ? 1 : 0;
        }
        return merged_here;
    };

    // Parallel phases: the lattice is tiled into blocks of kTile^3 lattice points; each block's active vertices
    // are processed by one task with collapses confined to the block (see try_collapse), so blocks are
    // independent and the result does not depend on the thread count. Collapses that straddle a block border
    // are retried with the tiling shifted by half a block, and whatever still straddles is done sequentially.
    constexpr int kTileShift = 4;  // tiles of 16 lattice points: fans span 1-2 points, so few straddle
    struct Tiling {
        int32_t offset;
        std::vector<int32_t> order;                     // active vertices grouped by tile, index order within
        std::vector<std::pair<int64_t, int64_t>> runs;  // [begin, end) in order per tile
    };
    auto tile_of = [&](int32_t v, int32_t offset) {
        // Arithmetic shift floors negative coordinates too; packing may alias far-apart tiles, which only merges
        // their work into one task (still isolated from all other tasks).
        uint64_t code = 0;
        for (int k = 0; k < 3; ++k)
            code = (code << 21) | (static_cast<uint64_t>((static_cast<int64_t>(key[v].k[k]) + offset) >> kTileShift) & 0x1FFFFFu);
        return code;
    };
    std::vector<Tiling> tilings;
    for (int32_t offset : {0, 1 << (kTileShift - 1)}) {
        Tiling tiling{offset, {}, {}};
        std::vector<std::pair<uint64_t, int32_t>> items(active.size());
        parallel_blocks(static_cast<int64_t>(active.size()), threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) items[i] = {tile_of(active[i], offset), active[i]};
        });
        std::sort(items.begin(), items.end());
        tiling.order.resize(items.size());
        for (std::size_t i = 0; i < items.size(); ++i) {
            tiling.order[i] = items[i].second;
            if (i == 0 || items[i].first != items[i - 1].first) tiling.runs.emplace_back(static_cast<int64_t>(i), 0);
            tiling.runs.back().second = static_cast<int64_t>(i + 1);
        }
        tilings.push_back(std::move(tiling));
    }

    std::size_t collapsed = 0;
    constexpr int kMaxPasses = 5;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        std::size_t pass_collapsed = 0;
        for (const Tiling& tiling : tilings) {
            std::vector<std::size_t> per_run(tiling.runs.size(), 0);
            parallel_blocks(static_cast<int64_t>(tiling.runs.size()), threads, 1, [&](int64_t begin, int64_t end) {
                Buffers b;
                for (int64_t r = begin; r < end; ++r) {
                    const auto run = tiling.runs[r];
                    const uint64_t tile = tile_of(tiling.order[run.first], tiling.offset);
                    const auto in_tile = [&](int32_t w) { return tile_of(w, tiling.offset) == tile; };
                    per_run[r] = merge_around(tiling.order.data() + run.first, static_cast<std::size_t>(run.second - run.first), b, in_tile);
                }
            });
            for (std::size_t n : per_run) pass_collapsed += n;
        }
        Buffers b;
        pass_collapsed += merge_around(active.data(), active.size(), b, anywhere);
        collapsed += pass_collapsed;
        if (pass_collapsed == 0) break;
    }
    if (collapsed == 0) return 0;
    drop_deleted_triangles(triangles, work.deleted_triangles());
    compact_into(mesh, triangles, positions, removed, &work.group_next(), threads);
    return collapsed;
}

}  // namespace meniscus
