// libFuzzer harness: read_particles' whole path on arbitrary bytes — gzip, detection by content, every reader.
// The name has no known extension, so only the content decides (the per-reader harnesses cover the extensions).
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return meniscus_fuzz::run(data, size, "fuzz.bin", [](const meniscus::io_detail::Source& s) {
        return meniscus::io_detail::read_particles_from_bytes(s.path, meniscus::io_detail::Bytes(s.data, s.data + s.size));
    });
}
