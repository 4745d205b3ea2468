#include "core/number_format.h"

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace doorbench {

std::string format_number(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

std::string format_significant(double value, int digits) {
  if (std::isnan(value)) return "-";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return printf_text("%.*g", digits, value);
}

std::string printf_text(const char* pattern, ...) {
  va_list arguments;
  va_start(arguments, pattern);
  va_list copy;
  va_copy(copy, arguments);
  const int size = std::vsnprintf(nullptr, 0, pattern, copy);
  va_end(copy);
  std::string text(size > 0 ? static_cast<std::size_t>(size) : 0, '\0');
  if (size > 0) std::vsnprintf(text.data(), text.size() + 1, pattern, arguments);
  va_end(arguments);
  return text;
}

std::string format_fixed(double value, int decimals) {
  if (std::isnan(value)) return "-";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::string text = printf_text("%.*f", decimals, value);
  // A negative value that rounds to zero reads as zero.
  if (text.front() == '-' && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}

std::string format_p_value(double p) {
  if (std::isnan(p)) return "-";
  if (p < 0.001) return "< 0.001";
  if (p >= 1.0) return "1";
  if (p > 0.999) return "> 0.999";
  return printf_text("%.3g", p);
}

std::string p_value_text(double p) {
  const std::string value = format_p_value(p);
  return value.front() == '<' || value.front() == '>' ? "p " + value : "p = " + value;
}

std::string format_readable(double value) {
  return printf_text("%.10g", value);
}

std::string format_percent(double fraction, int decimals) {
  if (!std::isfinite(fraction)) return "-";
  return printf_text("%.*f%%", decimals, 100.0 * fraction);
}

std::string format_signed_percent(double fraction, int decimals) {
  if (!std::isfinite(fraction)) return "-";
  return printf_text("%+.*f%%", decimals, 100.0 * fraction);
}

std::string format_percent_at_most(double fraction, int decimals, double limit) {
  if (std::isfinite(fraction) && fraction > limit) {
    return "> " + printf_text("%.0f%%", 100.0 * limit);
  }
  return format_percent(fraction, decimals);
}

}  // namespace doorbench
