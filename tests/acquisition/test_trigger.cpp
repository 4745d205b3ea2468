// The trigger stage (acquisition/record/trigger.h, docs/triggering.md) driven with synthetic
// blocks in the rings' layout, without threads: level crossings with hysteresis, the
// pre-trigger buffer, every stop, stroke markers, calibrated channels, no allocation per
// block; and the rig keys that configure it.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "acquisition/record/trigger.h"
#include "acquisition/rig/rig_file.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/trigger_test_rig.h"

using doorbench::CalibrationRecord;
using doorbench::ChannelInfo;
using doorbench::LevelCondition;
using doorbench::LevelDetector;
using doorbench::RawType;
using doorbench::RecordingSink;
using doorbench::SessionEvent;
using doorbench::TriggerOptions;
using doorbench::TriggerStage;

namespace {

constexpr double kRateHz = 1000.0;

ChannelInfo counts_channel(const std::string& name, const std::string& unit = "N") {
  ChannelInfo channel;
  channel.name = name;
  channel.sensor_kind = "load_cell";
  channel.raw_type = RawType::kCounts;
  channel.raw_unit = "counts";
  channel.unit = unit;
  channel.sample_rate_hz = kRateHz;
  return channel;
}

ChannelInfo polled_channel(const std::string& name, const std::string& unit) {
  ChannelInfo channel;
  channel.name = name;
  channel.sensor_kind = "gyroscope";
  channel.raw_type = RawType::kValues;
  channel.raw_unit = unit;
  channel.unit = unit;
  channel.sample_rate_hz = 0.0;
  return channel;
}

// Keeps everything it is given.
struct Sink : RecordingSink {
  explicit Sink(std::size_t channels) : counts(channels) {}
  struct Timed {
    std::uint32_t channel;
    double time_s, latency_s, raw;
  };
  std::vector<std::uint64_t> scan_numbers;
  std::vector<std::vector<std::int32_t>> counts;
  std::vector<Timed> timed;
  std::vector<SessionEvent> events;

  void scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* data,
             std::size_t stride) override {
    for (std::size_t s = 0; s < count; ++s) {
      scan_numbers.push_back(first_scan + s);
      for (std::size_t c = 0; c < counts.size(); ++c) counts[c].push_back(data[c * stride + s]);
    }
  }
  void timed_samples(std::uint32_t channel, std::span<const double> time_s,
                     std::span<const double> latency_s, std::span<const double> raw) override {
    for (std::size_t i = 0; i < time_s.size(); ++i) {
      timed.push_back({channel, time_s[i], latency_s[i], raw[i]});
    }
  }
  void event(double time_s, std::string_view kind, std::string_view channel,
             std::string_view detail) override {
    events.push_back({time_s, std::string(kind), std::string(channel), std::string(detail)});
  }
  std::vector<SessionEvent> of_kind(const std::string& kind) const {
    std::vector<SessionEvent> found;
    for (const SessionEvent& e : events) {
      if (e.kind == kind) found.push_back(e);
    }
    return found;
  }
};

// Feeds data[c][from … to) in blocks of `block` scans, laid out like the rings
// (counts[c * block + s]).
void feed(TriggerStage& stage, const std::vector<std::vector<std::int32_t>>& data,
          std::size_t block, std::size_t from = 0, std::size_t to = SIZE_MAX) {
  to = std::min(to, data[0].size());
  std::vector<std::int32_t> buffer(data.size() * block, 0);
  for (std::size_t first = from; first < to; first += block) {
    const std::size_t count = std::min(block, to - first);
    for (std::size_t c = 0; c < data.size(); ++c) {
      for (std::size_t s = 0; s < count; ++s) buffer[c * block + s] = data[c][first + s];
    }
    stage.scans(first, count, buffer.data(), block);
  }
}

// Deterministic noise in [-amplitude, amplitude].
double noise(std::size_t i, double amplitude) {
  return amplitude * std::sin(static_cast<double>(i) * 12.9898 + std::sin(i * 0.7) * 43758.5);
}

std::vector<std::int32_t> scan_index(std::size_t n) {
  std::vector<std::int32_t> index(n);
  for (std::size_t i = 0; i < n; ++i) index[i] = static_cast<std::int32_t>(i);
  return index;
}

LevelCondition level(const std::string& channel, double value, double hysteresis,
                     LevelCondition::Direction direction = LevelCondition::Direction::kRising) {
  LevelCondition condition;
  condition.channel = channel;
  condition.level = value;
  condition.hysteresis = hysteresis;
  condition.direction = direction;
  return condition;
}

}  // namespace

