// `doorbench spec --felt-share`: the share as typed.
#include "app/spec_campaign.h"

#include <stdexcept>

#include "app/commands.h"
#include "core/numbers.h"

namespace doorbench::app {

double parse_felt_share(std::string_view text) {
  std::string number(text);
  const bool percent = !number.empty() && number.back() == '%';
  if (percent) number.pop_back();
  std::size_t used = 0;
  double value = kNaN;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (percent) value /= 100.0;
  if (used == 0 || used != number.size() || !(value > 0 && value < 1)) {
    throw UsageError("--felt-share: '" + std::string(text) +
                     "' is not a share between 0 and 1 (e.g. 5% or 0.05)");
  }
  return value;
}

}  // namespace doorbench::app
