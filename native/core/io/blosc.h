// A decoder of Blosc 1.x frames (what OpenVDB writes with Blosc compression): BloscLZ or LZ4 blocks, optionally
// byte-shuffled, or stored (memcpyed). Written from the published format descriptions (Blosc's README_HEADER,
// the LZ4 block format, BloscLZ = FastLZ level 1 with 16-bit far distances); no Blosc library is needed.
#pragma once
#include <cstddef>
#include <string>

namespace meniscus {
namespace io_detail {

// Decodes the Blosc frame of `size` bytes at `in` into `out`, which must receive exactly `expected` bytes.
// Bit-shuffle and the compressors other than BloscLZ and LZ4 (Snappy, zlib, Zstd) are refused by name; any
// inconsistency (sizes, offsets, a match reaching before the output) is a FormatError naming `path` and `what`.
void blosc_decompress(const std::string& path, const unsigned char* in, std::size_t size, unsigned char* out,
                      std::size_t expected, const std::string& what);

}  // namespace io_detail
}  // namespace meniscus
