// The small geometry that mesh algorithms share: 3-vectors in double and the triangle measures built from them.
// Positions are stored as float; every measure converts them to double first, so that differences of nearby
// vertices far from the origin keep their digits and a product of differences does not overflow.
#pragma once
#include <cmath>
#include <cstdint>

namespace meniscus {

struct Vec3d {
    double x = 0.0, y = 0.0, z = 0.0;
};

inline Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double length(Vec3d a) { return std::sqrt(dot(a, a)); }
inline bool is_zero(Vec3d a) { return a.x == 0.0 && a.y == 0.0 && a.z == 0.0; }

// A stored float position (3 floats) as a double vector.
inline Vec3d to_vec3d(const float* p) { return {p[0], p[1], p[2]}; }
// Vertex v of a flat position array (3 floats per vertex).
inline Vec3d vertex_position(const float* vertices, int32_t v) { return to_vec3d(vertices + 3 * static_cast<int64_t>(v)); }

// (b - a) x (c - a): along the normal of triangle (a, b, c) (counter-clockwise seen from where it points), with
// twice the triangle's area as its length.
inline Vec3d triangle_cross(const float* a, const float* b, const float* c) {
    const Vec3d pa = to_vec3d(a);
    return cross(to_vec3d(b) - pa, to_vec3d(c) - pa);
}
// The same for triangle t (3 vertex indices) of a flat position array.
inline Vec3d triangle_cross(const float* vertices, const int32_t* t) {
    return triangle_cross(vertices + 3 * static_cast<int64_t>(t[0]), vertices + 3 * static_cast<int64_t>(t[1]),
                          vertices + 3 * static_cast<int64_t>(t[2]));
}

// Signed volume of the tetrahedron spanned by a, b and c from the origin, a . (b x c) / 6, written as the
// determinant's expansion along a. Summed over the triangles of a closed oriented surface (corners taken relative
// to any fixed point) it is the enclosed volume (divergence theorem).
inline double tetrahedron_volume(Vec3d a, Vec3d b, Vec3d c) {
    return (a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x)) / 6.0;
}

}  // namespace meniscus
