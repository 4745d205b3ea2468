#pragma once
// Angle units, named by what they convert: multiply an angle in degrees by kRadPerDeg to
// get radians, one in radians by kDegPerRad to get degrees. Every layer uses these; a local
// degree constant (`kDeg`, `kDegree`, ...) is refused by scripts/check_units.py.
#include <numbers>

namespace doorbench {

inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace doorbench
