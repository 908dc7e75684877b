// gzip files and zlib / raw deflate blocks, decompressed with a cap on the output (see io_util.h).
#include <zlib.h>

#include <algorithm>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

Bytes gunzip(const std::string& path, const Bytes& compressed) {
    const std::uint64_t limit = kGunzipRatioCap * compressed.size() + kGunzipSlackBytes;
    z_stream zs{};
    // 15 + 16: zlib window of 32 KiB, gzip wrapper only (we got here by the gzip magic).
    if (inflateInit2(&zs, 15 + 16) != Z_OK) fail(path, "cannot initialise zlib");
    struct Guard {
        z_stream* zs;
        ~Guard() { inflateEnd(zs); }
    } guard{&zs};

    // First guess of the output size: the gzip trailer's length field when it is plausible (it is mod 2^32, of the
    // last member only, and garbage in a truncated file), else 4x the input. Growth by doubling handles the rest.
    std::uint64_t guess = std::uint64_t(compressed.size()) * 4;
    if (compressed.size() >= 18) {
        std::uint64_t isize = load_le32(compressed.data() + compressed.size() - 4);
        if (isize >= compressed.size() / 2 && isize <= std::uint64_t(compressed.size()) * 16)
            guess = isize + 1;  // +1: room to see the end of the stream without growing
    }
    Bytes out(static_cast<std::size_t>(std::min<std::uint64_t>(limit, std::max<std::uint64_t>(guess, 1 << 16))));
    std::size_t in_pos = 0, out_pos = 0;
    while (true) {
        if (out_pos == out.size()) {
            if (out.size() >= limit)
                fail(path, "gzip data decompresses to more than " + std::to_string(limit) + " bytes (" +
                               std::to_string(kGunzipRatioCap) + " times the compressed size plus " +
                               std::to_string(kGunzipSlackBytes >> 20) + " MiB); refusing a corrupt file or decompression bomb");
            out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(limit, std::uint64_t(out.size()) * 2)));
        }
        // zlib counts in 32-bit units; feed large buffers in slices.
        std::size_t in_slice = std::min<std::size_t>(compressed.size() - in_pos, 1u << 30);
        std::size_t out_slice = std::min<std::size_t>(out.size() - out_pos, 1u << 30);
        zs.next_in = const_cast<Bytef*>(compressed.data() + in_pos);
        zs.avail_in = static_cast<uInt>(in_slice);
        zs.next_out = out.data() + out_pos;
        zs.avail_out = static_cast<uInt>(out_slice);
        int ret = inflate(&zs, Z_NO_FLUSH);
        in_pos += in_slice - zs.avail_in;
        out_pos += out_slice - zs.avail_out;
        if (ret == Z_STREAM_END) {
            // Another gzip member may follow (cat a.gz b.gz); anything else after the end is ignored.
            if (compressed.size() - in_pos >= 2 && compressed[in_pos] == 0x1f && compressed[in_pos + 1] == 0x8b) {
                inflateReset(&zs);
                continue;
            }
            break;
        }
        if (ret == Z_OK) continue;
        if (ret == Z_BUF_ERROR && in_pos == compressed.size())
            fail(path, "truncated gzip stream: the compressed data ends at byte " + std::to_string(compressed.size()) +
                           " before the end of the stream (" + std::to_string(out_pos) + " bytes decompressed so far)");
        if (ret == Z_BUF_ERROR) continue;  // output space was exhausted; grow it above
        if (ret == Z_MEM_ERROR) fail(path, "out of memory while decompressing gzip data");
        fail(path, std::string("corrupt gzip stream near compressed byte ") + std::to_string(in_pos) + ": " +
                       (zs.msg ? zs.msg : "invalid data"));
    }
    out.resize(out_pos);
    out.shrink_to_fit();
    if (out.empty()) fail(path, "empty file (the gzip stream decompresses to nothing)");
    return out;
}

void inflate_exact(const std::string& path, const unsigned char* in, std::size_t in_size, unsigned char* out,
                   std::size_t expected, int window_bits, const std::string& what) {
    z_stream zs{};
    if (inflateInit2(&zs, window_bits) != Z_OK) fail(path, "cannot initialise zlib");
    struct Guard {
        z_stream* zs;
        ~Guard() { inflateEnd(zs); }
    } guard{&zs};
    // One spare output byte: a stream that has more to give than `expected` is caught instead of silently cut.
    unsigned char spare = 0;
    std::size_t in_pos = 0, out_pos = 0;
    bool in_spare = expected == 0;  // zlib refuses a null output pointer even for zero bytes
    while (true) {
        std::size_t in_slice = std::min<std::size_t>(in_size - in_pos, 1u << 30);
        std::size_t out_slice = in_spare ? 1 : std::min<std::size_t>(expected - out_pos, 1u << 30);
        zs.next_in = const_cast<Bytef*>(in + in_pos);
        zs.avail_in = static_cast<uInt>(in_slice);
        zs.next_out = in_spare ? &spare : out + out_pos;
        zs.avail_out = static_cast<uInt>(out_slice);
        int ret = inflate(&zs, Z_NO_FLUSH);
        in_pos += in_slice - zs.avail_in;
        std::size_t produced = out_slice - zs.avail_out;
        if (in_spare && produced > 0)
            fail(path, what + ": the compressed data decompresses to more than the " + std::to_string(expected) +
                           " bytes its header announces");
        if (!in_spare) out_pos += produced;
        if (ret == Z_STREAM_END) break;
        if (ret == Z_OK || (ret == Z_BUF_ERROR && zs.avail_out == 0)) {
            if (!in_spare && out_pos == expected) in_spare = true;
            continue;
        }
        if (ret == Z_BUF_ERROR)
            fail(path, what + ": truncated compressed data (" + std::to_string(in_size) + " bytes end before the end of the "
                           "stream, " + std::to_string(out_pos) + " of " + std::to_string(expected) + " bytes decompressed)");
        if (ret == Z_MEM_ERROR) fail(path, what + ": out of memory while decompressing");
        fail(path, what + ": corrupt compressed data near byte " + std::to_string(in_pos) + " of the block: " +
                       (zs.msg ? zs.msg : "invalid data"));
    }
    if (out_pos != expected)
        fail(path, what + ": the compressed data decompresses to " + std::to_string(out_pos) + " bytes, " +
                       std::to_string(expected) + " expected");
}

}  // namespace io_detail
}  // namespace meniscus
