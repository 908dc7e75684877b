#include "post/quads.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "base/numbers.h"
#include "base/parallel.h"

namespace meniscus {

namespace {

using Vec = std::array<double, 3>;

Vec position(const TriMesh& mesh, int32_t v) {
    const float* p = &mesh.vertices[3 * static_cast<std::size_t>(v)];
    return {p[0], p[1], p[2]};
}
Vec minus(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double length(const Vec& a) { return std::sqrt(dot(a, a)); }

double angle_degrees(const Vec& a, const Vec& b) {
    const double la = length(a), lb = length(b);
    if (la == 0.0 || lb == 0.0) return 180.0;
    return std::acos(std::max(-1.0, std::min(1.0, dot(a, b) / (la * lb)))) * (180.0 / kPi);
}

// One directed edge of a triangle: its undirected key, the triangle and which of its edges it is.
struct EdgeSide {
    uint64_t key;
    int32_t triangle;
    int32_t corner;  // the edge runs from corner to corner + 1
};

struct Candidate {
    double score;  // the largest deviation of a corner from a right angle, in degrees: smaller is better
    uint64_t key;
    int32_t first, second;
    std::array<int32_t, 4> quad;
};

// The quad two triangles sharing the edge (a, b) make, in the first triangle's winding: t1 = a b c, t2 = b a d
// give a d b c. Nothing when it fails the criteria.
bool evaluate(const TriMesh& mesh, const EdgeSide& s1, const EdgeSide& s2, const QuadCriteria& criteria, Candidate& out) {
    const int32_t* t1 = &mesh.triangles[3 * static_cast<std::size_t>(s1.triangle)];
    const int32_t* t2 = &mesh.triangles[3 * static_cast<std::size_t>(s2.triangle)];
    const int32_t a = t1[s1.corner], b = t1[(s1.corner + 1) % 3], c = t1[(s1.corner + 2) % 3];
    const int32_t d = t2[(s2.corner + 2) % 3];
    if (t2[s2.corner] != b || t2[(s2.corner + 1) % 3] != a) return false;  // not oppositely wound: not oriented
    if (c == d) return false;
    const std::array<int32_t, 4> quad{a, d, b, c};
    const Vec pa = position(mesh, a), pb = position(mesh, b), pc = position(mesh, c), pd = position(mesh, d);
    if (angle_degrees(cross(minus(pb, pa), minus(pc, pa)), cross(minus(pa, pb), minus(pd, pb))) > criteria.max_normal_angle)
        return false;
    const std::array<Vec, 4> corners{pa, pd, pb, pc};
    const double diagonals[2] = {length(minus(pb, pa)), length(minus(pc, pd))};
    if (diagonals[0] == 0.0 || diagonals[1] == 0.0) return false;
    double score = 0.0;
    for (int k = 0; k < 4; ++k) {
        const Vec& here = corners[k];
        const Vec next = minus(corners[(k + 1) % 4], here), previous = minus(corners[(k + 3) % 4], here);
        const double angle = angle_degrees(next, previous);
        if (angle > criteria.max_interior_angle) return false;
        score = std::max(score, std::fabs(angle - 90.0));
        for (double diagonal : diagonals) {
            const double ratio = length(next) / diagonal;
            if (ratio > criteria.max_edge_diagonal_ratio || ratio * criteria.max_edge_diagonal_ratio < 1.0) return false;
        }
    }
    out = {score, s1.key, s1.triangle, s2.triangle, quad};
    return true;
}

}  // namespace

std::size_t merge_triangles_into_quads(TriMesh& mesh, const QuadCriteria& criteria, int threads) {
    const std::size_t triangle_count = mesh.num_triangles();
    std::vector<EdgeSide> sides;
    sides.reserve(3 * triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const int32_t* tri = &mesh.triangles[3 * t];
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
        for (int32_t k = 0; k < 3; ++k) {
            const uint64_t a = static_cast<uint32_t>(tri[k]), b = static_cast<uint32_t>(tri[(k + 1) % 3]);
            sides.push_back({std::min(a, b) << 32 | std::max(a, b), static_cast<int32_t>(t), k});
        }
    }
    std::sort(sides.begin(), sides.end(), [](const EdgeSide& x, const EdgeSide& y) {
        return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
    });
    // Interior edges: exactly two sides with the same key.
    std::vector<std::size_t> pairs;
    for (std::size_t i = 0; i < sides.size();) {
        std::size_t j = i + 1;
        while (j < sides.size() && sides[j].key == sides[i].key) ++j;
        if (j - i == 2) pairs.push_back(i);
        i = j;
    }
    std::vector<Candidate> evaluated(pairs.size());
    std::vector<uint8_t> valid(pairs.size(), 0);
    parallel_for(static_cast<int64_t>(pairs.size()), threads, [&](int64_t p) {
        valid[p] = evaluate(mesh, sides[pairs[p]], sides[pairs[p] + 1], criteria, evaluated[p]);
    }, 1024);
    std::vector<Candidate> candidates;
    for (std::size_t p = 0; p < pairs.size(); ++p)
        if (valid[p]) candidates.push_back(evaluated[p]);
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
        return x.score != y.score ? x.score < y.score : x.key < y.key;
    });
    // Greedy, best first: a triangle joins at most one quad.
    std::vector<uint8_t> merged(triangle_count, 0);
    std::vector<int32_t> quads;
    for (const Candidate& c : candidates) {
        if (merged[c.first] || merged[c.second]) continue;
        merged[c.first] = merged[c.second] = 1;
        quads.insert(quads.end(), c.quad.begin(), c.quad.end());
    }
    std::vector<int32_t> kept;
    kept.reserve(mesh.triangles.size() - 6 * (quads.size() / 4));
    for (std::size_t t = 0; t < triangle_count; ++t)
        if (!merged[t]) kept.insert(kept.end(), mesh.triangles.begin() + 3 * t, mesh.triangles.begin() + 3 * t + 3);
    mesh.triangles.swap(kept);
    mesh.quads.insert(mesh.quads.end(), quads.begin(), quads.end());
    return quads.size() / 4;
}

}  // namespace meniscus
