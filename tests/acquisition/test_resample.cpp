// Resampling for analysis (acquisition/session/resample.h, docs/synchronization.md): linear
// interpolation against known signals, no extrapolation, gaps marked; and the export of
// sessions whose channels have different clocks (session_to_recording).
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "acquisition/session/resample.h"
#include "acquisition/session/session_csv.h"
#include "core/percentile.h"
#include "fixtures/temp_dir.h"

using Catch::Matchers::Contains;
using namespace doorbench;

TEST_CASE("Resample: a linear signal comes back exactly, samples at their own times",
          "[resample]") {
  // Irregular times, as a polled channel has them.
  const std::vector<double> t = {0.0, 0.013, 0.021, 0.037, 0.040, 0.055};
  std::vector<double> v;
  for (double x : t) v.push_back(3.0 - 2.0 * x);
  const std::vector<double> at = {0.0, 0.005, 0.021, 0.030, 0.050, 0.055};
  const std::vector<double> out = resample_linear(t, v, at, 1.0);
  REQUIRE(out.size() == at.size());
  for (std::size_t i = 0; i < at.size(); ++i)
    CHECK(out[i] == Approx(3.0 - 2.0 * at[i]).margin(1e-15));
  CHECK(out[2] == v[2]);  // a sample's own time gives the sample exactly
}

TEST_CASE("Resample: a sine's interpolation error is within the linear-interpolation bound",
          "[resample]") {
  // 2 Hz sine sampled every ~4 ms with jitter; bound: h²/8 · max|y''| = h²/8 · (2πf)².
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.0005, 0.0005);
  const double f = 2.0, omega = 2 * std::numbers::pi * f;
  std::vector<double> t, v;
  for (int i = 0; i < 500; ++i) {
    t.push_back(i * 0.004 + jitter(random));
    v.push_back(std::sin(omega * t.back()));
  }
  const std::vector<double> at = uniform_axis(t.front(), t.back(), 1000.0);
  const std::vector<double> out = resample_linear(t, v, at, 3 * median_interval_s(t));
  const double h = 0.005;  // the largest interval
  double worst = 0;
  for (std::size_t i = 0; i < at.size(); ++i) {
    REQUIRE(!std::isnan(out[i]));
    worst = std::max(worst, std::abs(out[i] - std::sin(omega * at[i])));
  }
  CHECK(worst <= h * h / 8 * omega * omega);
  CHECK(worst > 0);  // it is interpolation, not the truth
}

TEST_CASE("Resample: no extrapolation, gaps are marked (NaN), not bridged", "[resample]") {
  const std::vector<double> t = {1.0, 1.1, 1.2, 1.8, 1.9};  // a 0.6 s gap
  const std::vector<double> v = {0, 1, 2, 3, 4};
  const std::vector<double> at = {0.9, 1.05, 1.5, 1.85, 2.0};
  const std::vector<double> out = resample_linear(t, v, at, 0.3);
  CHECK(std::isnan(out[0]));  // before the first sample
  CHECK(out[1] == Approx(0.5));
  CHECK(std::isnan(out[2]));  // inside the gap
  CHECK(out[3] == Approx(3.5));
  CHECK(std::isnan(out[4]));  // after the last sample
  CHECK_THROWS_WITH(resample_linear(std::vector<double>{0.0, 0.0}, std::vector<double>{1, 2}, at,
                                    1.0, "channel q"),
                    Contains("channel q: sample times do not increase at sample 1"));
  CHECK(uniform_axis(0.0, 0.01, 1000.0).size() == 11);
}

namespace {

ChannelInfo value_channel(const std::string& name, const std::string& unit, double rate_hz) {
  ChannelInfo channel;
  channel.name = name;
  channel.sensor_kind = name == "force" ? "load_cell" : "gyroscope";
  channel.raw_type = RawType::kValues;
  channel.raw_unit = unit;
  channel.unit = unit;
  channel.range_min = -1e9;
  channel.range_max = 1e9;
  channel.sample_rate_hz = rate_hz;
  return channel;
}

}  // namespace

