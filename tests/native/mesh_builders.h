// What the native tests build their cases from, once: small meshes built in code (platonic spheres, cube, torus, a
// noisy sphere, a marching-tetrahedra mesh of an implicit function, irregular like marching cubes output: valence 3
// vertices, slivers next to grid points), editing helpers that plant the marching-cubes "barnacle" configurations,
// checks on meshes, and the shared particle frames with their parameters.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mesh/adjacency.h"
#include "mesh/geometry.h"
#include "mesh/mesh.h"
#include "parameters.h"

namespace meniscus {
namespace test {

using V3 = std::array<double, 3>;

inline V3 vertex_of(const TriMesh& m, int32_t v) { return {m.vertices[3 * v], m.vertices[3 * v + 1], m.vertices[3 * v + 2]}; }

inline int32_t add_vertex(TriMesh& m, V3 p) {
    for (double x : p) m.vertices.push_back(static_cast<float>(x));
    return static_cast<int32_t>(m.num_vertices() - 1);
}

inline void add_triangle(TriMesh& m, int32_t a, int32_t b, int32_t c) {
    m.triangles.push_back(a);
    m.triangles.push_back(b);
    m.triangles.push_back(c);
}

// Loop-free midpoint subdivision of a closed mesh, every vertex projected onto the sphere (centre, radius).
inline TriMesh subdivide_onto_sphere(TriMesh m, int levels, double radius, V3 centre) {
    auto project = [&](V3 p) {
        const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        return V3{p[0] / l, p[1] / l, p[2] / l};
    };
    std::vector<V3> unit;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) unit.push_back(project(vertex_of(m, static_cast<int32_t>(v))));
    std::vector<int32_t> tris = m.triangles;
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<int32_t, int32_t>, int32_t> midpoint;
        auto mid = [&](int32_t a, int32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = midpoint.find(key);
            if (it != midpoint.end()) return it->second;
            unit.push_back(project({unit[a][0] + unit[b][0], unit[a][1] + unit[b][1], unit[a][2] + unit[b][2]}));
            const int32_t id = static_cast<int32_t>(unit.size() - 1);
            midpoint.emplace(key, id);
            return id;
        };
        std::vector<int32_t> next;
        for (std::size_t t = 0; t < tris.size(); t += 3) {
            const int32_t a = tris[t], b = tris[t + 1], c = tris[t + 2];
            const int32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            for (int32_t x : {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca}) next.push_back(x);
        }
        tris.swap(next);
    }
    TriMesh out;
    for (const V3& u : unit) add_vertex(out, {centre[0] + radius * u[0], centre[1] + radius * u[1], centre[2] + radius * u[2]});
    out.triangles = tris;
    return out;
}