TEST_CASE("Trigger: the level detector fires once per excursion, noise does not re-fire",
          "[trigger]") {
  LevelDetector detector(level("force", 2.0, 0.5));
  // Starts above the level: no fire until it has been below 1.5.
  CHECK_FALSE(detector.fire(3.0));
  CHECK_FALSE(detector.fire(1.8));  // below the level, not beyond the hysteresis
  CHECK_FALSE(detector.fire(2.5));
  CHECK_FALSE(detector.fire(1.4));  // armed
  CHECK(detector.fire(2.0));        // reaches the level
  // Noise of ±0.4 around the level: never back below 1.5, so no second fire.
  int fires = 0;
  for (std::size_t i = 0; i < 1000; ++i) fires += detector.fire(2.0 + noise(i, 0.4));
  CHECK(fires == 0);
  CHECK_FALSE(detector.fire(1.0));
  CHECK(detector.fire(2.2));

  LevelDetector falling(level("force", 2.0, 0.5, LevelCondition::Direction::kFalling));
  CHECK_FALSE(falling.fire(1.0));  // starts below: must first go above 2.5
  CHECK_FALSE(falling.fire(2.6));
  CHECK(falling.fire(1.99));
  LevelCondition absolute = level("rate", 0.2, 0.05);
  absolute.absolute = true;
  LevelDetector magnitude(absolute);
  CHECK_FALSE(magnitude.fire(0.0));
  CHECK(magnitude.fire(-0.3));  // |−0.3| > 0.2
}

TEST_CASE("Trigger: a level start on noisy data fires once, at the first crossing scan",
          "[trigger]") {
  // force: above the level at first (must not fire), then a noisy dip that stays above
  // level - hysteresis, then down to 0 (arms), then a noisy ramp up through 2 N.
  const std::size_t n = 3000;
  std::vector<std::int32_t> force(n);
  for (std::size_t i = 0; i < n; ++i) {
    double value = 0;
    if (i < 300)
      value = 2.6 + noise(i, 0.5);  // 2.1 … 3.1 N, above, never armed
    else if (i < 1000)
      value = 0.0;  // armed
    else
      value = (static_cast<double>(i) - 1000) * 0.004 + noise(i, 0.8);  // ramp
    force[i] = static_cast<std::int32_t>(std::lround(value * 1000));    // mN counts
  }
  ChannelInfo channel = counts_channel("force");
  channel.raw_scale = 0.001;  // counts are mN
  std::vector<std::vector<std::int32_t>> data{force, scan_index(n)};
  std::size_t expected = 0;  // the first scan >= 2 N after the first one below 1.5 N
  {
    bool armed = false;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = force[i] * 0.001;
      if (armed && v >= 2.0) {
        expected = i;
        break;
      }
      if (v < 1.5) armed = true;
    }
  }
  REQUIRE(expected > 1000);

  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("force", 2.0, 0.5);
  options.pre_trigger_s = 0.1;
  Sink sink(2);
  const std::vector<ChannelInfo> channels{channel, counts_channel("index", "counts")};
  TriggerStage stage(options, channels, kRateHz, 64, {}, {}, sink);
  feed(stage, data, 64);
  const auto triggers = sink.of_kind("trigger");
  REQUIRE(triggers.size() == 1);
  CHECK(triggers[0].detail == "level force > 2 N");
  CHECK(triggers[0].channel == "force");
  CHECK(triggers[0].time_s == Approx(expected / kRateHz));
  REQUIRE(stage.first_forwarded_scan());
  CHECK(*stage.first_forwarded_scan() == expected - 100);
  CHECK(*stage.first_forwarded_time_s() == Approx((expected - 100) / kRateHz));
  // Everything from the first kept scan to the end, renumbered from 0.
  REQUIRE(sink.counts[1].size() == n - (expected - 100));
  for (std::size_t i = 0; i < sink.counts[1].size(); ++i) {
    REQUIRE(sink.scan_numbers[i] == i);
    REQUIRE(sink.counts[1][i] == static_cast<std::int32_t>(expected - 100 + i));
  }
  CHECK(stage.state() == TriggerStage::State::kTriggered);
  CHECK_FALSE(stage.finished());
}

TEST_CASE("Trigger: the pre-trigger content is exactly the last N scans, at any block split",
          "[trigger]") {
  const std::size_t n = 2000;
  for (const std::size_t trigger_at :
       {std::size_t{523}, std::size_t{40}, std::size_t{100}, std::size_t{1999}}) {
    for (const std::size_t block :
         {std::size_t{1}, std::size_t{37}, std::size_t{100}, std::size_t{250}}) {
      CAPTURE(trigger_at, block);
      std::vector<std::int32_t> step(n, 0);
      for (std::size_t i = trigger_at; i < n; ++i) step[i] = 10;
      std::vector<std::vector<std::int32_t>> data{scan_index(n), step};
      TriggerOptions options;
      options.start = TriggerOptions::Start::kLevel;
      options.start_level = level("step", 5.0, 1.0);
      options.pre_trigger_s = 0.1;  // N = 100
      Sink sink(2);
      const std::vector<ChannelInfo> channels{counts_channel("index", "counts"),
                                              counts_channel("step")};
      TriggerStage stage(options, channels, kRateHz, 250, {}, {}, sink);
      feed(stage, data, block);
      const std::size_t first = trigger_at >= 100 ? trigger_at - 100 : 0;
      REQUIRE(sink.counts[0].size() == n - first);
      CHECK(sink.counts[0].front() == static_cast<std::int32_t>(first));
      CHECK(sink.counts[0].back() == static_cast<std::int32_t>(n - 1));
      bool contiguous = true;
      for (std::size_t i = 0; i < sink.counts[0].size(); ++i) {
        contiguous = contiguous && sink.counts[0][i] == static_cast<std::int32_t>(first + i) &&
                     sink.scan_numbers[i] == i;
      }
      CHECK(contiguous);
      // The scan before the trigger is the last pre-trigger one (step still 0).
      CHECK(sink.counts[1][trigger_at - first - 1] == 0);
      CHECK(sink.counts[1][trigger_at - first] == 10);
      REQUIRE(sink.of_kind("trigger").size() == 1);
      CHECK(sink.of_kind("trigger")[0].time_s == Approx(trigger_at / kRateHz));
    }
  }
}

