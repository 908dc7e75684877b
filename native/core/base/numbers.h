// Mathematical constants. M_PI is not standard C++: MSVC and mingw define it only with _USE_MATH_DEFINES.
#pragma once

namespace meniscus {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace meniscus
