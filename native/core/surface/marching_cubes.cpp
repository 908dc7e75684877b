#include "surface/marching_cubes.h"

#include <stdexcept>
#include <vector>

#include "mesh/geometry.h"

namespace meniscus {
namespace mc {

namespace {

Vec3d corner_position(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

std::array<Edge, 12> make_edges() {
    std::array<Edge, 12> result{};
    for (int axis = 0; axis < 3; ++axis) {
        int n = 0;
        for (int c = 0; c < 8; ++c)
            if (!((c >> axis) & 1)) result[4 * axis + n++] = {c, axis};
    }
    return result;
}

int edge_between(int a, int b) {
    if (a > b) std::swap(a, b);
    const int diff = a ^ b;
    const int axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
    const auto& all = edges();
    for (int e = 4 * axis; e < 4 * axis + 4; ++e)
        if (all[e].corner == a) return e;
    throw std::logic_error("marching cubes: corners are not adjacent");
}

// Two cube edges lie on a common face when they share a corner or are parallel on one face.
bool edges_share_face(int a, int b) {
    const Edge& ea = edges()[a];
    const Edge& eb = edges()[b];
    for (int face = 0; face < 6; ++face) {
        const int axis = face / 2, side = face % 2;
        auto on_face = [&](const Edge& e) { return e.axis != axis && ((e.corner >> axis) & 1) == side; };
        if (on_face(ea) && on_face(eb)) return true;
    }
    return false;
}

Vec3d edge_midpoint(int e) {
    const Edge& edge = edges()[e];
    Vec3d p = corner_position(edge.corner);
    (edge.axis == 0 ? p.x : edge.axis == 1 ? p.y : p.z) += 0.5;
    return p;
}

Case build_case(unsigned inside, unsigned joined) {
    auto is_in = [&](int c) { return ((inside >> c) & 1u) != 0; };
    std::array<int, 12> next;
    next.fill(-1);
    for (int face = 0; face < 6; ++face) {
        const int axis = face / 2, side = face % 2;
        Vec3d normal{0, 0, 0};
        (axis == 0 ? normal.x : axis == 1 ? normal.y : normal.z) = side ? 1.0 : -1.0;
        const auto& c = face_corners(face);
        // Cyclic edges of the face: E0 = c0-c1, E1 = c1-c2, E2 = c2-c3, E3 = c3-c0.
        int cyclic_edges[4];
        for (int i = 0; i < 4; ++i) cyclic_edges[i] = edge_between(c[i], c[(i + 1) % 4]);
        // Segments as (edge, edge, corner cut off by the segment).
        struct Segment {
            int a, b, cut_corner;
        };
        std::vector<Segment> segments;
        const bool ambiguous = face_is_ambiguous(is_in(c[0]), is_in(c[1]), is_in(c[2]), is_in(c[3]));
        if (ambiguous) {
            const bool join = ((joined >> face) & 1u) != 0;
            // Cut off corners c0 and c2, or c1 and c3: c0/c2 are cut when they are inside and kept apart, or outside
            // while the inside corners (c1, c3) are joined.
            const bool cut_even = is_in(c[0]) ? !join : join;
            if (cut_even) {
                segments.push_back({cyclic_edges[3], cyclic_edges[0], c[0]});
                segments.push_back({cyclic_edges[1], cyclic_edges[2], c[2]});
            } else {
                segments.push_back({cyclic_edges[0], cyclic_edges[1], c[1]});
                segments.push_back({cyclic_edges[2], cyclic_edges[3], c[3]});
            }
        } else {
            int changing[2], count = 0;
            for (int i = 0; i < 4; ++i)
                if (is_in(c[i]) != is_in(c[(i + 1) % 4])) changing[count++] = i;
            if (count == 2) {
                // Reference corner: the start corner of the first changing edge; the orientation test below works
                // with any corner, inside or outside, that is not on the segment.
                segments.push_back({cyclic_edges[changing[0]], cyclic_edges[changing[1]], c[changing[0]]});
            }
        }
        for (const Segment& s : segments) {
            const Vec3d p = edge_midpoint(s.a), q = edge_midpoint(s.b);
            const double side_of_corner = dot(cross(normal, q - p), corner_position(s.cut_corner) - p);
            // Seen from outside the cube, inside corners lie to the right of a segment's direction.
            const bool corner_on_right = side_of_corner < 0.0;
            const bool forward = corner_on_right == is_in(s.cut_corner);
            const int from = forward ? s.a : s.b, to = forward ? s.b : s.a;
            if (next[from] != -1) throw std::logic_error("marching cubes: inconsistent face segments");
            next[from] = to;
        }
    }
    Case result;
    bool visited[12] = {};
    for (int start = 0; start < 12; ++start) {
        if (next[start] == -1 || visited[start]) continue;
        std::vector<int> loop;
        for (int e = start; !visited[e]; e = next[e]) {
            if (e < 0) throw std::logic_error("marching cubes: open loop");
            visited[e] = true;
            loop.push_back(e);
        }
        const int n = static_cast<int>(loop.size());
        auto add = [&](int a, int b, int c) {
            const int t = result.triangle_count++;
            result.edges[3 * t + 0] = static_cast<int8_t>(a);
            result.edges[3 * t + 1] = static_cast<int8_t>(b);
            result.edges[3 * t + 2] = static_cast<int8_t>(c);
        };
        int apex = -1;
        for (int i = 0; i < n && apex < 0; ++i) {
            bool valid = true;
            for (int k = 2; k + 1 < n && valid; ++k)
                if (edges_share_face(loop[i], loop[(i + k) % n])) valid = false;
            if (valid) apex = i;
        }
        if (apex >= 0) {
            for (int k = 1; k + 1 < n; ++k) add(loop[apex], loop[(apex + k) % n], loop[(apex + k + 1) % n]);
        } else {
            if (result.centre_count >= kMaxCentres) throw std::logic_error("marching cubes: too many loop centres");
            uint16_t members = 0;
            for (int e : loop) members = static_cast<uint16_t>(members | (1u << e));
            const int centre = 12 + result.centre_count;
            result.centre_loops[result.centre_count++] = members;
            for (int k = 0; k < n; ++k) add(centre, loop[k], loop[(k + 1) % n]);
        }
    }
    return result;
}

struct Table {
    std::vector<Case> cases;         // 256 * 64
    std::array<uint8_t, 256> ambiguous_faces;
    Table() : cases(256 * 64) {
        for (unsigned inside = 0; inside < 256; ++inside) {
            unsigned mask = 0;
            for (int face = 0; face < 6; ++face) {
                const auto& c = face_corners(face);
                auto in = [&](int k) { return ((inside >> c[k]) & 1u) != 0; };
                if (face_is_ambiguous(in(0), in(1), in(2), in(3))) mask |= 1u << face;
            }
            ambiguous_faces[inside] = static_cast<uint8_t>(mask);
            for (unsigned joined = 0; joined < 64; ++joined)
                if ((joined & ~mask) == 0) cases[inside * 64 + joined] = build_case(inside, joined);
        }
    }
};

const Table& table() {
    static const Table instance;
    return instance;
}

}  // namespace

const std::array<Edge, 12>& edges() {
    static const std::array<Edge, 12> instance = make_edges();
    return instance;
}

const std::array<int, 4>& face_corners(int face) {
    static const std::array<std::array<int, 4>, 6> instance = [] {
        std::array<std::array<int, 4>, 6> result{};
        for (int face = 0; face < 6; ++face) {
            const int axis = face / 2, side = face % 2;
            const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
            const int base = side << axis;
            result[face] = {base, base | (1 << u), base | (1 << u) | (1 << v), base | (1 << v)};
        }
        return result;
    }();
    return instance[face];
}

const Case& lookup(unsigned inside, unsigned joined) {
    const Table& t = table();
    return t.cases[inside * 64 + (joined & t.ambiguous_faces[inside])];
}

}  // namespace mc
}  // namespace meniscus