TEST_CASE("Trigger: polled samples before the trigger are kept back only pre_trigger_s",
          "[trigger]") {
  // A 50 Hz polled rate channel, a 1 kHz force channel whose step triggers at scan 1523.
  const std::size_t n = 3000;
  std::vector<std::int32_t> force(n, 0);
  for (std::size_t i = 1523; i < n; ++i) force[i] = 5;
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("force", 2.0, 0.5);
  options.pre_trigger_s = 0.25;
  Sink sink(1);
  const std::vector<ChannelInfo> scans{counts_channel("force")};
  const std::vector<ChannelInfo> polled{polled_channel("rate", "rad/s")};
  TriggerStage stage(options, scans, kRateHz, 100, polled, {}, sink);
  std::vector<std::vector<std::int32_t>> data{force};
  // Interleaved as the writer drains: each 100-scan block, then the polls of its time
  // (they lag the scans by one block).
  std::size_t poll = 0;
  for (std::size_t first = 0; first < n; first += 100) {
    feed(stage, data, 100, first, first + 100);
    std::vector<double> t, latency, raw;
    for (; static_cast<double>(poll) * 0.02 < first / kRateHz; ++poll) {
      t.push_back(poll * 0.02 + 0.003);
      latency.push_back(0.002);
      raw.push_back(static_cast<double>(poll));
    }
    stage.timed_samples(0, t, latency, raw);
  }
  const double trigger_s = 1.523;
  REQUIRE(sink.of_kind("trigger").size() == 1);
  CHECK(sink.of_kind("trigger")[0].time_s == Approx(trigger_s));
  REQUIRE_FALSE(sink.timed.empty());
  // The first kept poll is the first at or after trigger - 0.25 s = 1.273 s: poll 64 at
  // 1.283 s (poll 63 at 1.263 s is outside the window).
  CHECK(sink.timed.front().raw == 64.0);
  CHECK(sink.timed.front().time_s >= trigger_s - 0.25);
  CHECK(sink.timed.front().latency_s == 0.002);
  for (std::size_t i = 1; i < sink.timed.size(); ++i) {
    REQUIRE(sink.timed[i].raw == sink.timed[i - 1].raw + 1);  // none lost after it
  }
  CHECK(sink.timed.back().raw == static_cast<double>(poll - 1));
  CHECK(stage.summary().timed_overwritten == 0);
}

TEST_CASE("Trigger: a falling level, and stop by duration after an exact scan count", "[trigger]") {
  const std::size_t n = 5000;
  std::vector<std::int32_t> angle(n);
  for (std::size_t i = 0; i < n; ++i) {
    angle[i] = static_cast<std::int32_t>(std::lround(1000 - 0.5 * i + noise(i, 3)));
  }
  std::size_t expected = 0;
  while (angle[expected] > 700) ++expected;  // starts far above 700 + 10: armed at once
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("angle", 700, 10, LevelCondition::Direction::kFalling);
  options.pre_trigger_s = 0.05;
  options.duration_s = 0.25;
  Sink sink(2);
  const std::vector<ChannelInfo> channels{counts_channel("angle", "counts"),
                                          counts_channel("index", "counts")};
  TriggerStage stage(options, channels, kRateHz, 64, {}, {}, sink);
  std::vector<std::vector<std::int32_t>> data{angle, scan_index(n)};
  feed(stage, data, 64);
  const auto triggers = sink.of_kind("trigger");
  REQUIRE(triggers.size() == 1);
  CHECK(triggers[0].detail == "level angle < 700 counts");
  CHECK(triggers[0].time_s == Approx(expected / kRateHz));
  // 50 pre-trigger scans and exactly 250 after the trigger.
  REQUIRE(sink.counts[1].size() == 300);
  CHECK(sink.counts[1].front() == static_cast<std::int32_t>(expected - 50));
  CHECK(sink.counts[1].back() == static_cast<std::int32_t>(expected + 249));
  const auto stops = sink.of_kind("stop");
  REQUIRE(stops.size() == 1);
  CHECK(stops[0].detail == "duration 0.25 s");
  CHECK(stops[0].time_s == Approx(expected / kRateHz + 0.25));
  CHECK(sink.events.back().kind == "stop");
  CHECK(stage.finished());
  CHECK(stage.summary().forwarded_scans == 300);
}

