// Marching-cubes case table, generated at start-up rather than typed in: for each of the 256 corner sign
// configurations and each choice on the ambiguous faces, the surface is built face by face (one segment per
// pair of sign-changing edges) and the segments are chained into loops and fanned into triangles. Because a
// face's segments depend only on that face's four corners (and the asymptotic decider on those corners'
// values), neighbouring cubes always agree: the mesh is closed and 2-manifold by construction.
//
// Conventions: corner c sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1). Edge e = 4 * axis + n runs along
// `axis` from the n-th corner (in increasing index order) whose `axis` bit is 0. Face f = 2 * axis + side.
#pragma once
#include <array>
#include <cstdint>

namespace meniscus {
namespace mc {

struct Edge {
    int corner;  // start corner (its `axis` bit is 0)
    int axis;
};
const std::array<Edge, 12>& edges();

// Canonical corners of face f in the order (u0v0, u1v0, u1v1, u0v1), u < v being the two other axes.
const std::array<int, 4>& face_corners(int face);

// A loop whose every fan would put a diagonal on a cube face gets an extra vertex at the mean of its edge
// vertices: two cubes sharing a face could otherwise both connect the same two vertices, giving an edge with four
// triangles.
constexpr int kMaxCentres = 4;
struct Case {
    uint8_t triangle_count = 0;
    // 3 entries per triangle, counter-clockwise seen from outside: 0-11 are edge vertices, 12 + k the centre of
    // loop k in `centre_loops`.
    std::array<int8_t, 48> edges{};
    uint8_t centre_count = 0;
    std::array<uint16_t, kMaxCentres> centre_loops{};  // bit e set: edge e's vertex belongs to the loop
};

// `inside`: bit c set when corner c is inside. `joined`: bit f set when the two inside corners of ambiguous face f
// are connected through the face (asymptotic decider); ignored for faces that are not ambiguous.
const Case& lookup(unsigned inside, unsigned joined);

// Face ambiguity: a face whose diagonal corners agree and adjacent corners differ.
inline bool face_is_ambiguous(bool c00, bool c10, bool c11, bool c01) { return c00 == c11 && c10 == c01 && c00 != c10; }

// Asymptotic decider on a face with canonical corner values (see face_corners): true when the inside corners are
// connected, i.e. the bilinear interpolant's saddle value is above the threshold.
inline bool inside_corners_joined(float v00, float v10, float v11, float v01, float threshold) {
    const double denominator = double(v00) + double(v11) - double(v10) - double(v01);
    if (denominator == 0.0) return false;
    const double saddle = (double(v00) * double(v11) - double(v10) * double(v01)) / denominator;
    return saddle > double(threshold);
}

}  // namespace mc
}  // namespace meniscus
