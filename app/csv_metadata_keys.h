#pragma once
#include "acquisition/session/recording_csv.h"

// The metadata keys `export` writes into a CSV and `import` reads back (docs/csv-format.md),
// so that a session's rig, operator, product and start survive the round trip.
namespace doorbench::app {

inline constexpr const char* kCsvRigKey = "rig";
inline constexpr const char* kCsvOperatorKey = "operator";
inline constexpr const char* kCsvProductKey = "product";
inline constexpr const char* kCsvStartKey = kStartTimeKey;

}  // namespace doorbench::app
