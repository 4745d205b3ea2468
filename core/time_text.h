#pragma once
// Dates and times as text: ISO 8601 in UTC, the one form doorbench writes and takes on the
// command line (a session's start, a record's expiry).
#include <string>

namespace doorbench {

// "" when `text` is an ISO 8601 date (YYYY-MM-DD) or UTC time (YYYY-MM-DDTHH:MM[:SS[.fraction]]Z)
// on the calendar; else why not: "TEXT is not an ISO 8601 date (YYYY-MM-DD, or
// YYYY-MM-DDTHH:MM:SSZ in UTC)" or "TEXT is not a day of the calendar".
std::string iso8601_utc_problem(const std::string& text);

}  // namespace doorbench
