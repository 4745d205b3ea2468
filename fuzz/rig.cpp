// Fuzzes the rig file parser (acquisition/rig/rig_file.h): any text gives a rig or a RigError
// naming file, line and key; nothing else may escape, crash or be undefined. Paths in the
// text are resolved against a folder that does not exist, so nothing is read.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "acquisition/rig/rig_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    doorbench::parse_rig(text, "fuzz.toml", "/nonexistent-doorbench-fuzz");
  } catch (const doorbench::RigError&) {
  }
  return 0;
}