TEST_CASE("Trigger: stop by a level that must hold, and the hold restarts after a dip",
          "[trigger]") {
  // Force up to 5 N at 1000, a 50 ms dip to 0.3 N at 2000 (too short for the 0.1 s hold),
  // back up, then down to 0 for good at 3000.
  const std::size_t n = 4000;
  std::vector<std::int32_t> force(n, 0);
  for (std::size_t i = 1000; i < 3000; ++i) force[i] = (i >= 2000 && i < 2050) ? 0 : 5;
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("force", 2.0, 0.5);
  options.stop = TriggerOptions::Stop::kLevel;
  options.stop_level = level("force", 0.5, 0.2, LevelCondition::Direction::kFalling);
  options.stop_level.hold_s = 0.1;
  options.pre_trigger_s = 0.0;
  Sink sink(2);
  const std::vector<ChannelInfo> channels{counts_channel("force"),
                                          counts_channel("index", "counts")};
  TriggerStage stage(options, channels, kRateHz, 64, {}, {}, sink);
  feed(stage, {force, scan_index(n)}, 64);
  const auto stops = sink.of_kind("stop");
  REQUIRE(stops.size() == 1);
  CHECK(stops[0].detail == "level force < 0.5 N held 0.1 s");
  CHECK(stops[0].channel == "force");
  CHECK(stops[0].time_s == Approx(3.1));  // 0.1 s after it fell at 3.0 s
  CHECK(sink.counts[1].front() == 1000);
  CHECK(sink.counts[1].back() == 3100);  // the scan where the hold completed is the last
  CHECK(stage.finished());
  // Nothing more after the stop, whatever comes.
  const std::size_t forwarded = sink.counts[1].size();
  const std::size_t events = sink.events.size();
  std::vector<std::int32_t> more(2 * 64, 7);
  stage.scans(n, 64, more.data(), 64);
  stage.event(4.0, "mark", "", "later");
  CHECK(sink.counts[1].size() == forwarded);
  CHECK(sink.events.size() == events);
}

TEST_CASE("Trigger: manual start and manual stop by flags", "[trigger]") {
  std::atomic<bool> start{false};
  std::atomic<bool> stop{false};
  TriggerOptions options;
  options.start = TriggerOptions::Start::kManual;
  options.stop = TriggerOptions::Stop::kManual;
  options.manual_start = &start;
  options.manual_stop = &stop;
  options.pre_trigger_s = 0.2;
  const std::size_t n = 3000;
  std::vector<std::vector<std::int32_t>> data{scan_index(n)};
  Sink sink(1);
  const std::vector<ChannelInfo> channels{counts_channel("index", "counts")};
  TriggerStage stage(options, channels, kRateHz, 100, {}, {}, sink);
  feed(stage, data, 100, 0, 1000);
  CHECK(sink.counts[0].empty());
  CHECK(stage.state() == TriggerStage::State::kArmed);
  start = true;
  feed(stage, data, 100, 1000, 2000);
  stop = true;
  feed(stage, data, 100, 2000, 3000);
  REQUIRE(sink.of_kind("trigger").size() == 1);
  CHECK(sink.of_kind("trigger")[0].detail == "manual");
  CHECK(sink.of_kind("trigger")[0].time_s == Approx(1.0));
  REQUIRE(sink.of_kind("stop").size() == 1);
  CHECK(sink.of_kind("stop")[0].detail == "manual");
  CHECK(sink.of_kind("stop")[0].time_s == Approx(2.0));
  // 200 pre-trigger scans, then scans 1000 … 1999; the block that saw the stop is not kept.
  REQUIRE(sink.counts[0].size() == 1200);
  CHECK(sink.counts[0].front() == 800);
  CHECK(sink.counts[0].back() == 1999);
  CHECK(stage.finished());

  options.manual_stop = &start;
  CHECK_THROWS_WITH(TriggerStage(options, channels, kRateHz, 100, {}, {}, sink),
                    "trigger options: manual_start and manual_stop must be different flags (the "
                    "start's would stop at once)");
}

