// Reading zip archives in memory (PKWARE APPNOTE): the central directory, zip64 records, stored and deflated
// members with their CRC-32 checked. Encrypted, split and otherwise compressed archives are refused by name. The
// only zips Meniscus reads are NumPy .npz files, so messages call the archive that.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

struct ZipMember {
    std::string name;
    std::uint16_t flags = 0, method = 0;
    std::uint32_t crc = 0;
    std::uint64_t compressed = 0, uncompressed = 0, local_offset = 0;
};

class ZipReader {
public:
    explicit ZipReader(const Source& source) : c_(source) {}

    // The members listed in the central directory, in order.
    std::vector<ZipMember> members();

    // The member's bytes, inflated if needed; `budget` is what the whole archive may still decompress to (members
    // claiming more, or more than max_inflated_size of their compressed size, are refused before inflating).
    Bytes extract(const ZipMember& m, std::uint64_t& budget);

private:
    Cursor c_;

    std::size_t find_end_record() const;
    void read_zip64_extra(const unsigned char* extra, std::size_t length, ZipMember& m) const;
};

}  // namespace io_detail
}  // namespace meniscus
