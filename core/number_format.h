#pragma once
// Numbers as text, one family for every report, message and file:
//
//   format_number(x)            the shortest text that reads back as exactly x ("0.1",
//                               "1e+300", "nan", "inf"): files and messages that quote a value
//   format_significant(x, n)    n significant digits as printf's %.<n>g ("10.9195"), "-" for
//                               NaN (a value not computed), "inf"/"-inf": report tables
//   printf_text(pattern, ...)   printf-style formatting into a std::string
//
// Pure functions: safe from any thread.
#include <string>

namespace doorbench {

std::string format_number(double value);
std::string format_significant(double value, int digits);
std::string printf_text(const char* pattern, ...) __attribute__((format(printf, 1, 2)));

}  // namespace doorbench
