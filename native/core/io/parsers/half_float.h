// IEEE 754 half precision (binary16) to float, as NumPy's float16 and Houdini's real16 store it.
#pragma once
#include <cstdint>

namespace meniscus {
namespace io_detail {

// The float with the same value as the half-precision bit pattern `bits` (every half is exactly a float):
// subnormals, signed zeros, infinities and NaNs (payload kept) included.
float half_to_float(std::uint16_t bits);

}  // namespace io_detail
}  // namespace meniscus