// Icosahedron subdivided `levels` times: 12 vertices of valence 5, all others 6.
inline TriMesh make_icosphere(int levels, double radius = 1.0, V3 centre = {0, 0, 0}) {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    TriMesh m;
    for (V3 p : {V3{-1, g, 0}, V3{1, g, 0}, V3{-1, -g, 0}, V3{1, -g, 0}, V3{0, -1, g}, V3{0, 1, g}, V3{0, -1, -g},
                 V3{0, 1, -g}, V3{g, 0, -1}, V3{g, 0, 1}, V3{-g, 0, -1}, V3{-g, 0, 1}})
        add_vertex(m, p);
    m.triangles = {0, 11, 5, 0, 5,  1,  0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
                   3, 9,  4, 3, 4,  2,  3, 2, 6, 3, 6,  8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
    return subdivide_onto_sphere(m, levels, radius, centre);
}

// Octahedron subdivided `levels` times: 6 vertices of valence 4 (on the axes), all others 6.
inline TriMesh make_octasphere(int levels, double radius = 1.0, V3 centre = {0, 0, 0}) {
    TriMesh m;
    for (V3 p : {V3{1, 0, 0}, V3{-1, 0, 0}, V3{0, 1, 0}, V3{0, -1, 0}, V3{0, 0, 1}, V3{0, 0, -1}}) add_vertex(m, p);
    m.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    return subdivide_onto_sphere(m, levels, radius, centre);
}

// Axis-aligned cube [0, size]^3, two triangles per face, outward counter-clockwise.
inline TriMesh make_cube(double size = 1.0) {
    TriMesh m;
    for (int c = 0; c < 8; ++c) add_vertex(m, {size * (c & 1), size * ((c >> 1) & 1), size * ((c >> 2) & 1)});
    m.triangles = {0, 2, 3, 0, 3, 1,   // z = 0 (normal -z)
                   4, 5, 7, 4, 7, 6,   // z = 1
                   0, 1, 5, 0, 5, 4,   // y = 0
                   2, 6, 7, 2, 7, 3,   // y = 1
                   0, 4, 6, 0, 6, 2,   // x = 0
                   1, 3, 7, 1, 7, 5};  // x = 1
    return m;
}

// Torus around the z axis (major radius R, minor r), nu x nv quads split into triangles.
inline TriMesh make_torus(double R, double r, int nu, int nv) {
    TriMesh m;
    const double pi = std::acos(-1.0);
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
            add_vertex(m, {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
        }
    auto id = [&](int i, int j) { return static_cast<int32_t>(((i + nu) % nu) * nv + (j + nv) % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            add_triangle(m, id(i, j), id(i + 1, j), id(i + 1, j + 1));
            add_triangle(m, id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    return m;
}

// Small deterministic generator (the tests must not depend on the standard library's distributions).
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed * 0x9E3779B97F4A7C15ull + 1) {}
    double uniform() {  // [0, 1)
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
    }
};

// Icosphere with every vertex moved radially by a uniform random amount in [-amplitude, amplitude].
inline TriMesh make_noisy_sphere(int levels, double radius, double amplitude, uint64_t seed = 1) {
    TriMesh m = make_icosphere(levels, radius);
    Rng rng(seed);
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const double f = 1.0 + amplitude * (2.0 * rng.uniform() - 1.0) / radius;
        for (int k = 0; k < 3; ++k) m.vertices[3 * v + k] = static_cast<float>(m.vertices[3 * v + k] * f);
    }
    return m;
}

inline void flip_orientation(TriMesh& m) {
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) std::swap(m.triangles[t + 1], m.triangles[t + 2]);
}

inline void append(TriMesh& m, const TriMesh& other) {
    const int32_t base = static_cast<int32_t>(m.num_vertices());
    m.vertices.insert(m.vertices.end(), other.vertices.begin(), other.vertices.end());
    for (int32_t i : other.triangles) m.triangles.push_back(base + i);
}

// Ordered one-ring of vertex h in a closed oriented manifold mesh (the order of the fan, counter-clockwise), and
// the indices of h's triangles.
inline std::vector<int32_t> ordered_ring(const TriMesh& m, int32_t h, std::vector<std::size_t>* fan = nullptr) {
    std::map<int32_t, int32_t> next;
    for (std::size_t t = 0; t < m.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k)
            if (m.triangles[3 * t + k] == h) {
                next[m.triangles[3 * t + (k + 1) % 3]] = m.triangles[3 * t + (k + 2) % 3];
                if (fan) fan->push_back(t);
            }
    std::vector<int32_t> ring{next.begin()->first};
    while (ring.size() < next.size()) ring.push_back(next.at(ring.back()));
    return ring;
}

inline void remove_triangles(TriMesh& m, std::vector<std::size_t> drop) {
    std::sort(drop.begin(), drop.end());
    std::vector<int32_t> kept;
    for (std::size_t t = 0, d = 0; t < m.num_triangles(); ++t) {
        if (d < drop.size() && drop[d] == t) {
            ++d;
            continue;
        }
        kept.insert(kept.end(), m.triangles.begin() + 3 * t, m.triangles.begin() + 3 * t + 3);
    }
    m.triangles.swap(kept);
}

// Replaces the star of h by an inner ring of `ring` vertices placed `scale` of the way towards the outer ring's
// edge midpoints, joined to the outer ring by a zig-zag strip (every inner vertex gets two outer neighbours,
// every outer vertex one more inner neighbour), and fills the inner ring with `fill`. This is how the barnacle
// configurations look in marching-cubes output: tiny triangles hugging a grid point.
inline std::vector<int32_t> replace_star(TriMesh& m, int32_t h, double scale) {
    std::vector<std::size_t> fan;
    const std::vector<int32_t> outer = ordered_ring(m, h, &fan);
    remove_triangles(m, fan);
    const V3 c = vertex_of(m, h);
    const std::size_t n = outer.size();
    std::vector<int32_t> inner(n);
    for (std::size_t i = 0; i < n; ++i) {
        const V3 a = vertex_of(m, outer[i]), b = vertex_of(m, outer[(i + 1) % n]);
        V3 p;
        for (int k = 0; k < 3; ++k) p[k] = c[k] + scale * (0.5 * (a[k] + b[k]) - c[k]);
        inner[i] = add_vertex(m, p);
    }
    // Inner vertex i lies between outer i and i + 1 (counter-clockwise): strip of 2n triangles.
    for (std::size_t i = 0; i < n; ++i) {
        add_triangle(m, inner[i], outer[i], outer[(i + 1) % n]);
        add_triangle(m, inner[i], outer[(i + 1) % n], inner[(i + 1) % n]);
    }
    return inner;
}

// Single-vertex configuration at a valence-4 vertex h: h keeps valence 4, its four new neighbours get valence 5.
inline void insert_single_configuration(TriMesh& m, int32_t h, double scale = 0.2) {
    const std::vector<int32_t> inner = replace_star(m, h, scale);
    if (inner.size() != 4) throw std::logic_error("insert_single_configuration needs a valence-4 vertex");
    for (int i = 0; i < 4; ++i) add_triangle(m, h, inner[i], inner[(i + 1) % 4]);
}

// Double-vertex configuration in place of a valence-6 vertex h: centres h and a new vertex d (both valence 5),
// shared neighbours inner[0] and inner[3] (valence 6), two more neighbours of valence 5 per centre.
inline void insert_double_configuration(TriMesh& m, int32_t h, double scale = 0.2) {
    const std::vector<int32_t> inner = replace_star(m, h, scale);
    if (inner.size() != 6) throw std::logic_error("insert_double_configuration needs a valence-6 vertex");
    const V3 c = vertex_of(m, h), a = vertex_of(m, inner[4]), b = vertex_of(m, inner[1]);
    V3 pc, pd;
    for (int k = 0; k < 3; ++k) {
        pc[k] = c[k] + 0.3 * (a[k] - c[k]);  // centre h moves towards its own side
        pd[k] = c[k] + 0.3 * (b[k] - c[k]);
    }
    for (int k = 0; k < 3; ++k) m.vertices[3 * h + k] = static_cast<float>(pc[k]);
    const int32_t d = add_vertex(m, pd);
    // h: fan over inner 3, 4, 5, 0 and d; d: fan over inner 0, 1, 2, 3 and h.
    add_triangle(m, h, inner[3], inner[4]);
    add_triangle(m, h, inner[4], inner[5]);
    add_triangle(m, h, inner[5], inner[0]);
    add_triangle(m, h, inner[0], d);
    add_triangle(m, h, d, inner[3]);
    add_triangle(m, d, inner[0], inner[1]);
    add_triangle(m, d, inner[1], inner[2]);
    add_triangle(m, d, inner[2], inner[3]);
}

// Marching tetrahedra (each grid cube split into the 6 tetrahedra around its main diagonal, consistent across
// cubes) of the region field > 0 sampled on the lattice of spacing h over [lo, hi]. The field must be negative on
// the sampled box's border: the mesh is then closed, 2-manifold and oriented outward. Vertices on lattice edges
// by linear interpolation, like marching cubes, so it shows the same slivers near lattice points.
inline TriMesh marching_tetrahedra(const std::function<double(double, double, double)>& field, V3 lo, V3 hi, double h) {
    int n[3];
    for (int k = 0; k < 3; ++k) n[k] = static_cast<int>(std::ceil((hi[k] - lo[k]) / h)) + 1;
    auto index = [&](int i, int j, int k) { return (static_cast<int64_t>(k) * n[1] + j) * n[0] + i; };
    std::vector<double> value(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) value[index(i, j, k)] = field(lo[0] + i * h, lo[1] + j * h, lo[2] + k * h);
    auto point = [&](int64_t id) {
        const int64_t i = id % n[0], j = (id / n[0]) % n[1], k = id / (int64_t(n[0]) * n[1]);
        return V3{lo[0] + i * h, lo[1] + j * h, lo[2] + k * h};
    };
    TriMesh m;
    std::map<std::pair<int64_t, int64_t>, int32_t> edge_vertex;
    auto crossing = [&](int64_t a, int64_t b) {  // a inside, b outside
        const auto key = std::make_pair(std::min(a, b), std::max(a, b));
        auto it = edge_vertex.find(key);
        if (it != edge_vertex.end()) return it->second;
        const double t = value[a] / (value[a] - value[b]);
        const V3 pa = point(a), pb = point(b);
        const int32_t id = add_vertex(m, {pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1]), pa[2] + t * (pb[2] - pa[2])});
        edge_vertex.emplace(key, id);
        return id;
    };
    // Orients triangle (a, b, c) so that its normal points from the inside corners to the outside ones.
    auto emit = [&](int32_t a, int32_t b, int32_t c, V3 inward_to_outward) {
        const int32_t corners[3] = {a, b, c};
        const Vec3d n = triangle_cross(m.vertices.data(), corners);
        if (dot(n, Vec3d{inward_to_outward[0], inward_to_outward[1], inward_to_outward[2]}) >= 0) add_triangle(m, a, b, c);
        else add_triangle(m, a, c, b);
    };
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int k = 0; k + 1 < n[2]; ++k)
        for (int j = 0; j + 1 < n[1]; ++j)
            for (int i = 0; i + 1 < n[0]; ++i)
                for (const auto& perm : perms) {
                    int c[3] = {i, j, k};
                    int64_t tet[4];
                    tet[0] = index(c[0], c[1], c[2]);
                    for (int s = 0; s < 3; ++s) {
                        ++c[perm[s]];
                        tet[s + 1] = index(c[0], c[1], c[2]);
                    }
                    std::vector<int64_t> in, out;
                    for (int64_t p : tet) (value[p] > 0 ? in : out).push_back(p);
                    if (in.empty() || out.empty()) continue;
                    V3 ci{0, 0, 0}, co{0, 0, 0};
                    for (int64_t p : in)
                        for (int q = 0; q < 3; ++q) ci[q] += point(p)[q] / in.size();
                    for (int64_t p : out)
                        for (int q = 0; q < 3; ++q) co[q] += point(p)[q] / out.size();
                    const V3 dir{co[0] - ci[0], co[1] - ci[1], co[2] - ci[2]};
                    if (in.size() == 1) emit(crossing(in[0], out[0]), crossing(in[0], out[1]), crossing(in[0], out[2]), dir);
                    else if (in.size() == 3) emit(crossing(in[0], out[0]), crossing(in[1], out[0]), crossing(in[2], out[0]), dir);
                    else {
                        // Quad through the four crossing edges, in cyclic order; split along one diagonal inside the
                        // tetrahedron (the split never touches a shared face, so neighbours need not agree).
                        const int32_t q0 = crossing(in[0], out[0]), q1 = crossing(in[0], out[1]), q2 = crossing(in[1], out[1]),
                                      q3 = crossing(in[1], out[0]);
                        emit(q0, q1, q2, dir);
                        emit(q0, q2, q3, dir);
                    }
                }
    return m;
}

