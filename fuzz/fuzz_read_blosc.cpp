// libFuzzer harness: the Blosc frame decoder (io/blosc.cpp) on arbitrary bytes, expecting what the frame's header
// says (up to 1 MiB), so that the BloscLZ and LZ4 decoders, the splits and the unshuffle are all reached.
#include <vector>

#include "fuzz_common.h"
#include "io/blosc.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 16) return 0;
    const std::size_t expected = meniscus::io_detail::load_le32(data + 4);
    if (expected > (std::size_t(1) << 20)) return 0;
    std::vector<unsigned char> out(expected);
    try {
        meniscus::io_detail::blosc_decompress("fuzz.blosc", data, size, out.data(), expected, "fuzz");
    } catch (const meniscus::FormatError&) {
    }
    return 0;
}
