#pragma once
// Numbers as text, one family for every report, message and file:
//
//   format_number(x)            the shortest text that reads back as exactly x ("0.1",
//                               "1e+300", "nan", "inf"): files and messages that quote a value
//   format_significant(x, n)    n significant digits as printf's %.<n>g ("10.9195"), "-" for
//                               NaN (a value not computed), "inf"/"-inf": report tables
//   printf_text(pattern, ...)   printf-style formatting into a std::string
//   format_fixed(x, d)          d decimals as printf's %.<d>f, never "-0.00" ("0.00"), "-"
//                               for NaN, "inf"/"-inf": a report column of estimates
//   format_p_value(p)           a p-value as statisticians write it: "< 0.001" below 0.001,
//                               else 3 significant digits ("0.0123", "0.148"), "> 0.999"
//                               just below 1, "1" at 1, "-" for NaN
//   p_value_text(p)             "p < 0.001" or "p = 0.148": a p-value in a sentence
//   format_percent(f, d)        a fraction as a percentage with d decimals (0.123, 1 ->
//                               "12.3%"), "-" for NaN or an infinity
//   format_signed_percent(f, d) the same with its sign always written ("+12.3%", "-0.5%")
//   format_percent_at_most(f, d, limit)
//                               format_percent up to `limit` (a fraction), "> " and the
//                               limit's percentage above it (limit 10: "> 1000%"; "-" for NaN
//                               or an infinity): a relative uncertainty whose size past the
//                               limit says only "undetermined"
//   format_readable(x)          a value or a limit in a message as people write it: 10
//                               significant digits, no exponent below 1e10 ("1000000000",
//                               "0.05", "1.21" where format_number says 1.2100000000000002),
//                               "nan", "inf"/"-inf"
//
// Pure functions: safe from any thread.
#include <string>

namespace doorbench {

std::string format_number(double value);
std::string format_significant(double value, int digits);
std::string printf_text(const char* pattern, ...) __attribute__((format(printf, 1, 2)));
std::string format_fixed(double value, int decimals);
std::string format_p_value(double p);
std::string p_value_text(double p);
std::string format_readable(double value);
std::string format_percent(double fraction, int decimals);
std::string format_signed_percent(double fraction, int decimals);
std::string format_percent_at_most(double fraction, int decimals, double limit);

}  // namespace doorbench
