// Half-edge collapses on a working copy of a mesh, the one operation of barnacle decimation (decimation.h) and
// mesh cleanup (mesh_cleanup.h). A collapse n -> c makes vertex n disappear: its triangles are re-attached to c and
// the two triangles of edge (n, c) are deleted. It is only made when it is legal:
//   - n and c each have a closed disk fan and the edge (n, c) has exactly two triangles of opposite direction
//     (so non-manifold or open input is left alone where it is broken, never made worse);
//   - link condition: n and c share exactly the two neighbours opposite the edge (no fold-over, no duplicate
//     triangles, the mesh stays a closed 2-manifold);
//   - no vertex drops below valence 3 (this also refuses to collapse a tetrahedron);
//   - no re-attached triangle becomes degenerate (zero area) or turns its normal by 90 degrees or more.
//
// Triangles are rewritten in place and flagged when deleted; a vertex's current fan is the union of the static CSR
// rows of the vertices merged into it (a singly linked "group" list), so no per-vertex containers are allocated
// and a collapse costs O(fan sizes).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "base/parallel.h"
#include "base/short_sort.h"
#include "base/uninitialized_vector.h"
#include "mesh/adjacency.h"
#include "mesh/geometry.h"
#include "mesh/mesh.h"

namespace meniscus {

// Buffers one thread reuses across collapses.
struct CollapseScratch {
    std::vector<int32_t> fan_n, fan_c, ring_n, ring_c, fan_tmp, ring_tmp, successor;
};

// Region predicate that accepts every vertex (sequential or otherwise isolated work).
struct Anywhere {
    bool operator()(int32_t) const { return true; }
};
constexpr Anywhere anywhere{};

class CollapseMesh {
public:
    // `triangles` and `positions` are the working arrays (edited in place); `vt` is the vertex -> triangle CSR of
    // `triangles` at construction; `removed` flags vertices already collapsed away (kept across rebuilds).
    CollapseMesh(std::vector<int32_t>& triangles, std::vector<float>& positions, const CsrList& vt, std::vector<uint8_t>& removed,
                 int threads = 1)
        : tris_(triangles), pos_(positions), vt_(vt), removed_(removed) {
        const int64_t nv = static_cast<int64_t>(positions.size() / 3);
        fill_in_parallel(deleted_, triangles.size() / 3, uint8_t{0}, threads);
        next_.resize(static_cast<std::size_t>(nv));
        tail_.resize(static_cast<std::size_t>(nv));
        parallel_blocks(nv, threads, 1 << 14, [&](int64_t begin, int64_t end) {
            for (int64_t v = begin; v < end; ++v) next_[v] = -1, tail_[v] = static_cast<int32_t>(v);
        });
    }

