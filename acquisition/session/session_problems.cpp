// SessionReader::problems(): the checks of a session as a whole (session_file.h).
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "acquisition/session/printable.h"
#include "acquisition/session/session_file.h"
#include "core/number_format.h"

namespace doorbench {
namespace {

// The time a channel on a sample clock ends: its first sample's time plus its samples'.
double clock_end_s(const SessionReader& session, const ChannelInfo& c) {
  return c.first_sample_time_s +
         static_cast<double>(session.sample_count(c.name)) / c.sample_rate_hz;
}

// Calibration records `c` names that the session lacks.
void add_missing_records(const ChannelInfo& c, const std::set<std::string>& records,
                         std::vector<SessionProblem>& problems) {
  for (const std::string* id : {&c.calibration_id, &c.geometry_calibration_id}) {
    if (id->empty() || records.count(*id) > 0) continue;
    problems.push_back({"channel " + printable(c.name) + " uses calibration record " +
                            printable(*id) +
                            ", which is not in the session: its values cannot be calibrated "
                            "(export and fit refuse the session)",
                        true});
  }
}

// An explicit-time channel whose times are not finite or do not increase.
void add_time_order(const SessionReader& session, const ChannelInfo& c,
                    std::vector<SessionProblem>& problems) {
  ChannelSlice slice;
  try {
    slice = session.read(c.name);
  } catch (const SessionError& error) {  // times that are not finite or go backwards
    problems.push_back({printable(error.what()), true});
    return;
  }
  for (std::size_t i = 1; i < slice.time_s.size(); ++i) {
    if (slice.time_s[i] > slice.time_s[i - 1]) continue;
    problems.push_back({"channel " + printable(c.name) + ": the time of sample " +
                            std::to_string(i) + " (" + printf_text("%g", slice.time_s[i]) +
                            " s) is not after sample " + std::to_string(i - 1) + " (" +
                            printf_text("%g", slice.time_s[i - 1]) + " s): its times go backwards",
                        true});
    return;
  }
}

}  // namespace

std::vector<SessionProblem> SessionReader::problems() const {
  std::vector<SessionProblem> problems;
  std::set<std::string> records;
  for (const CalibrationRecord& r : calibrations()) records.insert(r.id);
  // Channels on a sample clock end together; the one that ends last, and when.
  double last_end_s = -INFINITY;
  std::string last_name;
  for (const ChannelInfo& c : channels()) {
    add_missing_records(c, records, problems);
    if (c.sample_rate_hz > 0) {
      if (clock_end_s(*this, c) > last_end_s) {
        last_end_s = clock_end_s(*this, c);
        last_name = c.name;
      }
      continue;
    }
    add_time_order(*this, c, problems);
  }
  for (const ChannelInfo& c : channels()) {
    // More than one sample period short of the last: not a rounding of the clock.
    if (c.sample_rate_hz <= 0) continue;
    const double end_s = clock_end_s(*this, c);
    if (end_s >= last_end_s - 1.0 / c.sample_rate_hz) continue;
    problems.push_back(
        {"channel " + printable(c.name) + " has " + std::to_string(sample_count(c.name)) +
             " samples and ends at " +
             printf_text("%.6g s, %.6g s before", end_s, last_end_s - end_s) + " " +
             printable(last_name) +
             " (export leaves its cells empty from there; fit uses only the time where every "
             "channel has samples)",
         false});
  }
  return problems;
}

}  // namespace doorbench
