// Shared body of the libFuzzer harnesses: feed the bytes to one reader, accept a clean result or a FormatError,
// and check the result's invariants. Anything else (a crash, a sanitizer report, another exception escaping, an
// inconsistent result, an allocation beyond -malloc_limit_mb) is a finding.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "base/errors.h"
#include "io/io_util.h"

namespace meniscus_fuzz {

inline void check(const meniscus::ParticleData& p) {
    if (p.positions.size() % 3 != 0) {
        std::fprintf(stderr, "positions size %zu is not a multiple of 3\n", p.positions.size());
        std::abort();
    }
    for (const auto& a : p.attributes)
        if (a.components < 1 || a.values.size() != p.size() * static_cast<std::size_t>(a.components)) {
            std::fprintf(stderr, "attribute '%s': %zu values, %d components, %zu particles\n", a.name.c_str(), a.values.size(),
                         a.components, p.size());
            std::abort();
        }
}

inline void check(const meniscus::TriMesh& m) {
    if (m.vertices.size() % 3 != 0 || m.triangles.size() % 3 != 0 || (!m.normals.empty() && m.normals.size() != m.vertices.size())) {
        std::fprintf(stderr, "inconsistent mesh arrays\n");
        std::abort();
    }
    for (auto t : m.triangles)
        if (t < 0 || static_cast<std::size_t>(t) >= m.num_vertices()) {
            std::fprintf(stderr, "triangle index %d out of range\n", t);
            std::abort();
        }
}

template <class Reader>
int run(const std::uint8_t* data, std::size_t size, const char* name, Reader reader) {
    meniscus::io_detail::Source source{name, data, size, false};
    try {
        check(reader(source));
    } catch (const meniscus::FormatError&) {
    }
    return 0;
}

}  // namespace meniscus_fuzz

// One harness per reader: MENISCUS_FUZZ_READER(read_vtu_particles, "fuzz.vtu").
#define MENISCUS_FUZZ_READER(function, name)                                                       \
    extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {            \
        return meniscus_fuzz::run(data, size, name, [](const meniscus::io_detail::Source& s) {     \
            return meniscus::io_detail::function(s);                                              \
        });                                                                                       \
    }
