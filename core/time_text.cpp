#include "core/time_text.h"

#include <cstdio>
#include <ctime>
#include <stdexcept>

namespace doorbench {

std::string iso8601_utc_problem(const std::string& text) {
  const std::string form = " is not an ISO 8601 date (YYYY-MM-DD, or YYYY-MM-DDTHH:MM:SSZ in UTC)";
  const auto digits = [&](std::size_t at, std::size_t count) {
    if (at + count > text.size()) return -1;
    int value = 0;
    for (std::size_t i = at; i < at + count; ++i) {
      if (text[i] < '0' || text[i] > '9') return -1;
      value = value * 10 + (text[i] - '0');
    }
    return value;
  };
  const int year = digits(0, 4), month = digits(5, 2), day = digits(8, 2);
  if (year < 0 || month < 0 || day < 0 || text[4] != '-' || text[7] != '-') return text + form;
  if (text.size() > 10) {  // THH:MM[:SS[.fraction]]Z
    const int hour = digits(11, 2), minute = digits(14, 2);
    std::size_t end = 16;
    int second = 0;
    if (text.size() > 17 && text[16] == ':') {
      second = digits(17, 2);
      end = 19;
      if (text.size() > 20 && text[19] == '.') {
        for (end = 20; end < text.size() && text[end] >= '0' && text[end] <= '9';) ++end;
        if (end == 20) return text + form;
      }
    }
    // hour and minute >= 0: the text reaches index 15, so [10] and [13] are in it.
    if (hour < 0 || minute < 0 || text[10] != 'T' || text[13] != ':' || hour > 23 || minute > 59 ||
        second < 0 || second > 59 || end + 1 != text.size() || text[end] != 'Z') {
      return text + form;
    }
  }
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  const int days[] = {31, leap ? 29 : 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month < 1 || month > 12 || day < 1 || day > days[month - 1]) {
    return text + " is not a day of the calendar";
  }
  return "";
}

std::string utc_now_iso8601() {
  return iso8601_utc_text(static_cast<std::int64_t>(std::time(nullptr)));
}

std::string iso8601_utc_text(std::int64_t unix_s, std::int64_t fraction, int fraction_digits) {
  std::int64_t units = 1;
  for (int i = 0; i < fraction_digits; ++i) units *= 10;
  if (fraction_digits < 0 || fraction_digits > 9 || fraction < 0 || fraction >= units) {
    throw std::invalid_argument("iso8601_utc_text: fraction " + std::to_string(fraction) +
                                " is not from 0 to 10^" + std::to_string(fraction_digits) +
                                " - 1 with 0 to 9 digits");
  }
  const auto time = static_cast<std::time_t>(unix_s);
  std::tm utc{};
  gmtime_r(&time, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%S", &utc);
  if (fraction_digits == 0) return std::string(date) + "Z";
  char text[48];
  std::snprintf(text, sizeof text, "%s.%0*lldZ", date, fraction_digits,
                static_cast<long long>(fraction));
  return text;
}

}  // namespace doorbench
