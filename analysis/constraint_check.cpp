#include "analysis/constraint_check.h"

#include <charconv>

namespace doorbench {

std::string format_number(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

}  // namespace doorbench
