#include "io/parsers/half_float.h"

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h >> 15) << 31;
    std::uint32_t exponent = (h >> 10) & 31, mantissa = h & 1023;
    if (exponent == 31) return bits_to_float(sign | 0x7f800000u | (mantissa << 13));  // inf / nan
    if (exponent == 0) {
        if (mantissa == 0) return bits_to_float(sign);
        // Subnormal: shift the mantissa up until its leading 1 is the implicit bit of a normal float.
        int shift = 0;
        while (!(mantissa & 1024)) {
            mantissa <<= 1;
            ++shift;
        }
        return bits_to_float(sign | (std::uint32_t(127 - 15 + 1 - shift) << 23) | ((mantissa & 1023) << 13));
    }
    return bits_to_float(sign | ((exponent + 127 - 15) << 23) | (mantissa << 13));
}

}  // namespace io_detail
}  // namespace meniscus