TEST_CASE("Trigger: stroke markers on force and on |rate|: 3 strokes, a blip ignored",
          "[trigger]") {
  // Three 1 s half-sine pushes of 20 N, 1 s apart, and a 50 ms blip of 5 N between the
  // second and the third; noise ±0.3 N throughout.
  const std::size_t n = 8000;
  std::vector<std::int32_t> force(n);
  std::vector<double> rate(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = i / kRateHz;
    double f = 0, w = 0;
    for (int k = 0; k < 3; ++k) {
      const double start = 1.0 + 2.0 * k + (k == 2 ? 0.5 : 0.0);
      if (t >= start && t < start + 1.0) {
        f = 20 * std::sin(M_PI * (t - start));
        w = (k % 2 == 0 ? 1.0 : -1.0) * std::sin(M_PI * (t - start));  // opening, closing
      }
    }
    if (t >= 4.2 && t < 4.25) f = 5, w = 0.5;  // the blip
    force[i] = static_cast<std::int32_t>(std::lround((f + noise(i, 0.3)) * 1000));
    rate[i] = w + noise(i, 0.03);
  }
  ChannelInfo channel = counts_channel("force");
  channel.raw_scale = 0.001;
  const std::vector<ChannelInfo> channels{channel};

  SECTION("on a scan channel") {
    TriggerOptions options;
    options.strokes = level("force", 2.0, 0.5);
    options.min_stroke_s = 0.2;
    Sink sink(1);
    TriggerStage stage(options, channels, kRateHz, 64, {}, {}, sink);
    feed(stage, {force}, 64);
    const auto starts = sink.of_kind("stroke_start");
    const auto ends = sink.of_kind("stroke_end");
    REQUIRE(starts.size() == 3);
    REQUIRE(ends.size() == 3);
    const double begins[] = {1.0, 3.0, 5.5};
    for (int k = 0; k < 3; ++k) {
      CHECK(starts[k].detail == "stroke " + std::to_string(k + 1));
      CHECK(starts[k].channel == "force");
      // 2 N of a 20 N half-sine is reached 32 ms in; 1.5 N going down 24 ms before the end.
      CHECK(starts[k].time_s == Approx(begins[k] + std::asin(0.1) / M_PI).margin(0.006));
      CHECK(ends[k].time_s == Approx(begins[k] + 1 - std::asin(0.075) / M_PI).margin(0.006));
      CHECK(ends[k].time_s > starts[k].time_s);
    }
    CHECK(stage.summary().strokes == 3);
  }
  SECTION("on |rate| of a polled channel, delivered in pieces") {
    TriggerOptions options;
    options.strokes = level("rate", 0.2, 0.05);
    options.strokes->absolute = true;
    Sink sink(1);
    const std::vector<ChannelInfo> polled{polled_channel("rate", "rad/s")};
    TriggerStage stage(options, channels, kRateHz, 64, polled, {}, sink);
    feed(stage, {force}, 64, 0, 64);  // immediate start
    std::vector<double> t(n), latency(n, 0.001);
    for (std::size_t i = 0; i < n; ++i) t[i] = i / kRateHz;
    for (std::size_t first = 0; first < n; first += 333) {
      const std::size_t count = std::min<std::size_t>(333, n - first);
      stage.timed_samples(0, std::span(t).subspan(first, count),
                          std::span(latency).subspan(first, count),
                          std::span(rate).subspan(first, count));
    }
    CHECK(sink.of_kind("stroke_start").size() == 3);
    CHECK(sink.of_kind("stroke_end").size() == 3);
    CHECK(sink.of_kind("trigger").at(0).detail == "immediate");
  }
}

TEST_CASE("Trigger: a level on a calibrated counts channel fires at the physical threshold",
          "[trigger]") {
  // 16-bit counts over ±10 V; the record: N = -1 + 10 · V. 2 N is 0.3 V, count 33751.04.
  ChannelInfo channel = counts_channel("force");
  channel.raw_scale = 20.0 / 65536;
  channel.raw_offset = -10.0;
  channel.calibration_id = "load_cell-test-v1";
  CalibrationRecord record;
  record.id = "load_cell-test-v1";
  record.unit = "N";
  record.coefficients = {-1.0, 10.0};
  const std::size_t n = 6000;
  std::vector<std::int32_t> counts(n);
  for (std::size_t i = 0; i < n; ++i) counts[i] = static_cast<std::int32_t>(30000 + i);
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("force", 2.0, 0.1);
  options.pre_trigger_s = 0;
  Sink sink(1);
  const std::vector<ChannelInfo> channels{channel};
  const std::vector<CalibrationRecord> records{record};
  TriggerStage stage(options, channels, kRateHz, 100, {}, records, sink);
  feed(stage, {counts}, 100);
  REQUIRE(sink.counts[0].size() > 0);
  CHECK(sink.counts[0].front() == 33752);  // the first count whose physical value is >= 2 N
  CHECK(sink.of_kind("trigger").at(0).time_s == Approx(3752 / kRateHz));

  CHECK_THROWS_WITH(TriggerStage(options, channels, kRateHz, 100, {}, {}, sink),
                    "channel force: its calibration record \"load_cell-test-v1\" is not among the "
                    "session's records");
  options.start_level.channel = "forse";
  CHECK_THROWS_WITH(TriggerStage(options, channels, kRateHz, 100, {}, records, sink),
                    "trigger options: start condition names channel \"forse\", which is not in "
                    "the session (channels: force)");
}

