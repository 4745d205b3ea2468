#pragma once
// A recorded session's clock origin (its "clock" group's origin_monotonic_ns attribute): the
// monotonic instant of sample time zero. Header-only, test code.
#include <cstdint>
#include <string>

#include "acquisition/session/session_file.h"

namespace doorbench::testing {

inline std::int64_t session_origin_ns(const SessionReader& session) {
  return std::stoll(session.read_group_attribute("clock", "origin_monotonic_ns"));
}

}  // namespace doorbench::testing
