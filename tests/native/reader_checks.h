// What the reader tests check again and again, written once: where the test files are, how a read must fail (a
// FormatError whose message starts with the path), what a successful read must satisfy, and the small files and
// meshes several test files build.
#pragma once
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "base/errors.h"
#include "io/io.h"
#include "test_files.h"

namespace meniscus {
namespace test {

inline const std::string kShared = MENISCUS_SHARED_DATA;
inline const std::string kTestData = MENISCUS_TEST_DATA;
inline const std::string kFormats = kTestData + "/formats";
inline const std::string kVariants = kFormats + "/variants";
// The frame the samples in tests/data/formats/ were converted from (tests/data/formats/make_samples.py).
inline const std::string kSource = kShared + "/splashsurf/double_dam_break_frame_26_4732_particles.vtk";

inline std::string as_text(const Bytes& b) { return std::string(b.begin(), b.end()); }
inline Bytes as_bytes(const std::string& s) { return Bytes(s.begin(), s.end()); }
inline bool starts_with(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

// Runs f; returns the FormatError message, or "" when f succeeds. Any other exception fails the test.
template <class F>
std::string format_error_of(F&& f) {
    try {
        f();
    } catch (const FormatError& e) {
        return e.what();
    }
    return "";
}

// Reads the file: "" and the data on success, else the FormatError message.
inline std::string outcome(const std::string& path, ParticleData* out = nullptr) {
    return format_error_of([&] {
        ParticleData p = read_particles(path);
        if (out) *out = std::move(p);
    });
}

// read_particles(path) must fail with a FormatError that starts with the path (and contains `expect` if given).
inline std::string require_particle_error(const std::string& path, const std::string& expect = "") {
    std::string message = outcome(path);
    INFO("path: " << path << "\nmessage: " << message);
    REQUIRE(!message.empty());
    REQUIRE(starts_with(message, path));
    if (!expect.empty()) REQUIRE_THAT(message, Catch::Contains(expect));
    return message;
}

// The same for read_mesh.
inline std::string require_mesh_error(const std::string& path, const std::string& expect = "") {
    std::string message = format_error_of([&] { read_mesh(path); });
    INFO("path: " << path << "\nmessage: " << message);
    REQUIRE(!message.empty());
    REQUIRE(starts_with(message, path));
    if (!expect.empty()) REQUIRE_THAT(message, Catch::Contains(expect));
    return message;
}

// Either a clean read or a FormatError naming the path: what every damaged file must give.
inline void require_clean_outcome(const std::string& path) {
    std::string message = outcome(path);
    INFO("path: " << path << "\nmessage: " << message);
    if (!message.empty()) REQUIRE(starts_with(message, path));
}

// A successful read must be self-consistent: whole triples, every attribute one tuple per particle.
inline void require_consistent(const ParticleData& p) {
    REQUIRE(p.positions.size() % 3 == 0);
    for (const auto& a : p.attributes) {
        REQUIRE(a.components >= 1);
        REQUIRE(a.values.size() == p.size() * static_cast<std::size_t>(a.components));
    }
}

// The decompressed content of a gzip file.
inline Bytes gunzip_file(const std::string& path) {
    gzFile f = gzopen(path.c_str(), "rb");
    REQUIRE(f != nullptr);
    Bytes out;
    unsigned char buffer[1 << 16];
    int n;
    while ((n = gzread(f, buffer, sizeof buffer)) > 0) out.insert(out.end(), buffer, buffer + n);
    gzclose(f);
    return out;
}

// Replaces the first occurrence of `from` by `to` (same file otherwise).
inline Bytes replace_text(const Bytes& bytes, const std::string& from, const std::string& to) {
    std::string s(bytes.begin(), bytes.end());
    auto pos = s.find(from);
    REQUIRE(pos != std::string::npos);
    s.replace(pos, from.size(), to);
    return Bytes(s.begin(), s.end());
}

// Offsets of the keyword lines ("\nPOINTS ...", "\nCELLS ...") in a binary legacy VTK file.
inline std::vector<std::size_t> vtk_keyword_offsets(const Bytes& bytes) {
    static const char* keywords[] = {"POINTS ", "CELLS ", "CELL_TYPES ", "POINT_DATA ", "SCALARS ", "LOOKUP_TABLE ", "FIELD "};
    std::vector<std::size_t> out;
    for (std::size_t i = 1; i < bytes.size(); ++i) {
        if (bytes[i - 1] != '\n') continue;
        for (const char* k : keywords)
            if (bytes.size() - i > std::strlen(k) && std::memcmp(&bytes[i], k, std::strlen(k)) == 0) out.push_back(i);
    }
    return out;
}

// ---- the reference frame ----

inline const ParticleData& reference() {
    static const ParticleData data = read_particles(kSource);
    return data;
}

// The first n particles of the reference frame, with the given attributes (id and/or velocity, which Houdini
// calls "v").
inline void require_same(const ParticleData& p, std::size_t n, bool with_id, bool with_velocity, const char* velocity_name = "velocity") {
    const ParticleData& ref = reference();
    REQUIRE(p.size() == n);
    REQUIRE(std::equal(p.positions.begin(), p.positions.end(), ref.positions.begin()));
    std::size_t expected = std::size_t(with_id) + std::size_t(with_velocity);
    REQUIRE(p.attributes.size() == expected);
    if (with_id) {
        const Attribute* id = find_attribute(p.attributes, "id");
        REQUIRE(id);
        REQUIRE(id->components == 1);
        REQUIRE(std::equal(id->values.begin(), id->values.end(), ref.attributes[0].values.begin()));
        REQUIRE(id->values.size() == n);
    }
    if (with_velocity) {
        const Attribute* v = find_attribute(p.attributes, std::string(velocity_name));
        REQUIRE(v);
        REQUIRE(v->components == 3);
        REQUIRE(v->values.size() == 3 * n);
        REQUIRE(std::equal(v->values.begin(), v->values.end(), ref.attributes[1].values.begin()));
    }
}

// ---- builders for synthetic files ----

struct BigEndianWriter {
    Bytes bytes;
    void text(const std::string& s) { bytes.insert(bytes.end(), s.begin(), s.end()); }
    void u8(unsigned v) { bytes.push_back(static_cast<unsigned char>(v)); }
    void u16(unsigned v) {
        u8(v >> 8);
        u8(v);
    }
    void u32(std::uint32_t v) {
        u16(v >> 16);
        u16(v & 0xffff);
    }
    void u64(std::uint64_t v) {
        u32(static_cast<std::uint32_t>(v >> 32));
        u32(static_cast<std::uint32_t>(v));
    }
    void f32(float f) {
        std::uint32_t u;
        std::memcpy(&u, &f, 4);
        u32(u);
    }
    void f64(double d) {
        std::uint64_t u;
        std::memcpy(&u, &d, 8);
        u64(u);
    }
};

struct BgeoAttr {
    std::string name;
    int type;  // 0 float, 1 int, 4 index, 5 vector
    int size;
};

// A classic BGEO with the given attributes; point i has position (i, 2i, 3i) and attribute word k = i * 10 + k.
inline Bytes make_bgeo(std::int32_t points, const std::vector<BgeoAttr>& attrs, int version = 5) {
    BigEndianWriter w;
    w.text("BgeoV");
    w.u32(static_cast<std::uint32_t>(version));
    for (std::int32_t c : {points, 0, 0, 0, static_cast<std::int32_t>(attrs.size()), 0, 0, 0}) w.u32(static_cast<std::uint32_t>(c));
    for (const auto& a : attrs) {
        w.u16(static_cast<unsigned>(a.name.size()));
        w.text(a.name);
        w.u16(static_cast<unsigned>(a.size));
        w.u32(static_cast<std::uint32_t>(a.type));
        if (a.type == 4) {
            w.u32(2);
            for (const char* s : {"water", "foam"}) {
                w.u16(static_cast<unsigned>(std::strlen(s)));
                w.text(s);
            }
        } else {
            for (int k = 0; k < a.size; ++k) w.u32(0);
        }
    }
    for (std::int32_t i = 0; i < points; ++i) {
        w.f32(float(i));
        w.f32(float(2 * i));
        w.f32(float(3 * i));
        w.f32(1.0f);
        for (const auto& a : attrs)
            for (int k = 0; k < a.size; ++k) {
                if (a.type == 0 || a.type == 5)
                    w.f32(float(i * 10 + k));
                else
                    w.u32(static_cast<std::uint32_t>(a.type == 4 ? i % 2 : i * 10 + k));
            }
    }
    w.u8(0);
    w.u8(0xff);
    return w.bytes;
}

// An octahedron: 6 vertices, 8 triangles, unit normals, attributes of 1, 3 and 2 components.
inline TriMesh make_test_mesh() {
    TriMesh m;
    m.vertices = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    m.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    m.normals = m.vertices;
    for (float& x : m.vertices) x = x * 0.3f + 0.1f;  // values that are not short decimals
    Attribute density{"density", 1, {}}, velocity{"velocity", 3, {}}, uv{"uv", 2, {}};
    for (int v = 0; v < 6; ++v) {
        density.values.push_back(1000.0f + v / 7.0f);
        for (int k = 0; k < 3; ++k) velocity.values.push_back(std::sin(float(v * 3 + k)));
        for (int k = 0; k < 2; ++k) uv.values.push_back(v * 0.1f + k);
    }
    m.attributes = {density, velocity, uv};
    return m;
}

inline void require_same_mesh(const TriMesh& a, const TriMesh& b, bool with_attributes) {
    REQUIRE(a.vertices == b.vertices);
    REQUIRE(a.triangles == b.triangles);
    REQUIRE(a.normals == b.normals);
    if (!with_attributes) return;
    REQUIRE(a.attributes.size() == b.attributes.size());
    for (std::size_t i = 0; i < a.attributes.size(); ++i) {
        CHECK(a.attributes[i].name == b.attributes[i].name);
        CHECK(a.attributes[i].components == b.attributes[i].components);
        CHECK(a.attributes[i].values == b.attributes[i].values);
    }
}

// write_mesh then read_mesh gives the mesh back; returns what was read.
inline TriMesh require_round_trip(const TriMesh& mesh, const std::string& path, bool with_attributes = true) {
    write_mesh(mesh, path);
    TriMesh back = read_mesh(path);
    require_same_mesh(mesh, back, with_attributes);
    return back;
}

// An empty mesh writes and reads back empty.
inline void require_empty_round_trip(const std::string& path) {
    write_mesh(TriMesh{}, path);
    TriMesh empty = read_mesh(path);
    REQUIRE(empty.vertices.empty());
    REQUIRE(empty.triangles.empty());
}

}  // namespace test
}  // namespace meniscus