// ---- checks ----------------------------------------------------------------------------------------------------

inline bool all_finite(const std::vector<float>& values) {
    for (float x : values)
        if (!std::isfinite(x)) return false;
    return true;
}

// Every triangle of a sphere-like mesh centred at c faces away from c.
inline bool faces_outward(const TriMesh& m, V3 c = {0, 0, 0}) {
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
        const Vec3d n = triangle_cross(m.vertices.data(), &m.triangles[3 * t]);
        const Vec3d a = vertex_position(m.vertices.data(), m.triangles[3 * t]);
        if (dot(n, a - Vec3d{c[0], c[1], c[2]}) <= 0) return false;
    }
    return true;
}

// Signed enclosed volume measured from the origin (divergence theorem).
inline double signed_volume(const TriMesh& m) {
    double volume = 0.0;
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
        const int32_t* c = &m.triangles[3 * t];
        volume += tetrahedron_volume(vertex_position(m.vertices.data(), c[0]), vertex_position(m.vertices.data(), c[1]),
                                     vertex_position(m.vertices.data(), c[2]));
    }
    return volume;
}

// FNV-1a over the bits of the vertices and the triangles: equal for bit-identical meshes.
inline uint64_t mesh_hash(const TriMesh& mesh) {
    uint64_t h = 1469598103934665603ull;
    auto mix = [&](uint32_t v) { h = (h ^ v) * 1099511628211ull; };
    for (float v : mesh.vertices) {
        uint32_t bits;
        std::memcpy(&bits, &v, 4);
        mix(bits);
    }
    for (int32_t t : mesh.triangles) mix(static_cast<uint32_t>(t));
    return h;
}

