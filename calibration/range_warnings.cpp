#include "calibration/range_warnings.h"

#include <cmath>
#include <numbers>

#include "calibration/inclinometer_calibration.h"
#include "calibration/procedure.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "core/units.h"
#include "sensors/channel_limits.h"

namespace doorbench::calibration {

namespace {

// "left its ±100 °/s range 3 times for 1.234 s in all (first at 0.980 s)", or "" when no
// sample is out.
std::string excursions(const std::vector<double>& time_s, const std::vector<bool>& out,
                       const std::string& range) {
  std::size_t runs = 0;
  double total_s = 0.0, first_s = 0.0, run_start_s = 0.0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!out[i]) continue;
    if (i == 0 || !out[i - 1]) {
      if (runs == 0) first_s = time_s[i];
      ++runs;
      run_start_s = time_s[i];
    }
    if (i + 1 == out.size() || !out[i + 1]) total_s += time_s[i] - run_start_s;
  }
  if (runs == 0) return "";
  return "left its " + range + " range " + std::to_string(runs) + (runs == 1 ? " time" : " times") +
         " for " + fixed(total_s, 3) + " s in all (first at " + fixed(first_s, 3) + " s)";
}

std::string record_range(const CalibrationRecord& r) {
  return shortest(r.valid_min) + " to " + shortest(r.valid_max) + " " + r.unit + " (record " +
         r.id + ")";
}

}  // namespace

std::string RangeWarningOptions::validate() const {
  if (!(record_tolerance_fraction >= 0)) {
    return "range warnings record_tolerance_fraction = " + shortest(record_tolerance_fraction) +
           " must be >= 0";
  }
  return "";
}

std::vector<std::string> range_warnings(const SessionReader& session,
                                        const RangeWarningOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::optional<RigDefinition> rig = session_rig(session);
  std::vector<std::string> warnings;
  for (const ChannelInfo& c : session.channels()) {
    const RigChannel* rc = rig ? rig->find_channel(c.name) : nullptr;
    if (rc && rc->sensor != c.sensor_kind) rc = nullptr;
    const std::string who = c.sensor_kind + " " + c.name + " ";
    if (c.sensor_kind == "inclinometer" && rc) {
      const std::string warning = inclinometer_range_warning(session, c.name);
      if (!warning.empty()) warnings.push_back(warning);
      continue;
    }
    if (c.sensor_kind == "gyroscope" && rc) {
      const GyroscopeParameters p = gyroscope_parameters(*rc);
      const ChannelSignal s = read_channel_signal(session, c.name);
      const double limit_V = sensors::gyroscope_limit_V(p);
      std::vector<bool> out(s.signal.size());
      for (std::size_t i = 0; i < out.size(); ++i) out[i] = std::abs(s.signal[i]) >= limit_V;
      const std::string text = excursions(s.time_s, out, "±" + shortest(p.range_dps) + " °/s");
      if (!text.empty()) {
        warnings.push_back(who + text + " (saturated); those samples are not rates");
      }
      continue;
    }
    const ChannelSignal s = read_channel_signal(session, c.name);
    if (!s.record || !std::isfinite(s.record->valid_min) || !std::isfinite(s.record->valid_max)) {
      if (c.sensor_kind == "inclinometer") {
        warnings.push_back(who +
                           "range not checked: the session has no rig with this channel and its "
                           "record states no valid range");
      }
      continue;
    }
    const CalibrationRecord& r = *s.record;
    const double tolerance = options.record_tolerance_fraction * (r.valid_max - r.valid_min);
    std::vector<bool> out(s.physical.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = s.physical[i] < r.valid_min - tolerance || s.physical[i] > r.valid_max + tolerance;
    }
    const std::string text = excursions(s.time_s, out, record_range(r));
    if (!text.empty()) {
      warnings.push_back(who + text + "; those values are outside its calibration");
    }
  }
  return warnings;
}

}  // namespace doorbench::calibration
