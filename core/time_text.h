#pragma once
// Dates and times as text: ISO 8601 in UTC, the one form doorbench writes and takes on the
// command line (a session's start, a record's expiry).
#include <cstdint>
#include <string>

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

}  // namespace doorbench