TEST_CASE("Trigger: a polled channel's level starts the recording, scans ahead are kept",
          "[trigger]") {
  const std::size_t n = 2000;
  std::vector<std::vector<std::int32_t>> data{scan_index(n)};
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("rate", 0.5, 0.1);
  options.pre_trigger_s = 0.105;
  Sink sink(1);
  const std::vector<ChannelInfo> scans{counts_channel("index", "counts")};
  const std::vector<ChannelInfo> polled{polled_channel("rate", "rad/s")};
  TriggerStage stage(options, scans, kRateHz, 100, polled, {}, sink);
  // Scans reach 1.2 s before the polls arrive; the poll at 0.8105 s crosses.
  feed(stage, data, 100, 0, 1200);
  std::vector<double> t, latency, raw;
  for (int k = 0; k < 100; ++k) {
    t.push_back(0.0105 + 0.01 * k);
    latency.push_back(0.001);
    raw.push_back(k >= 80 ? 1.0 : 0.0);
  }
  stage.timed_samples(0, t, latency, raw);
  REQUIRE(sink.of_kind("trigger").size() == 1);
  CHECK(sink.of_kind("trigger")[0].time_s == Approx(0.8105));
  CHECK(sink.of_kind("trigger")[0].channel == "rate");
  // First scan at or after 0.8105 s is 811; 105 before it: 706 … 1199 so far.
  CHECK(*stage.first_forwarded_scan() == 706);
  REQUIRE(sink.counts[0].size() == 1200 - 706);
  CHECK(sink.counts[0].front() == 706);
  feed(stage, data, 100, 1200, n);
  CHECK(sink.counts[0].back() == static_cast<std::int32_t>(n - 1));
  CHECK(sink.counts[0].size() == n - 706);
  // Polls from 0.8105 - 0.105 = 0.7055 s on: the first is 0.7105 s.
  CHECK(sink.timed.front().time_s == Approx(0.7105));
  CHECK(sink.timed.size() == 30);
}

TEST_CASE("Trigger: events wait for the trigger, faults pass at once, none after the stop",
          "[trigger]") {
  std::atomic<bool> start{false};
  TriggerOptions options;
  options.start = TriggerOptions::Start::kManual;
  options.manual_start = &start;
  options.pre_trigger_s = 0.5;
  options.duration_s = 1.0;
  Sink sink(1);
  const std::vector<ChannelInfo> channels{counts_channel("index", "counts")};
  TriggerStage stage(options, channels, kRateHz, 100, {}, {}, sink);
  std::vector<std::vector<std::int32_t>> data{scan_index(4000)};
  stage.event(0.0, "trigger", "", "start (software)");
  stage.event(0.2, "mark", "", "too early");
  stage.event(0.3, "fault", "", "overrun");
  feed(stage, data, 100, 0, 1000);
  stage.event(0.7, "mark", "", "in the window");
  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0].kind == "mark");
  CHECK(sink.events[0].detail == "acquisition started (start (software))");
  CHECK(sink.events[1].kind == "fault");
  start = true;
  feed(stage, data, 100, 1000, 4000);
  stage.event(3.0, "fault", "", "after the stop");
  std::vector<std::string> kinds;
  for (const SessionEvent& e : sink.events) kinds.push_back(e.kind + ":" + e.detail);
  CHECK(kinds == std::vector<std::string>{"mark:acquisition started (start (software))",
                                          "fault:overrun", "mark:in the window", "trigger:manual",
                                          "stop:duration 1 s"});
  CHECK(sink.counts[0].size() == 1500);
}

TEST_CASE("Trigger: a gap while armed restarts the pre-trigger buffer, gaps stay gaps",
          "[trigger]") {
  const std::size_t n = 3000;
  std::vector<std::int32_t> step(n, 0);
  for (std::size_t i = 1050; i < n; ++i) step[i] = 5;
  std::vector<std::vector<std::int32_t>> data{scan_index(n), step};
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("step", 2.0, 0.5);
  options.pre_trigger_s = 0.2;
  Sink sink(2);
  const std::vector<ChannelInfo> channels{counts_channel("index", "counts"),
                                          counts_channel("step")};
  TriggerStage stage(options, channels, kRateHz, 100, {}, {}, sink);
  feed(stage, data, 100, 0, 900);
  feed(stage, data, 100, 1000, 2000);  // scans 900 … 999 lost
  feed(stage, data, 100, 2100, n);     // and 2000 … 2099, after the trigger
  // Only 50 scans of history after the gap, not 200.
  CHECK(*stage.first_forwarded_scan() == 1000);
  REQUIRE(sink.counts[0].size() == 1000 + 900);
  CHECK(sink.counts[0].front() == 1000);
  CHECK(sink.scan_numbers[999] == 999);
  CHECK(sink.scan_numbers[1000] == 1100);  // the lost scans stay a gap for the sink
  CHECK(sink.counts[0][1000] == 2100);
}

