// Blosc 1.x frames: a 16-byte header (version, compressor version, flags, type size, uncompressed size, block size,
// compressed size), the block start offsets, then per block one stream (or one per byte of the type, "split").
#include "io/blosc.h"

#include <cstdint>
#include <cstring>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

namespace {

constexpr unsigned kShuffle = 0x1, kMemcpyed = 0x2, kBitShuffle = 0x4, kDontSplit = 0x10;
constexpr int kBloscLz = 0, kLz4 = 1;
constexpr std::size_t kMaxSplits = 16, kMinBufferSize = 128;  // Blosc's rule for splitting a block by bytes
constexpr std::size_t kBloscLzMaxDistance = 8191;

// Adds a length's extension bytes (each 255 continues; BloscLZ and LZ4 both spell long lengths so); false at the end
// of the stream.
bool add_length_extension(const unsigned char* in, std::size_t in_size, std::size_t& ip, std::size_t& length) {
    unsigned byte;
    do {
        if (ip >= in_size) return false;
        byte = in[ip++];
        length += byte;
    } while (byte == 255);
    return true;
}

// Each decoder fills exactly out_size bytes from in_size bytes, or returns a reason.
const char* decode_blosclz(const unsigned char* in, std::size_t in_size, unsigned char* out, std::size_t out_size) {
    std::size_t ip = 0, op = 0;
    if (in_size == 0) return out_size == 0 ? nullptr : "an empty stream";
    unsigned ctrl = in[ip++] & 31u;  // the first instruction is always a literal run
    while (true) {
        if (ctrl >= 32) {
            std::size_t length = (ctrl >> 5) - 1;
            std::size_t distance = (ctrl & 31u) << 8;
            if (length == 6 && !add_length_extension(in, in_size, ip, length)) return "a match length runs past the end";
            if (ip >= in_size) return "a match distance runs past the end";
            const unsigned code = in[ip++];
            length += 3;
            distance += code;
            if (code == 255 && (ctrl & 31u) == 31u) {  // a far match: a 16-bit distance follows
                if (ip + 2 > in_size) return "a far match distance runs past the end";
                distance = ((std::size_t(in[ip]) << 8) | in[ip + 1]) + kBloscLzMaxDistance;
                ip += 2;
            }
            distance += 1;
            if (distance > op) return "a match reaches before the start of the output";
            if (length > out_size - op) return "a match runs past the end of the output";
            for (std::size_t k = 0; k < length; ++k, ++op) out[op] = out[op - distance];  // may overlap
        } else {
            const std::size_t length = ctrl + 1;
            if (length > out_size - op) return "literals run past the end of the output";
            if (length > in_size - ip) return "literals run past the end of the stream";
            std::memcpy(out + op, in + ip, length);
            op += length;
            ip += length;
        }
        if (ip >= in_size) break;
        ctrl = in[ip++];
    }
    return op == out_size ? nullptr : "the stream ends before the block is full";
}

const char* decode_lz4(const unsigned char* in, std::size_t in_size, unsigned char* out, std::size_t out_size) {
    std::size_t ip = 0, op = 0;
    while (true) {
        if (ip >= in_size) return "the stream ends without its last literals";
        const unsigned token = in[ip++];
        std::size_t literals = token >> 4;
        if (literals == 15 && !add_length_extension(in, in_size, ip, literals)) return "a literal length runs past the end";
        if (literals > in_size - ip) return "literals run past the end of the stream";
        if (literals > out_size - op) return "literals run past the end of the output";
        if (literals) std::memcpy(out + op, in + ip, literals);
        ip += literals;
        op += literals;
        if (ip == in_size) break;  // the last sequence has literals only
        if (ip + 2 > in_size) return "a match offset runs past the end";
        const std::size_t offset = in[ip] | (std::size_t(in[ip + 1]) << 8);
        ip += 2;
        if (offset == 0 || offset > op) return "a match reaches before the start of the output";
        std::size_t length = token & 15u;
        if (length == 15 && !add_length_extension(in, in_size, ip, length)) return "a match length runs past the end";
        length += 4;
        if (length > out_size - op) return "a match runs past the end of the output";
        for (std::size_t k = 0; k < length; ++k, ++op) out[op] = out[op - offset];
    }
    return op == out_size ? nullptr : "the stream ends before the block is full";
}

}  // namespace