// ---- meshes for the post-processing tests ----------------------------------------------------------------------

// A bumpy blob: sphere of radius 1 with a few low-frequency waves, so marching cubes/tetrahedra of it produce
// every kind of sliver near lattice points.
inline double blob(double x, double y, double z) {
    const double r = std::sqrt(x * x + y * y + z * z);
    return 1.0 - r + 0.08 * std::sin(5.1 * x + 0.3) * std::sin(4.3 * y + 1.1) * std::sin(3.7 * z + 0.7);
}

// Test mesh with planted barnacles: an octasphere (six valence-4 vertices on the axes, valence 6 elsewhere) with a
// single-vertex configuration at each of the six axis vertices and double-vertex configurations at valence-6
// vertices far from them and from each other.
inline TriMesh barnacle_sphere(std::size_t& singles, std::size_t& doubles) {
    TriMesh m = make_octasphere(4);
    const std::size_t base = m.num_vertices();
    const MeshAdjacency adj = build_adjacency(m, 1);
    std::vector<int32_t> axis, picks;
    for (int32_t v = 0; v < static_cast<int32_t>(base); ++v)
        if (adj.valence(v) == 4) axis.push_back(v);
    // Valence-6 vertices whose position is near the diagonal directions (+-1, +-1, +-1)/sqrt(3): far from the axes.
    for (int32_t v = 0; v < static_cast<int32_t>(base); ++v) {
        const V3 p = vertex_of(m, v);
        if (adj.valence(v) != 6) continue;
        const double s = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]);
        bool far = s > 1.70;
        for (int32_t q : picks) {
            const V3 o = vertex_of(m, q);
            far = far && (p[0] - o[0]) * (p[0] - o[0]) + (p[1] - o[1]) * (p[1] - o[1]) + (p[2] - o[2]) * (p[2] - o[2]) > 0.5;
        }
        if (far) picks.push_back(v);
    }
    for (int32_t v : axis) insert_single_configuration(m, v);
    for (int32_t v : picks) insert_double_configuration(m, v);
    singles = axis.size();
    doubles = picks.size();
    return m;
}