TEST_CASE("Trigger: a session of polled channels only: level start, duration stop", "[trigger]") {
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("angle", 0.1, 0.02);
  options.duration_s = 1.0;
  options.pre_trigger_s = 0.5;
  Sink sink(0);
  const std::vector<ChannelInfo> polled{polled_channel("angle", "rad"),
                                        polled_channel("rate", "rad/s")};
  TriggerStage stage(options, {}, 0.0, 0, polled, {}, sink);
  for (int k = 0; k < 400; ++k) {  // 100 Hz, both channels; angle steps to 0.2 at 2.005 s
    const double t[] = {k * 0.01 + 0.005}, latency[] = {0.002};
    const double angle[] = {k >= 200 ? 0.2 : 0.0}, rate[] = {static_cast<double>(k)};
    stage.timed_samples(0, t, latency, angle);
    stage.timed_samples(1, t, latency, rate);
  }
  REQUIRE(sink.of_kind("trigger").size() == 1);
  CHECK(sink.of_kind("trigger")[0].time_s == Approx(2.005));
  REQUIRE(sink.of_kind("stop").size() == 1);
  CHECK(sink.of_kind("stop")[0].time_s == Approx(3.005));
  CHECK(stage.finished());
  CHECK_FALSE(stage.first_forwarded_scan());
  // Each channel from 1.505 s (0.5 s before) to before 3.005 s: 150 samples.
  std::size_t angle_samples = 0, rate_samples = 0;
  double first_rate = 1e9;
  for (const auto& sample : sink.timed) {
    (sample.channel == 0 ? angle_samples : rate_samples) += 1;
    if (sample.channel == 1) first_rate = std::min(first_rate, sample.raw);
    CHECK(sample.time_s >= 1.5);
    CHECK(sample.time_s < 3.005);
  }
  CHECK(angle_samples == 150);
  CHECK(first_rate == 150.0);
  // rate's samples of k = 150 … 199 came before the trigger, 200 … 299 after.
  CHECK(rate_samples == 150);
}

TEST_CASE("Trigger: the per-block path allocates nothing after construction", "[trigger]") {
  // Counts what it gets, without keeping it.
  struct CountingSink : RecordingSink {
    std::uint64_t scans_seen = 0, timed_seen = 0, events_seen = 0;
    void scans(std::uint64_t, std::size_t count, const std::int32_t*, std::size_t) override {
      scans_seen += count;
    }
    void timed_samples(std::uint32_t, std::span<const double> t, std::span<const double>,
                       std::span<const double>) override {
      timed_seen += t.size();
    }
    void event(double, std::string_view, std::string_view, std::string_view) override {
      ++events_seen;
    }
  } sink;
  const std::size_t block = 500, blocks = 1000, channels = 8;
  std::vector<ChannelInfo> infos;
  for (std::size_t c = 0; c < channels; ++c)
    infos.push_back(counts_channel("ch" + std::to_string(c)));
  const std::vector<ChannelInfo> polled{polled_channel("rate", "rad/s")};
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("ch0", 2.0, 0.5);
  options.stop = TriggerOptions::Stop::kLevel;
  options.stop_level = level("rate", -5.0, 0.5, LevelCondition::Direction::kFalling);
  options.stop_level.hold_s = 0.01;
  options.strokes = level("ch1", 2.0, 0.5);
  options.min_stroke_s = 0.01;
  options.pre_trigger_s = 1.0;
  TriggerStage stage(options, infos, 50000.0, block, polled, {}, sink);
  std::vector<std::int32_t> counts(channels * block);
  std::vector<double> t(5), latency(5, 0.001), raw(5, 0.0);

  const long long before = doorbench::testing::allocations();
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::size_t s = 0; s < block; ++s) {
      const std::size_t scan = b * block + s;
      counts[0 * block + s] = scan > 100000 ? 5 : 0;      // triggers at 2 s
      counts[1 * block + s] = (scan / 1000) % 2 ? 5 : 0;  // strokes of 20 ms
    }
    stage.scans(b * block, block, counts.data(), block);
    for (std::size_t i = 0; i < t.size(); ++i) {
      t[i] = (b * 5 + i) * 0.002;
      raw[i] = t[i] > 9.0 ? -10.0 : 0.0;  // stops at 9 s + hold
    }
    stage.timed_samples(0, t, latency, raw);
    stage.event(b * 0.01, "mark", "", "a long detail text that std::string would put on the heap");
  }
  const long long allocated = doorbench::testing::allocations() - before;
  CHECK(allocated == 0);
  CHECK(stage.finished());
  CHECK(sink.scans_seen > 300000);
  CHECK(stage.summary().strokes > 100);
}

// --- the rig keys --------------------------------------------------------------------------

using doorbench::testing::kTriggerRig;

