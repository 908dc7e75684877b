// Decoding the DataArrays of a VTK XML file: ASCII text, base64 inline data, and appended data (raw or base64),
// each binary one optionally zlib-compressed.
//
// Binary payloads start with a header of header_type words: uncompressed, one word with the byte count; compressed,
// [number of blocks, block size, size of the last block, compressed size of each block].
//
// Memory: nothing is allocated before the bytes it comes from have been found in the file. Each appended array may
// only read up to the next array's offset (and vtu.cpp refuses two kept arrays at one offset), so the arrays together
// never decode more than the file holds (times the zlib cap of max_inflated_size for compressed ones).
#include <algorithm>
#include <memory>

#include "io/formats/vtu.h"
#include "io/parsers/base64.h"

namespace meniscus {
namespace io_detail {
namespace vtu {
namespace {

// The bytes of one binary payload: a window of the file (raw appended data) or a base64 stream.
class Payload {
public:
    Payload(const Cursor& c, std::size_t begin, std::size_t end, std::string what)
        : c_(c), what_(std::move(what)), pos_(begin), end_(end) {}
    Payload(const Cursor& c, std::vector<TextRange> ranges, std::string what)
        : c_(c), what_(what), base64_(std::make_unique<Base64Reader>(c, std::move(ranges), what)) {}

    std::uint64_t max_remaining() const { return base64_ ? base64_->max_remaining() : end_ - pos_; }

    // n bytes; the pointer stays valid until the next call.
    const unsigned char* take(std::uint64_t n, const std::string& what) {
        if (n > max_remaining()) fail_short(n, what);
        if (!base64_) {
            const unsigned char* p = c_.source().data + pos_;
            pos_ += static_cast<std::size_t>(n);
            return p;
        }
        scratch_.resize(static_cast<std::size_t>(n));
        base64_->read(scratch_.data(), n);
        return scratch_.data();
    }

private:
    const Cursor& c_;
    std::string what_;
    std::size_t pos_ = 0, end_ = 0;
    std::unique_ptr<Base64Reader> base64_;
    Bytes scratch_;

    [[noreturn]] void fail_short(std::uint64_t n, const std::string& what) const {
        if (base64_)
            c_.fail(what + " needs " + std::to_string(n) + " bytes but the base64 data of " + what_ + " holds at most " +
                    std::to_string(max_remaining()) + " (a wrong count, or the file is truncated)");
        c_.fail(what + " needs " + std::to_string(n) + " bytes from " + c_.where(pos_) + " but only " + std::to_string(end_ - pos_) +
                " are available for " + what_ + " (a wrong count, or truncated at " + c_.where(c_.size()) + ")");
    }
};

// The compression header of a zlib-compressed payload.
struct Blocks {
    std::uint64_t block_size = 0, last_size = 0, total = 0, compressed_total = 0;
    std::vector<std::uint64_t> sizes;  // compressed size of each block
};

class ArrayDecoder {
public:
    ArrayDecoder(const Cursor& c, const File& file, const DataArray& a, std::string what)
        : c_(c), file_(file), settings_(file.settings), a_(a), what_(std::move(what)) {}

    std::vector<float> decode(std::uint64_t tuples) {
        std::uint64_t count = 0;
        if (!checked_mul(tuples, a_.components, count)) c_.fail(what_ + ": size is impossibly large");
        if (a_.encoding == Encoding::ascii) return ascii(count);
        if (a_.encoding == Encoding::binary) {
            Payload payload(c_, a_.text, what_);
            return binary(payload, count);
        }
        auto region = appended_region();
        if (file_.appended.base64) {
            Payload payload(c_, std::vector<TextRange>{{region.first, region.second}}, what_);
            return binary(payload, count);
        }
        Payload payload(c_, region.first, region.second, what_);
        return binary(payload, count);
    }

private:
    const Cursor& c_;
    const File& file_;
    const FileSettings& settings_;
    const DataArray& a_;
    std::string what_;

    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const { c_.fail(what + " at " + c_.where(pos)); }

    // The region of an appended array: from its offset up to the next larger offset of any appended array.
    std::pair<std::size_t, std::size_t> appended_region() const {
        const AppendedData& appended = file_.appended;
        if (!appended.present) fail_at(a_.tag_pos, what_ + " is appended but the file has no AppendedData (truncated?)");
        const std::uint64_t length = appended.end - appended.begin;
        if (a_.offset >= length)
            fail_at(a_.tag_pos, what_ + " has offset " + std::to_string(a_.offset) + " beyond the " + std::to_string(length) +
                                    " bytes of appended data (a wrong offset, or truncated at " + c_.where(c_.size()) + ")");
        auto next = std::upper_bound(appended.offsets.begin(), appended.offsets.end(), a_.offset);
        std::uint64_t end = next == appended.offsets.end() ? length : std::min<std::uint64_t>(*next, length);
        return {appended.begin + static_cast<std::size_t>(a_.offset), appended.begin + static_cast<std::size_t>(end)};
    }

    std::uint64_t header_word(Payload& payload, const std::string& what) const {
        const unsigned char* p = payload.take(settings_.header_size, what);
        if (settings_.header_size == 4) return settings_.big_endian ? load_be32(p) : load_le32(p);
        return settings_.big_endian ? load_be64(p) : load_le64(p);
    }

    std::vector<float> to_floats(const unsigned char* p, std::uint64_t count) const {
        std::vector<float> values(static_cast<std::size_t>(count));
        decode_to_float(p, values.size(), a_.type, settings_.big_endian, values.data());
        return values;
    }

