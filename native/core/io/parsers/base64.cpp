#include "io/parsers/base64.h"

namespace meniscus {
namespace io_detail {

namespace {

// The 6-bit value of a base64 character, or -1.
int sextet(int ch) {
    if (ch >= 'A' && ch <= 'Z') return ch - 'A';
    if (ch >= 'a' && ch <= 'z') return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9') return ch - '0' + 52;
    if (ch == '+') return 62;
    if (ch == '/') return 63;
    return -1;
}

}  // namespace

Base64Reader::Base64Reader(const Cursor& c, std::vector<TextRange> ranges, std::string what)
    : c_(c), ranges_(std::move(ranges)), what_(std::move(what)) {
    for (const auto& r : ranges_) chars_left_ += r.end - r.begin;
    if (!ranges_.empty()) pos_ = ranges_[0].begin;
}

void Base64Reader::read(unsigned char* out, std::uint64_t n) {
    for (std::uint64_t i = 0; i < n; ++i) {
        if (pending_pos_ == pending_end_ && !refill())
            c_.fail("truncated base64 data in " + what_ + ": it ends after " + std::to_string(decoded_) + " bytes, more were needed");
        out[i] = pending_[pending_pos_++];
        ++decoded_;
    }
}

// Next significant character and its position, or -1 at the end.
int Base64Reader::next_char(std::size_t& at) {
    while (range_ < ranges_.size()) {
        if (pos_ >= ranges_[range_].end) {
            if (++range_ < ranges_.size()) pos_ = ranges_[range_].begin;
            continue;
        }
        unsigned char ch = c_.source().data[pos_];
        at = pos_++;
        --chars_left_;
        if (!Cursor::is_space(ch)) return ch;
    }
    return -1;
}

// Decodes the next group of up to four characters; false at the end of the text.
bool Base64Reader::refill() {
    int values[4];
    int count = 0, padding = 0;
    std::size_t at = 0;
    while (count + padding < 4) {
        int ch = next_char(at);
        if (ch < 0) break;
        if (ch == '=') {
            if (count < 2) c_.fail("bad base64 padding at " + c_.where(at) + " in " + what_);
            ++padding;
            continue;
        }
        if (padding > 0) c_.fail("bad base64 padding at " + c_.where(at) + " in " + what_);
        int v = sextet(ch);
        if (v < 0)
            c_.fail("invalid base64 character " + quote(std::string(1, static_cast<char>(ch))) + " at " + c_.where(at) + " in " + what_);
        values[count++] = v;
    }
    if (count < 2) {
        if (count == 1) c_.fail("truncated base64 data in " + what_ + ": a lone character at " + c_.where(at));
        return false;
    }
    for (int k = count; k < 4; ++k) values[k] = 0;
    std::uint32_t bits = (std::uint32_t(values[0]) << 18) | (std::uint32_t(values[1]) << 12) | (std::uint32_t(values[2]) << 6) |
                         std::uint32_t(values[3]);
    pending_[0] = static_cast<unsigned char>(bits >> 16);
    pending_[1] = static_cast<unsigned char>(bits >> 8);
    pending_[2] = static_cast<unsigned char>(bits);
    pending_pos_ = 0;
    pending_end_ = count - 1;  // 2 characters give 1 byte, 3 give 2, 4 give 3
    return true;
}

}  // namespace io_detail
}  // namespace meniscus