TEST_CASE("Export: a polled force goes on the rate channel's clock, a gap is left out",
          "[resample][session]") {
  testing::TempDir dir("resample");
  const auto path = dir / "mixed.h5";
  {
    SessionWriter writer(path, SessionMetadata{});
    // Force polled every ~5 ms from 0.1 s to 1.0 s with a gap 0.5-0.6 s; rate uniform 1 kHz
    // from 0 to 1.2 s. force = 10 t, rate = 1 + t: both linear, so interpolation is exact.
    const int force = writer.add_channel(value_channel("force", "N", 0.0));
    const int rate = writer.add_channel(value_channel("rate", "rad/s", 1000.0));
    std::vector<double> ft, fv;
    for (int i = 0; i <= 180; ++i) {
      const double t = 0.1 + i * 0.005 + (i % 3) * 0.0004;
      if (t > 0.5 && t < 0.6) continue;
      ft.push_back(t);
      fv.push_back(10 * t);
    }
    writer.append_timed_values(force, ft, fv);
    std::vector<double> rv;
    for (int i = 0; i <= 1200; ++i) rv.push_back(1 + i / 1000.0);
    writer.append_values(rate, rv);
    writer.close();
  }
  const SessionReader session(path);
  const Recording recording = session_to_recording(session);
  REQUIRE(recording.size() > 700);
  CHECK(recording.sample_rate_hz == 1000.0);
  CHECK(recording.time_s.front() >= 0.1);
  CHECK(recording.time_s.back() <= 1.0 + 0.0009);
  bool jumped = false;
  for (std::size_t i = 0; i < recording.size(); ++i) {
    const double t = recording.time_s[i];
    CHECK(!(t > 0.5 && t < 0.6));  // the gap is not bridged
    if (i > 0 && t - recording.time_s[i - 1] > 0.05) jumped = true;
    CHECK(recording.force_N[i] == Approx(10 * t).margin(1e-9));
    CHECK((*recording.rate_rad_s)[i] == Approx(1 + t).margin(1e-9));
  }
  CHECK(jumped);
  std::string resampled, gaps;
  for (const auto& [key, value] : recording.metadata) {
    if (key == "resampled") resampled = value;
    if (key == "resample_gaps") gaps = value;
  }
  CHECK_THAT(resampled, Contains("linear interpolation on the clock of rate"));
  CHECK_THAT(gaps, Contains("force 0.49"));
}

TEST_CASE("Export: without a uniform channel, a common rate of the force's median interval",
          "[resample][session]") {
  testing::TempDir dir("resample");
  const auto path = dir / "polled.h5";
  {
    SessionWriter writer(path, SessionMetadata{});
    const int force = writer.add_channel(value_channel("force", "N", 0.0));
    const int rate = writer.add_channel(value_channel("rate", "rad/s", 0.0));
    std::vector<double> ft, fv, rt, rv;
    for (int i = 0; i < 200; ++i) {
      ft.push_back(0.002 + i * 0.004 + (i % 4 == 1 ? 0.0003 : 0.0));  // median interval 4 ms
      fv.push_back(std::sin(ft.back()));
      rt.push_back(0.001 + i * 0.0041);
      rv.push_back(2 * rt.back());
    }
    writer.append_timed_values(force, ft, fv);
    writer.append_timed_values(rate, rt, rv);
    writer.close();
  }
  const Recording recording = session_to_recording(SessionReader(path));
  REQUIRE(recording.sample_rate_hz);
  CHECK(*recording.sample_rate_hz == Approx(250.0));
  CHECK(recording.time_s.front() == Approx(0.002));
  CHECK(recording.time_s[1] - recording.time_s[0] == Approx(0.004));
  CHECK(recording.time_s.back() <= 0.001 + 199 * 0.0041);
  for (std::size_t i = 0; i < recording.size(); ++i) {
    CHECK((*recording.rate_rad_s)[i] == Approx(2 * recording.time_s[i]).margin(1e-12));
    CHECK(recording.force_N[i] == Approx(std::sin(recording.time_s[i])).margin(1e-5));
  }
}