// A vertex attribute "id" holding each vertex's index, to follow vertices through a stage that renumbers them.
inline void add_index_attribute(TriMesh& m) {
    Attribute id{"id", 1, {}};
    for (std::size_t v = 0; v < m.num_vertices(); ++v) id.values.push_back(static_cast<float>(v));
    m.attributes.push_back(id);
}

// ---- particle frames ---------------------------------------------------------------------------------------------

// A frame of ../shared/data by its name there ("splashsurf/bunny_frame_14_7705_particles.vtk").
inline std::string shared_frame(const std::string& name) { return std::string(MENISCUS_SHARED_DATA) + "/" + name; }

// Droplets on an nx x nx x 2 lattice of spacing 0.3 (jittered), every second one with a partner nearby: at c = 1.0
// (r = 0.025) a marching-cubes mesh of many small components carrying barnacles close together.
inline std::vector<float> droplet_particles(unsigned seed, int nx) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> offset(0.0f, 0.05f);
    std::normal_distribution<float> partner(0.0f, 0.025f);
    std::vector<float> positions;
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < nx; ++j)
            for (int k = 0; k < 2; ++k) {
                const float c[3] = {i * 0.3f + offset(random), j * 0.3f + offset(random), k * 0.3f + offset(random)};
                positions.insert(positions.end(), c, c + 3);
                if ((i + j + k) % 2)
                    for (int a = 0; a < 3; ++a) positions.push_back(c[a] + partner(random));
            }
    return positions;
}

inline ReconstructionParams reconstruction_params(double radius, double cube) {
    ReconstructionParams p;
    p.particle_radius = radius;
    p.cube_size = cube;
    return p;
}

}  // namespace test
}  // namespace meniscus
