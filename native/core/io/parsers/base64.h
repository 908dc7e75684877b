// Base64 decoding (RFC 4648, standard alphabet) of text spread over ranges of a source, as VTK XML stores binary
// DataArrays. White space is skipped. '=' ends a group of four early and decoding goes on after it: VTK encodes an
// array's header and its data as two base64 strings written back to back.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

class Base64Reader {
public:
    // `what` names the data in messages ("DataArray 'velocity'").
    Base64Reader(const Cursor& c, std::vector<TextRange> ranges, std::string what);

    // An upper bound of the bytes still to come, to check counts before allocating.
    std::uint64_t max_remaining() const { return chars_left_ / 4 * 3 + 3 + (pending_end_ - pending_pos_); }

    // Decodes the next n bytes into out; fewer left, or invalid characters, are FormatErrors.
    void read(unsigned char* out, std::uint64_t n);

private:
    const Cursor& c_;
    std::vector<TextRange> ranges_;
    std::string what_;
    std::size_t range_ = 0, pos_ = 0;
    std::uint64_t chars_left_ = 0, decoded_ = 0;
    unsigned char pending_[3] = {0, 0, 0};  // bytes of the current group not yet handed out
    int pending_pos_ = 0, pending_end_ = 0;

    int next_char(std::size_t& at);
    bool refill();
};

}  // namespace io_detail
}  // namespace meniscus
