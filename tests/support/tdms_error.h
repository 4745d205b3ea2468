#pragma once
// What parse_tdms (acquisition/session/tdms.h) says about a file's bytes: its TdmsError's
// message, or "(no error)" when they parse. Header-only, test code.
#include <cstdint>
#include <string>
#include <vector>

#include "acquisition/session/tdms.h"

namespace doorbench::testing::tdms {

inline std::string error_of(const std::vector<std::uint8_t>& bytes) {
  try {
    parse_tdms(bytes, "mem.tdms");
  } catch (const TdmsError& error) {
    return error.what();
  }
  return "(no error)";
}

}  // namespace doorbench::testing::tdms
