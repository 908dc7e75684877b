#include "io/parsers/zip.h"

#include <zlib.h>

#include <algorithm>

namespace meniscus {
namespace io_detail {
namespace {

// Record signatures ("PK" and two bytes) and fixed record sizes.
constexpr std::uint32_t kLocalHeader = 0x04034b50u, kCentralHeader = 0x02014b50u, kEndRecord = 0x06054b50u,
                        kZip64EndRecord = 0x06064b50u, kZip64Locator = 0x07064b50u;
constexpr std::size_t kEndRecordSize = 22, kCentralHeaderSize = 46, kLocalHeaderSize = 30, kMaxComment = 65535;

std::string method_name(std::uint16_t method) {
    switch (method) {
        case 12: return " (bzip2)";
        case 14: return " (LZMA)";
        case 93: return " (Zstandard)";
        case 95: return " (XZ)";
        case 9: return " (deflate64)";
        default: return "";
    }
}

std::uint32_t crc32_of(const Bytes& data) {
    std::uint32_t crc = 0;
    for (std::size_t off = 0; off < data.size(); off += 1u << 30)  // zlib counts in 32-bit units
        crc = static_cast<std::uint32_t>(crc32(crc, data.data() + off, static_cast<uInt>(std::min<std::size_t>(data.size() - off, 1u << 30))));
    return crc;
}

}  // namespace

// The end-of-central-directory record sits in the last 22 + 65535 (comment) bytes.
std::size_t ZipReader::find_end_record() const {
    const std::size_t size = c_.size();
    const unsigned char* d = c_.source().data;
    if (size < kEndRecordSize)
        c_.fail("not a zip archive (.npz): " + std::to_string(size) + " bytes are too few for the end record (truncated?)");
    for (std::size_t i = size - kEndRecordSize + 1; i-- > 0 && size - i <= kEndRecordSize + kMaxComment;)
        if (load_le32(d + i) == kEndRecord) return i;
    c_.fail("no zip end-of-central-directory record in the last " +
            std::to_string(std::min<std::size_t>(size, kEndRecordSize + kMaxComment)) +
            " bytes: the .npz archive is truncated or not a zip");
}

std::vector<ZipMember> ZipReader::members() {
    const std::size_t size = c_.size();
    const unsigned char* d = c_.source().data;
    const std::size_t eocd = find_end_record();
    std::uint64_t entries = load_le16(d + eocd + 10);
    std::uint64_t cd_size = load_le32(d + eocd + 12);
    std::uint64_t cd_offset = load_le32(d + eocd + 16);
    if (load_le16(d + eocd + 4) != 0 || load_le16(d + eocd + 6) != 0) c_.fail("multi-part (split) zip archives are not supported");
    if (entries == 0xffff || cd_size == 0xffffffffu || cd_offset == 0xffffffffu) {
        // zip64: a locator just before the end record points at the zip64 end record.
        if (eocd < 20 || load_le32(d + eocd - 20) != kZip64Locator) c_.fail("zip64 archive without a zip64 end locator at " + c_.where(eocd));
        std::uint64_t record = load_le64(d + eocd - 20 + 8);
        if (record > size || size - record < 56 || load_le32(d + record) != kZip64EndRecord)
            c_.fail("the zip64 end record offset " + std::to_string(record) + " does not point at a zip64 end record");
        entries = load_le64(d + record + 32);
        cd_size = load_le64(d + record + 40);
        cd_offset = load_le64(d + record + 48);
    }
    if (cd_offset > size || cd_size > size - cd_offset)
        c_.fail("the zip central directory (" + std::to_string(cd_size) + " bytes at offset " + std::to_string(cd_offset) +
                ") lies outside the " + std::to_string(size) + "-byte file (truncated?)");
    if (entries > cd_size / kCentralHeaderSize)
        c_.fail("the zip central directory claims " + std::to_string(entries) + " members but has room for " +
                std::to_string(cd_size / kCentralHeaderSize));
    std::vector<ZipMember> out;
    out.reserve(static_cast<std::size_t>(entries));
    Cursor cd(c_.source());
    cd.seek(static_cast<std::size_t>(cd_offset));
    const std::size_t cd_end = static_cast<std::size_t>(cd_offset + cd_size);
    for (std::uint64_t e = 0; e < entries; ++e) {
        std::size_t at = cd.pos();
        if (cd_end - at < kCentralHeaderSize || load_le32(cd.here()) != kCentralHeader)
            c_.fail("bad zip central directory entry " + std::to_string(e) + " at " + c_.where(at));
        const unsigned char* h = cd.take(kCentralHeaderSize, "zip central directory entry");
        ZipMember m;
        m.flags = load_le16(h + 8);
        m.method = load_le16(h + 10);
        m.crc = load_le32(h + 16);
        m.compressed = load_le32(h + 20);
        m.uncompressed = load_le32(h + 24);
        std::uint16_t name_length = load_le16(h + 28), extra_length = load_le16(h + 30), comment_length = load_le16(h + 32);
        m.local_offset = load_le32(h + 42);
        if (std::uint64_t(name_length) + extra_length + comment_length > cd_end - cd.pos())
            c_.fail("zip central directory entry " + std::to_string(e) + " at " + c_.where(at) + " runs past the directory");
        const unsigned char* name = cd.take(name_length, "zip member name");
        m.name.assign(reinterpret_cast<const char*>(name), name_length);
        const unsigned char* extra = cd.take(extra_length, "zip extra field");
        cd.take(comment_length, "zip member comment");
        read_zip64_extra(extra, extra_length, m);
        out.push_back(std::move(m));
    }
    return out;
}

Bytes ZipReader::extract(const ZipMember& m, std::uint64_t& budget) {
    const std::string what = "zip member " + quote(m.name);
    if (m.flags & 1) c_.fail(what + " is encrypted; encrypted archives are not supported");
    if (m.method != 0 && m.method != 8)
        c_.fail(what + " uses compression method " + std::to_string(m.method) + method_name(m.method) +
                "; only stored (0) and deflate (8) are supported (numpy.savez and savez_compressed write these)");
    const std::size_t size = c_.size();
    const unsigned char* d = c_.source().data;
    if (m.local_offset > size || size - m.local_offset < kLocalHeaderSize || load_le32(d + m.local_offset) != kLocalHeader)
        c_.fail(what + ": no local header at offset " + std::to_string(m.local_offset) + " (truncated or corrupt archive)");
    std::uint64_t data = m.local_offset + kLocalHeaderSize + load_le16(d + m.local_offset + 26) + load_le16(d + m.local_offset + 28);
    if (data > size || m.compressed > size - data)
        c_.fail(what + ": its " + std::to_string(m.compressed) + " bytes at offset " + std::to_string(data) +
                " run past the end of the " + std::to_string(size) + "-byte file (truncated?)");
    Bytes out;
    if (m.method == 0) {
        if (m.compressed != m.uncompressed)
            c_.fail(what + " is stored but its sizes differ (" + std::to_string(m.compressed) + " and " + std::to_string(m.uncompressed) + ")");
        out.assign(d + data, d + data + m.compressed);
    } else {
        if (m.uncompressed > max_inflated_size(m.compressed) || m.uncompressed > budget)
            c_.fail(what + ": " + std::to_string(m.compressed) + " compressed bytes claim to hold " + std::to_string(m.uncompressed) +
                    ", beyond any real data; refusing a corrupt file or decompression bomb");
        budget -= m.uncompressed;
        out.resize(static_cast<std::size_t>(m.uncompressed));
        inflate_exact(c_.source().path, d + data, static_cast<std::size_t>(m.compressed), out.data(), out.size(), -15, what);
    }
    if (crc32_of(out) != m.crc) c_.fail(what + ": CRC-32 mismatch, the archive is corrupt");
    return out;
}

// Zip64 extended information (id 1): the 64-bit values of those fixed fields that hold 0xffffffff, in order.
void ZipReader::read_zip64_extra(const unsigned char* extra, std::size_t length, ZipMember& m) const {
    std::size_t i = 0;
    while (i + 4 <= length) {
        std::uint16_t id = load_le16(extra + i), n = load_le16(extra + i + 2);
        if (n > length - i - 4) break;
        if (id == 1) {
            const unsigned char* p = extra + i + 4;
            std::size_t left = n;
            auto next = [&](std::uint64_t& field) {
                if (field != 0xffffffffu) return;
                if (left < 8) c_.fail("zip member " + quote(m.name) + ": truncated zip64 extra field");
                field = load_le64(p);
                p += 8;
                left -= 8;
            };
            next(m.uncompressed);
            next(m.compressed);
            next(m.local_offset);
        }
        i += 4 + n;
    }
}

}  // namespace io_detail
}  // namespace meniscus