    std::vector<float> binary(Payload& payload, std::uint64_t count) {
        std::uint64_t expected = 0;
        if (!checked_mul(count, scalar_size(a_.type), expected))
            c_.fail(what_ + ": " + std::to_string(count) + " values is impossibly large");
        if (settings_.compressed) return compressed(payload, count, expected);
        std::uint64_t bytes = header_word(payload, what_ + " size header");
        if (bytes != expected)
            c_.fail(what_ + " holds " + std::to_string(bytes) + " bytes but " + std::to_string(count) + " values of type " + a_.type_name +
                    " need " + std::to_string(expected) + " (the NumberOfPoints or NumberOfComponents does not match the data)");
        return to_floats(payload.take(bytes, what_ + " data"), count);
    }

    std::vector<float> compressed(Payload& payload, std::uint64_t count, std::uint64_t expected) {
        const Blocks blocks = read_blocks(payload);
        if (blocks.total != expected)
            c_.fail(what_ + " decompresses to " + std::to_string(blocks.total) + " bytes but " + std::to_string(count) +
                    " values of type " + a_.type_name + " need " + std::to_string(expected));
        if (blocks.total > max_inflated_size(blocks.compressed_total))
            c_.fail(what_ + ": " + std::to_string(blocks.compressed_total) + " compressed bytes claim to hold " +
                    std::to_string(blocks.total) + ", beyond any real data; refusing a corrupt file or decompression bomb");
        const unsigned char* p = payload.take(blocks.compressed_total, what_ + " compressed data");
        Bytes raw(static_cast<std::size_t>(blocks.total));
        std::uint64_t in = 0, out = 0;
        for (std::size_t b = 0; b < blocks.sizes.size(); ++b) {
            std::uint64_t n = b + 1 == blocks.sizes.size() && blocks.last_size ? blocks.last_size : blocks.block_size;
            inflate_exact(c_.source().path, p + in, static_cast<std::size_t>(blocks.sizes[b]), raw.data() + out,
                          static_cast<std::size_t>(n), 15, what_ + " block " + std::to_string(b));
            in += blocks.sizes[b];
            out += n;
        }
        return to_floats(raw.data(), count);
    }

    // The compression header, every size checked against the data left before it is trusted.
    Blocks read_blocks(Payload& payload) const {
        const std::string what = what_ + " compression header";
        Blocks b;
        std::uint64_t count = header_word(payload, what);
        if (count > payload.max_remaining() / settings_.header_size)
            c_.fail(what_ + ": compression header claims " + std::to_string(count) + " blocks, more than the data can hold");
        b.block_size = header_word(payload, what);
        b.last_size = header_word(payload, what);
        b.sizes.resize(static_cast<std::size_t>(count));
        for (auto& s : b.sizes) {
            s = header_word(payload, what);
            if (s > payload.max_remaining() || b.compressed_total + s < b.compressed_total)
                c_.fail(what_ + ": a compressed block of " + std::to_string(s) + " bytes is larger than the data left");
            b.compressed_total += s;
        }
        if (b.last_size > b.block_size)
            c_.fail(what_ + ": the last block (" + std::to_string(b.last_size) + " bytes) is larger than the block size " +
                    std::to_string(b.block_size));
        if (count > 0) {
            const std::uint64_t last = b.last_size ? b.last_size : b.block_size;
            if (!checked_mul(count - 1, b.block_size, b.total) || b.total + last < b.total)
                c_.fail(what_ + ": compression header sizes are impossibly large");
            b.total += last;
        }
        return b;
    }

    std::vector<float> ascii(std::uint64_t count) {
        std::uint64_t chars = 0;
        for (const auto& r : a_.text) chars += r.end - r.begin;
        // Every value takes at least one character plus a separator.
        if (count > (chars + 1) / 2)
            fail_at(a_.tag_pos, what_ + ": " + std::to_string(count) + " ASCII values cannot fit in its " + std::to_string(chars) +
                                    " characters (NumberOfPoints wrong or file truncated)");
        std::vector<float> values(static_cast<std::size_t>(count));
        std::uint64_t i = 0;
        for (const auto& r : a_.text) i = ascii_range(r, values, i);
        if (i != count)
            fail_at(a_.tag_pos, what_ + " has only " + std::to_string(i) + " of " + std::to_string(count) + " values (truncated?)");
        return values;
    }

    // The numbers of one text range into values[i...]; returns the next index.
    std::uint64_t ascii_range(const TextRange& r, std::vector<float>& values, std::uint64_t i) const {
        const unsigned char* d = c_.source().data;
        std::size_t pos = r.begin;
        while (true) {
            while (pos < r.end && Cursor::is_space(d[pos])) ++pos;
            if (pos >= r.end) return i;
            std::size_t start = pos;
            while (pos < r.end && !Cursor::is_space(d[pos])) ++pos;
            std::string_view token = c_.view(start, pos);
            if (i == values.size())
                fail_at(start, what_ + " has more than the " + std::to_string(values.size()) +
                                   " values NumberOfPoints and NumberOfComponents call for");
            float v = 0.0f;
            if (!parse_float(token, v)) fail_at(start, "bad value " + quote(token) + " in " + what_ + " (expected a number)");
            values[static_cast<std::size_t>(i++)] = v;
        }
    }
};

}  // namespace

std::string array_label(const DataArray& a, std::size_t piece, std::size_t pieces) {
    std::string s = a.is_points ? std::string("Points DataArray") : "DataArray " + quote(a.name);
    return pieces > 1 ? s + " of piece " + std::to_string(piece) : s;
}

std::vector<float> decode_array(const Cursor& c, const File& file, const DataArray& a, std::uint64_t tuples, const std::string& label) {
    return ArrayDecoder(c, file, a, label).decode(tuples);
}

}  // namespace vtu
}  // namespace io_detail
}  // namespace meniscus
