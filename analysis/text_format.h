#pragma once
// printf-style formatting into a std::string, for the reports' text.
#include <string>

namespace doorbench {

std::string printf_text(const char* pattern, ...) __attribute__((format(printf, 1, 2)));

}  // namespace doorbench