void blosc_decompress(const std::string& path, const unsigned char* in, std::size_t size, unsigned char* out,
                      std::size_t expected, const std::string& what) {
    auto bad = [&](const std::string& why) { fail(path, what + ": corrupt Blosc data: " + why); };
    if (size < 16) bad("a " + std::to_string(size) + "-byte frame is shorter than its 16-byte header");
    // Blosc 1 writes format versions 1-2; Blosc2 chunks (3 and up) lay their header out otherwise.
    if (in[0] > 2) fail(path, what + ": Blosc format version " + std::to_string(in[0]) + " (Blosc2) is not supported");
    const unsigned flags = in[2];
    const std::size_t type_size = in[3] == 0 ? 1 : in[3];
    const std::size_t nbytes = load_le32(in + 4), block_size = load_le32(in + 8), cbytes = load_le32(in + 12);
    if (nbytes != expected)
        bad("it holds " + std::to_string(nbytes) + " bytes where " + std::to_string(expected) + " are expected");
    if (cbytes != size) bad("its header says " + std::to_string(cbytes) + " bytes, the frame has " + std::to_string(size));
    if (flags & kBitShuffle) fail(path, what + ": Blosc bit-shuffle is not supported (byte shuffle is)");
    if (flags & kMemcpyed) {
        if (size - 16 < nbytes) bad("stored data of " + std::to_string(nbytes) + " bytes in a frame of " + std::to_string(size));
        if (nbytes) std::memcpy(out, in + 16, nbytes);  // out may be null when nothing is expected
        return;
    }
    const int compressor = static_cast<int>(flags >> 5);
    if (compressor != kBloscLz && compressor != kLz4) {
        static const char* names[] = {"BloscLZ", "LZ4", "Snappy", "zlib", "Zstd"};
        fail(path, what + ": Blosc compressor " + (compressor < 5 ? names[compressor] : std::to_string(compressor)) +
                       " is not supported (BloscLZ and LZ4 are)");
    }
    if (nbytes == 0) return;
    if (block_size == 0 || block_size > nbytes) bad("block size " + std::to_string(block_size));
    const std::size_t blocks = (nbytes + block_size - 1) / block_size;
    if (blocks > (size - 16) / 4) bad(std::to_string(blocks) + " block offsets do not fit in the frame");
    const bool shuffle = (flags & kShuffle) && type_size > 1;
    std::vector<unsigned char> unshuffled(shuffle ? block_size : 0);
    for (std::size_t b = 0; b < blocks; ++b) {
        const bool leftover = b + 1 == blocks && nbytes % block_size != 0;
        const std::size_t this_block = leftover ? nbytes % block_size : block_size;
        const std::size_t splits =
            !(flags & kDontSplit) && !leftover && type_size <= kMaxSplits && this_block / type_size >= kMinBufferSize ? type_size : 1;
        if (this_block % splits != 0) bad("a block of " + std::to_string(this_block) + " bytes in " + std::to_string(splits) + " streams");
        std::size_t ip = load_le32(in + 16 + 4 * b);
        unsigned char* dest = shuffle ? unshuffled.data() : out + b * block_size;
        const std::size_t stream_size = this_block / splits;
        for (std::size_t s = 0; s < splits; ++s) {
            if (ip < 16 || ip > size || size - ip < 4) bad("block " + std::to_string(b) + " starts outside the frame");
            const std::size_t csize = load_le32(in + ip);
            ip += 4;
            if (csize > size - ip) bad("block " + std::to_string(b) + " runs past the end of the frame");
            unsigned char* target = dest + s * stream_size;
            if (csize == stream_size) {
                std::memcpy(target, in + ip, csize);  // stored: it did not compress
            } else {
                const char* error = compressor == kLz4 ? decode_lz4(in + ip, csize, target, stream_size)
                                                       : decode_blosclz(in + ip, csize, target, stream_size);
                if (error) bad(std::string(compressor == kLz4 ? "LZ4" : "BloscLZ") + " in block " + std::to_string(b) + ": " + error);
            }
            ip += csize;
        }
        if (shuffle) {  // byte k of element i was stored at k * elements + i; trailing bytes stay in place
            const std::size_t elements = this_block / type_size;
            unsigned char* o = out + b * block_size;
            for (std::size_t i = 0; i < elements; ++i)
                for (std::size_t k = 0; k < type_size; ++k) o[i * type_size + k] = unshuffled[k * elements + i];
            if (this_block > elements * type_size)
                std::memcpy(o + elements * type_size, unshuffled.data() + elements * type_size, this_block - elements * type_size);
        }
    }
}

}  // namespace io_detail
}  // namespace meniscus
