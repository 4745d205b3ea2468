#include "acquisition/session/resample.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "acquisition/session/recording_csv.h"
#include "core/number_format.h"
#include "core/percentile.h"

namespace doorbench {

std::vector<double> resample_linear(std::span<const double> time_s, std::span<const double> values,
                                    std::span<const double> at, double max_gap_s,
                                    const std::string& what) {
  if (time_s.size() != values.size()) {
    throw std::invalid_argument(what + ": " + std::to_string(time_s.size()) + " times but " +
                                std::to_string(values.size()) + " values");
  }
  if (!(max_gap_s > 0)) throw std::invalid_argument(what + ": the gap limit must be > 0");
  for (std::size_t i = 1; i < time_s.size(); ++i) {
    if (!(time_s[i] > time_s[i - 1])) {
      throw std::invalid_argument(what + ": sample times do not increase at sample " +
                                  std::to_string(i));
    }
  }
  std::vector<double> out(at.size(), std::numeric_limits<double>::quiet_NaN());
  std::size_t k = 0;  // time_s[k] <= t < time_s[k + 1] for the current t
  for (std::size_t j = 0; j < at.size(); ++j) {
    const double t = at[j];
    if (j > 0 && !(t >= at[j - 1])) {
      throw std::invalid_argument(what + ": the target times do not increase at " +
                                  std::to_string(j));
    }
    if (time_s.empty() || t < time_s.front() || t > time_s.back()) continue;
    while (k + 1 < time_s.size() && time_s[k + 1] <= t) ++k;
    if (time_s[k] == t) {
      out[j] = values[k];
      continue;
    }
    const double span = time_s[k + 1] - time_s[k];
    if (span > max_gap_s) continue;  // a gap: marked, not bridged
    const double s = (t - time_s[k]) / span;
    out[j] = values[k] + s * (values[k + 1] - values[k]);
  }
  return out;
}

std::vector<double> uniform_axis(double start_s, double end_s, double rate_hz) {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("uniform axis: rate must be > 0");
  }
  std::vector<double> axis;
  if (!(end_s >= start_s)) return axis;
  const auto count = static_cast<std::size_t>(std::floor((end_s - start_s) * rate_hz + 1e-9)) + 1;
  axis.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    axis.push_back(start_s + static_cast<double>(i) / rate_hz);
  while (!axis.empty() && axis.back() > end_s) axis.pop_back();
  return axis;
}

namespace {

// One column at the times `at` (--resample-hz at rate_hz). Slower than the recording
// (rate_hz below 1 / its median interval): each new sample is the mean of the recorded ones
// nearest to its time, those within half a new interval, [t − 0.5/rate_hz, t + 0.5/rate_hz) (a
// boxcar against aliasing), missing (NaN) when none is there or one of them is missing. Otherwise
// linear interpolation between the two samples around it, missing across a gap of more than
// kGapIntervals median intervals (acquisition/session/resample.h).
std::vector<double> resample_column(const std::vector<double>& time_s,
                                    const std::vector<double>& values,
                                    const std::vector<double>& at, double rate_hz, double median_s,
                                    const std::string& what) {
  if (rate_hz * median_s >= 1.0) {
    return resample_linear(time_s, values, at, kGapIntervals * median_s, what);
  }
  // Each recorded sample to the new time nearest to it, k = ⌊(t − at[0])·rate_hz + ½⌋ (a part
  // in 10⁹ of slack, so that 0.014 s is halfway between 0.012 and 0.016 at 250 Hz, and a tie
  // goes to the later time).
  std::vector<double> sum(at.size(), 0.0);
  std::vector<std::size_t> count(at.size(), 0);
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    const double k = std::floor((time_s[i] - at.front()) * rate_hz + 0.5 + 1e-9);
    if (!(k >= 0) || k >= static_cast<double>(at.size())) continue;
    sum[static_cast<std::size_t>(k)] += values[i];  // a missing sample makes the mean missing
    ++count[static_cast<std::size_t>(k)];
  }
  std::vector<double> out(at.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (count[k] > 0) out[k] = sum[k] / static_cast<double>(count[k]);
  }
  return out;
}

}  // namespace

Recording resample_recording(const Recording& in, double rate_hz) {
  if (in.size() < 2) throw std::runtime_error(in.source + ": too few samples to resample");
  const double median_s = median_interval_s(in.time_s);
  Recording out;
  out.source = in.source;
  out.metadata = in.metadata;
  out.handle_radius_m = in.handle_radius_m;
  out.sample_rate_hz = rate_hz;
  out.time_s = uniform_axis(in.time_s.front(), in.time_s.back(), rate_hz);
  const auto column = [&](const std::vector<double>& values, std::string_view name) {
    return resample_column(in.time_s, values, out.time_s, rate_hz, median_s,
                           in.source + ": column " + std::string(name));
  };
  out.force_N = column(in.force_N, kForceColumn);
  if (in.angle_rad) out.angle_rad = column(*in.angle_rad, kAngleColumn);
  if (in.rate_rad_s) out.rate_rad_s = column(*in.rate_rad_s, kRateColumn);
  out.calibrations = in.calibrations;
  out.extra_names = in.extra_names;
  for (std::size_t j = 0; j < in.extra_columns.size(); ++j) {
    out.extra_columns.push_back(column(in.extra_columns[j], in.extra_names[j]));
  }
  if (in.stroke) {
    out.stroke.emplace(out.size(), 0);
    std::size_t i = 0;
    for (std::size_t k = 0; k < out.size(); ++k) {
      while (i + 1 < in.size() && in.time_s[i + 1] <= out.time_s[k]) ++i;
      (*out.stroke)[k] = (*in.stroke)[i];
    }
  }
  const bool slower = rate_hz * median_s < 1.0;
  out.metadata.emplace_back(
      std::string(kResampledMetadataKey),
      std::string("from ")
          .append(format_significant(1.0 / median_s, 6))
          .append(" Hz (1 / the median interval) to ")
          .append(format_number(rate_hz))
          .append(" Hz, ")
          .append(slower ? "each sample the mean over its interval" : "linear interpolation"));
  return out;
}

}  // namespace doorbench
