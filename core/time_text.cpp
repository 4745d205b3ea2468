#include "core/time_text.h"

#include <cstdio>
#include <ctime>
#include <stdexcept>

namespace doorbench {
namespace {

// Reads `count` digits at `at`; -1 when they are not all there.
int read_digits(std::string_view text, std::size_t at, std::size_t count) {
  if (at + count > text.size()) return -1;
  int value = 0;
  for (std::size_t i = at; i < at + count; ++i) {
    if (text[i] < '0' || text[i] > '9') return -1;
    value = value * 10 + (text[i] - '0');
  }
  return value;
}

// True when year-month-day names a day of the proleptic Gregorian calendar.
bool is_calendar_day(int year, int month, int day) {
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  const int days[] = {31, leap ? 29 : 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month >= 1 && month <= 12 && day >= 1 && day <= days[month - 1];
}

}  // namespace

std::string iso8601_utc_problem(const std::string& text) {
  const std::string form = " is not an ISO 8601 date (YYYY-MM-DD, or YYYY-MM-DDTHH:MM:SSZ in UTC)";
  const auto digits = [&](std::size_t at, std::size_t count) {
    return read_digits(text, at, count);
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
  if (!is_calendar_day(year, month, day)) return text + " is not a day of the calendar";
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

namespace {

// Days from 1970-01-01 to year-month-day of the proleptic Gregorian calendar: whole 400-year
// eras of 146097 days, with March as the first month so that a leap day ends its year.
std::int64_t days_since_epoch(std::int64_t year, int month, int day) {
  const std::int64_t y = month <= 2 ? year - 1 : year;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const std::int64_t year_of_era = y - era * 400;                               // [0, 399]
  const int month_from_march = month > 2 ? month - 3 : month + 9;               // [0, 11]
  const std::int64_t day_of_year = (153 * month_from_march + 2) / 5 + day - 1;  // [0, 365]
  const std::int64_t day_of_era =
      year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
  return era * 146097 + day_of_era - 719468;  // 719468: days from 0000-03-01 to 1970-01-01
}

}  // namespace

namespace {

// "hh:mm[:ss[.fraction]]" at `at`: its seconds since midnight and fraction into `out`, and the
// index after it; npos when it is not one (or names no time of the day).
std::size_t read_clock(std::string_view text, std::size_t at, DateTimeText& out) {
  const int hour = read_digits(text, at, 2), minute = read_digits(text, at + 3, 2);
  if (hour < 0 || minute < 0 || text[at + 2] != ':' || hour > 23 || minute > 59) {
    return std::string_view::npos;
  }
  at += 5;
  int second = 0;
  if (at < text.size() && text[at] == ':') {
    second = read_digits(text, at + 1, 2);
    if (second < 0 || second > 59) return std::string_view::npos;
    at += 3;
    if (at < text.size() && text[at] == '.') {
      // The digits as an integer over a power of ten (one rounding); beyond 18, ignored.
      std::int64_t numerator = 0, denominator = 1;
      const std::size_t first = ++at;
      for (; at < text.size() && text[at] >= '0' && text[at] <= '9'; ++at) {
        if (at - first >= 18) continue;
        numerator = numerator * 10 + (text[at] - '0');
        denominator *= 10;
      }
      if (at == first) return std::string_view::npos;
      out.fraction_s = static_cast<double>(numerator) / static_cast<double>(denominator);
    }
  }
  out.seconds = hour * 3600 + minute * 60 + second;
  return at;
}

// A zone after the clock at `at` ("Z", "+01:00", "-0500", "+01", spaces before it allowed):
// its offset east of UTC in minutes, 0 and zone_known false when there is none, and the index
// after it; npos when what follows is no zone.
std::size_t read_zone(std::string_view text, std::size_t at, int& offset_minutes,
                      bool& zone_known) {
  while (at < text.size() && text[at] == ' ') ++at;
  offset_minutes = 0;
  zone_known = false;
  if (at < text.size() && text[at] == 'Z') {
    zone_known = true;
    ++at;
  } else if (at < text.size() && (text[at] == '+' || text[at] == '-')) {
    const int sign = text[at] == '+' ? 1 : -1;
    const int offset_hours = read_digits(text, at + 1, 2);
    if (offset_hours < 0 || offset_hours > 18) return std::string_view::npos;
    at += 3;
    int offset_extra = 0;
    if (at < text.size()) {
      const std::size_t digits_at = text[at] == ':' ? at + 1 : at;
      offset_extra = read_digits(text, digits_at, 2);
      if (offset_extra < 0 || offset_extra > 59) return std::string_view::npos;
      at = digits_at + 2;
    }
    offset_minutes = sign * (offset_hours * 60 + offset_extra);
    zone_known = true;
  }
  return at;
}

}  // namespace

std::optional<DateTimeText> parse_date_time(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  DateTimeText out;
  if (text.size() > 2 && text[2] == ':') {  // a time of the day alone
    out.date_known = false;
    if (read_clock(text, 0, out) != text.size()) return std::nullopt;
    return out;
  }
  const int year = read_digits(text, 0, 4), month = read_digits(text, 5, 2);
  const int day = read_digits(text, 8, 2);
  if (year < 0 || month < 0 || day < 0 || text.size() < 11 || text[4] != '-' || text[7] != '-' ||
      (text[10] != 'T' && text[10] != ' ') || !is_calendar_day(year, month, day)) {
    return std::nullopt;
  }
  int offset_minutes = 0;
  std::size_t at = read_clock(text, 11, out);
  if (at != std::string_view::npos) at = read_zone(text, at, offset_minutes, out.zone_known);
  if (at != text.size()) return std::nullopt;
  out.seconds += days_since_epoch(year, month, day) * 86400 - offset_minutes * 60;
  return out;
}

}  // namespace doorbench