    const UninitializedVector<uint8_t>& deleted_triangles() const { return deleted_; }
    // Per vertex, the next vertex merged into the same survivor (-1: last), starting from the survivor itself.
    const UninitializedVector<int32_t>& group_next() const { return next_; }

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
        sort_short(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    int32_t valence(int32_t v, CollapseScratch& s) const {
        fan(v, s.fan_tmp);
        neighbours(v, s.fan_tmp, s.ring_tmp);
        return static_cast<int32_t>(s.ring_tmp.size());
    }

    // Half-edge collapse n -> c; c moves to `target` when given. Returns false (and changes nothing) when the
    // collapse is not legal. With a `region` predicate, the collapse is also refused unless n, c and every
    // vertex of their fans belong to the region: the collapse then reads and writes only triangles whose corners
    // are all in the region and vertices of the region, so disjoint regions can be processed concurrently
    // (n and c must be known to be in the region before the call: their flags are read first).
    template <class Region>
    bool try_collapse(int32_t n, int32_t c, const float* target, CollapseScratch& s, const Region& region) {
        if (n == c || removed_[n] || removed_[c]) return false;
        fan(n, s.fan_n);
        fan(c, s.fan_c);
        for (const std::vector<int32_t>* f : {&s.fan_n, &s.fan_c})
            for (int32_t t : *f)
                for (int k = 0; k < 3; ++k)
                    if (!region(tri(t)[k])) return false;
        EdgeFans edge;
        if (!find_edge_fans(n, c, s.fan_n, edge) || !topology_allows(n, c, edge, s)) return false;
        const float* p = target ? target : position(c);
        const bool c_moves = target && (p[0] != position(c)[0] || p[1] != position(c)[1] || p[2] != position(c)[2]);
        if (!geometry_allows(n, c, p, c_moves, edge, s)) return false;
        apply(n, c, p, c_moves, edge, s);
        return true;
    }

private:
    // The two triangles of edge (n, c) and the vertex opposite the edge in each.
    struct EdgeFans {
        int32_t triangles[2] = {-1, -1};
        int32_t opposite[2] = {-1, -1};
        bool contains(int32_t t) const { return t == triangles[0] || t == triangles[1]; }
    };

    const int32_t* tri(int32_t t) const { return tris_.data() + 3 * static_cast<int64_t>(t); }
    int32_t* tri(int32_t t) { return tris_.data() + 3 * static_cast<int64_t>(t); }
    const float* position(int32_t v) const { return pos_.data() + 3 * static_cast<int64_t>(v); }

    // Exactly two triangles of n's fan contain edge (n, c), in opposite directions, with different opposite
    // vertices; no triangle of the fan repeats an index.
    bool find_edge_fans(int32_t n, int32_t c, const std::vector<int32_t>& fan_n, EdgeFans& edge) const {
        int count = 0, direction = 0;
        for (int32_t t : fan_n) {
            const int32_t* p = tri(t);
            if (has_repeated_index(p)) return false;
            const int kn = corner_of(p, n);
            const int32_t next = p[(kn + 1) % 3], prev = p[(kn + 2) % 3];
            if (next != c && prev != c) continue;
            if (count == 2) return false;  // non-manifold edge
            edge.triangles[count] = t;
            edge.opposite[count] = next == c ? prev : next;
            direction += next == c ? 1 : -1;
            ++count;
        }
        return count == 2 && direction == 0 && edge.opposite[0] != edge.opposite[1];
    }

    // Both fans are closed disks, the link condition holds and every valence stays at 3 or more.
    bool topology_allows(int32_t n, int32_t c, const EdgeFans& edge, CollapseScratch& s) const {
        neighbours(n, s.fan_n, s.ring_n);
        neighbours(c, s.fan_c, s.ring_c);
        if (!closed_disk(n, s.fan_n, s.ring_n, s) || !closed_disk(c, s.fan_c, s.ring_c, s)) return false;
        // Link condition: the common neighbours are exactly the two opposite vertices (both are common).
        std::size_t common = 0;
        for (std::size_t i = 0, j = 0; i < s.ring_n.size() && j < s.ring_c.size();) {
            if (s.ring_n[i] < s.ring_c[j]) ++i;
            else if (s.ring_c[j] < s.ring_n[i]) ++j;
            else { ++common; ++i; ++j; }
        }
        if (common != 2) return false;
        // Valences afterwards: c gets the union of both rings minus {n, c}; each opposite vertex loses n.
        if (static_cast<int64_t>(s.ring_n.size() + s.ring_c.size()) - 4 < 3) return false;
        for (int32_t x : edge.opposite)
            if (valence(x, s) < 4) return false;
        return true;
    }

    // Every triangle that keeps existing and moves (n's, re-attached to c at p; c's, when c moves to p) stays
    // non-degenerate and does not flip.
    bool geometry_allows(int32_t n, int32_t c, const float* p, bool c_moves, const EdgeFans& edge, const CollapseScratch& s) const {
        for (int32_t t : s.fan_n)
            if (!edge.contains(t) && !moves_well(t, n, p)) return false;
        if (c_moves)
            for (int32_t t : s.fan_c)
                if (!edge.contains(t) && !moves_well(t, c, p)) return false;
        return true;
    }

    void apply(int32_t n, int32_t c, const float* p, bool c_moves, const EdgeFans& edge, const CollapseScratch& s) {
        deleted_[edge.triangles[0]] = deleted_[edge.triangles[1]] = 1;
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
    }

    // The fan of v is a closed disk: as many triangles as neighbours, and the link edges next(v) -> prev(v)
    // form one cycle through all neighbours.
    bool closed_disk(int32_t v, const std::vector<int32_t>& fan, const std::vector<int32_t>& ring, CollapseScratch& s) const {
        const std::size_t k = ring.size();
        if (fan.size() != k || k < 3) return false;
        s.successor.assign(k, -1);
        auto local = [&](int32_t u) { return static_cast<int32_t>(std::lower_bound(ring.begin(), ring.end(), u) - ring.begin()); };
        for (int32_t t : fan) {
            const int32_t* p = tri(t);
            if (has_repeated_index(p)) return false;
            const int kv = corner_of(p, v);
            const int32_t a = local(p[(kv + 1) % 3]);
            if (s.successor[a] != -1) return false;
            s.successor[a] = local(p[(kv + 2) % 3]);
        }
        int32_t cur = 0;
        for (std::size_t i = 1; i <= k; ++i) {
            cur = s.successor[cur];
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
        const Vec3d n0 = triangle_cross(before[0], before[1], before[2]);
        const Vec3d n1 = triangle_cross(after[0], after[1], after[2]);
        if (is_zero(n1)) return false;
        if (!std::isfinite(n1.x + n1.y + n1.z)) return false;
        if (is_zero(n0)) return true;  // was degenerate: no orientation to keep
        return dot(n0, n1) > 0.0;
    }

    std::vector<int32_t>& tris_;
    std::vector<float>& pos_;
    const CsrList& vt_;
    std::vector<uint8_t>& removed_;
    // Filled in parallel (a pass's arrays are ~25 MB at a million particles).
    UninitializedVector<uint8_t> deleted_;
    UninitializedVector<int32_t> next_, tail_;  // group lists: vertices merged into a vertex, in merge order
};

// The adjacency of working arrays (removed vertices simply have no triangles), built without copying them.
MeshAdjacency working_adjacency(std::vector<int32_t>& triangles, std::vector<float>& positions, int threads);

// Drops deleted triangles from the working triangle array.
void drop_deleted_triangles(std::vector<int32_t>& triangles, const UninitializedVector<uint8_t>& deleted, int threads);

// Writes the working arrays back into mesh without the removed vertices. With group lists (cleanup), every
// surviving vertex's normal and attributes become the mean over the original vertices merged into it, like its
// position; without them (barnacles: the centre stays where it is) the survivor keeps its own values.
// Returns the new index of every old vertex (-1: removed). positions is consumed (the vertices are compacted in it
// when few were removed).
UninitializedVector<int32_t> compact_into(TriMesh& mesh, std::vector<int32_t>& triangles, std::vector<float>& positions,
                                          const std::vector<uint8_t>& removed, const UninitializedVector<int32_t>* group_next, int threads);

}  // namespace meniscus
