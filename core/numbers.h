#pragma once
// Named numbers every layer shares. kNaN is the quiet NaN that stands for "not measured" or
// "not defined" in results, tables and reports (written as "-" by format_significant, as
// null in JSON by the writers that say so). One definition, so that no source file keeps
// its own (a unity build of a library would see two).
#include <limits>

namespace doorbench {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace doorbench
