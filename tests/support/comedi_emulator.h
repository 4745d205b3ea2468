#pragma once
// The comedi emulator library built beside the tests (tests/comedi_emulator, its path in
// DOORBENCH_COMEDI_EMULATOR), loaded through the same entry points as libcomedi. Header-only,
// test code.
#include "sensors/comedi_api.h"

namespace doorbench::testing {

inline const sensors::ComediApi& comedi_emulator() {
  return sensors::load_comedi_library(DOORBENCH_COMEDI_EMULATOR);
}

}  // namespace doorbench::testing