TEST_CASE("Trigger: level and manual triggers and the recording table from a rig file",
          "[trigger]") {
  const doorbench::RigDefinition rig = doorbench::parse_rig(kTriggerRig, "rig.toml", {});
  REQUIRE(rig.triggers.size() == 5);
  CHECK(rig.triggers[1].kind == "level");
  CHECK(rig.triggers[1].channel == "force");
  CHECK(rig.triggers[1].direction == "rising");
  CHECK(rig.triggers[1].level == 2.0);
  CHECK(rig.triggers[1].hysteresis == 0.5);
  CHECK(rig.triggers[2].direction == "falling");
  CHECK(rig.triggers[2].hold_s == 1.5);
  CHECK(rig.triggers[3].absolute);
  CHECK(rig.triggers[3].kind == "level");
  CHECK(rig.recording.start == "push");
  CHECK(rig.recording.stop == "release");
  CHECK(rig.recording.duration_s == 30);
  CHECK(rig.recording.pre_trigger_s == 2);
  CHECK(rig.recording.strokes == "moving");
  CHECK(rig.recording.min_stroke_s == 0.2);
  CHECK(rig.recording.line == 51);

  const TriggerOptions options = doorbench::trigger_options_from_rig(rig);
  CHECK(options.start == TriggerOptions::Start::kLevel);
  CHECK(options.start_level.channel == "force");
  CHECK(options.start_level.level == 2.0);
  CHECK(options.stop == TriggerOptions::Stop::kLevel);
  CHECK(options.stop_level.direction == LevelCondition::Direction::kFalling);
  CHECK(options.stop_level.hold_s == 1.5);
  CHECK(options.duration_s == 30);
  CHECK(options.pre_trigger_s == 2);
  REQUIRE(options.strokes);
  CHECK(options.strokes->absolute);
  CHECK(options.validate() == "");

  // Without [recording]: at once, no stop, 1 s pre-trigger. "At once" is at the DAQ's
  // external start line when [daq] start_trigger names one.
  const std::string plain = kTriggerRig.substr(0, kTriggerRig.find("[recording]"));
  const TriggerOptions defaults =
      doorbench::trigger_options_from_rig(doorbench::parse_rig(plain, "rig.toml", {}));
  CHECK(defaults.start == TriggerOptions::Start::kExternal);
  CHECK(defaults.external_source == "PFI0");
  const std::string software_start =
      plain.substr(0, plain.find("start_trigger")) + plain.substr(plain.find("[[channels]]"));
  CHECK(doorbench::trigger_options_from_rig(doorbench::parse_rig(software_start, "rig.toml", {}))
            .start == TriggerOptions::Start::kImmediate);
  CHECK(defaults.stop == TriggerOptions::Stop::kNone);
  CHECK(defaults.pre_trigger_s == 1.0);
  CHECK_FALSE(defaults.strokes);
  // The external start: the DAQ's line, named in the trigger event.
  const TriggerOptions external = doorbench::trigger_options_from_rig(
      doorbench::parse_rig(plain + "[recording]\nstart = \"door_switch\"\n", "rig.toml", {}));
  CHECK(external.start == TriggerOptions::Start::kExternal);
  CHECK(external.external_source == "PFI0");
  const TriggerOptions manual = doorbench::trigger_options_from_rig(doorbench::parse_rig(
      plain + "[recording]\nstart = \"enter\"\nstop = \"enter\"\n", "rig.toml", {}));
  CHECK(manual.start == TriggerOptions::Start::kManual);
  CHECK(manual.stop == TriggerOptions::Stop::kManual);
}

// Not run by default: the stage's cost at the rate (docs/triggering.md quotes it).
TEST_CASE("Trigger: throughput at 8 channels x 50 kS/s", "[trigger]") {
  struct NullSink : RecordingSink {
    std::uint64_t scans_seen = 0;
    void scans(std::uint64_t, std::size_t count, const std::int32_t*, std::size_t) override {
      scans_seen += count;
    }
    void timed_samples(std::uint32_t, std::span<const double>, std::span<const double>,
                       std::span<const double>) override {}
    void event(double, std::string_view, std::string_view, std::string_view) override {}
  } sink;
  const double rate_hz = 50000;
  const std::size_t block = 500, channels = 8, blocks = 6000;  // 60 s of data
  std::vector<ChannelInfo> infos;
  for (std::size_t c = 0; c < channels; ++c) {
    ChannelInfo info = counts_channel("ch" + std::to_string(c));
    info.raw_scale = 20.0 / 65536;
    info.raw_offset = -10;
    infos.push_back(info);
  }
  TriggerOptions options;
  options.start = TriggerOptions::Start::kLevel;
  options.start_level = level("ch0", 2.0, 0.5);
  options.stop = TriggerOptions::Stop::kLevel;
  options.stop_level = level("ch2", -5.0, 0.5, LevelCondition::Direction::kFalling);
  options.strokes = level("ch1", 2.0, 0.5);
  options.min_stroke_s = 0.001;  // a stroke every 4 ms: far more events than a door makes
  options.pre_trigger_s = 1.0;
  TriggerStage stage(options, infos, rate_hz, block, {}, {}, sink);
  std::vector<std::int32_t> counts(channels * block, 32768);
  for (const bool triggered : {false, true}) {
    for (std::size_t s = 0; s < block; ++s) {
      counts[0 * block + s] = triggered ? 45000 : 32768;  // ch0 above 2 V once triggered
      counts[1 * block + s] = (s / 100) % 2 ? 45000 : 32768;
    }
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t first = (triggered ? blocks : 0) * block + b * block;
      stage.scans(first, block, counts.data(), block);
    }
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double data_s = blocks * block / rate_hz;
    std::printf("trigger stage %s: %.0f s of 8 x 50 kS/s in %.3f s (%.2f %% of real time)\n",
                triggered ? "triggered (strokes, stop level)" : "armed (buffering, level)", data_s,
                elapsed_s, 100 * elapsed_s / data_s);
  }
  CHECK(stage.state() == TriggerStage::State::kTriggered);
  CHECK(stage.summary().strokes > 1000);
}
