#pragma once
// Dates and times as text: ISO 8601 in UTC, the one form doorbench writes and takes on the
// command line (a session's start, a record's expiry).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace doorbench {

// "" when `text` is an ISO 8601 date (YYYY-MM-DD) or UTC time (YYYY-MM-DDTHH:MM[:SS[.fraction]]Z)
// on the calendar; else why not: "TEXT is not an ISO 8601 date (YYYY-MM-DD, or
// YYYY-MM-DDTHH:MM:SSZ in UTC)" or "TEXT is not a day of the calendar".
std::string iso8601_utc_problem(const std::string& text);

// "YYYY-MM-DDTHH:MM:SSZ": the present moment from the system clock, to the second.
std::string utc_now_iso8601();

// "YYYY-MM-DDTHH:MM:SS.fZ" of `unix_s` seconds since 1970-01-01 UTC plus `fraction` units of
// 10^-fraction_digits s (fraction_digits 1..9, 0 <= fraction < 10^fraction_digits; with
// fraction_digits 0 no fraction is written). Throws std::invalid_argument outside those
// ranges.
std::string iso8601_utc_text(std::int64_t unix_s, std::int64_t fraction = 0,
                             int fraction_digits = 0);

// A date and time as a logger writes it (parse_date_time).
struct DateTimeText {
  std::int64_t seconds = 0;  // since 1970-01-01T00:00:00 on its own clock (UTC when zone_known)
  double fraction_s = 0.0;   // the fraction of the second, [0, 1)
  bool zone_known = false;   // the text ends in Z or an offset, so `seconds` are UTC
  bool date_known = true;    // false for a time of the day alone: `seconds` since its midnight
};

// "YYYY-MM-DD hh:mm:ss", 'T' or one space between date and time, seconds optional, a fraction
// after '.' of any number of digits, then optionally 'Z' or an offset +hh:mm, +hhmm or +hh
// (- too), with spaces around it allowed; nullopt for anything else or a day that is not on
// the calendar. An offset is taken off: 08:00:00+01:00 is 07:00:00 UTC. A time of the day alone,
// "hh:mm[:ss[.fraction]]" without a zone, is read as seconds since its midnight (date_known
// false).
std::optional<DateTimeText> parse_date_time(std::string_view text);

}  // namespace doorbench
