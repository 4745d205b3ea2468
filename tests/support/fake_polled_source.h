#pragma once
// A polled source for tests (PolledSource, acquisition/record/polled_source.h): one polling
// thread reads each channel in turn every period; a "request" is answered after a fake
// latency, and the value is a known function of the absolute CLOCK_MONOTONIC time at the
// request/reply midpoint (a sine), or the poll's index (a counter, to find lost samples).
// Fault events can be injected every N polls. The polling thread allocates nothing.
#include <time.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/record/polled_source.h"
#include "acquisition/record/ring_buffer.h"

namespace doorbench::testing {

struct FakePolledOptions {
  std::vector<std::string> names = {"fake"};
  double period_s = 0.002;    // between polls of the same channel
  double latency_s = 0.0003;  // request to reply
  bool counter = false;       // raw = the channel's poll index instead of the sine
  double amplitude = 1.0;     // raw = offset + amplitude · sin(2π f t), t monotonic in s
  double frequency_hz = 1.0;
  double offset = 0.0;
  std::size_t fault_every = 0;  // a fault event every N polls of channel 0; 0: none
  std::size_t ring = 1 << 16;
};

inline double fake_sine(const FakePolledOptions& o, std::int64_t monotonic_ns) {
  return o.offset + o.amplitude * std::sin(2 * std::numbers::pi * o.frequency_hz *
                                           (static_cast<double>(monotonic_ns) * 1e-9));
}

class FakePolledSource : public PolledSource {
 public:
  explicit FakePolledSource(FakePolledOptions options)
      : options_(std::move(options)),
        samples_(options_.ring, PolledSample{}),
        events_(1024, PolledEvent{}) {}
  ~FakePolledSource() override { stop(); }

  std::string description() const override { return "fake polled source"; }
  std::vector<ChannelInfo> channels() const override {
    std::vector<ChannelInfo> channels;
    for (const std::string& name : options_.names) {
      ChannelInfo channel;
      channel.name = name;
      channel.sensor_kind = "fake";
      channel.sensor_serial = "F1";
      channel.raw_type = RawType::kValues;
      // Copied, not assigned from literals: GCC 12 warns falsely (-Wrestrict) on those here.
      channel.raw_unit = volts_;
      channel.unit = volts_;
      channel.range_min = -1e9;
      channel.range_max = 1e9;
      channel.sample_rate_hz = 0.0;
      channels.push_back(channel);
    }
    return channels;
  }
  std::vector<doorbench::CalibrationRecord> calibrations() const override { return {}; }

  void start() override {
    running_.store(true);
    thread_ = std::thread([this] { poll(); });
  }
  void stop() override {
    running_.store(false);
    if (thread_.joinable()) thread_.join();
  }
  std::size_t take_samples(std::span<PolledSample> out) override {
    std::size_t n = 0;
    while (n < out.size()) {
      const PolledSample* slot = samples_.consumer_slot();
      if (slot == nullptr) break;
      out[n++] = *slot;
      samples_.release();
    }
    return n;
  }
  std::size_t take_events(std::span<PolledEvent> out) override {
    std::size_t n = 0;
    while (n < out.size()) {
      const PolledEvent* slot = events_.consumer_slot();
      if (slot == nullptr) break;
      out[n++] = *slot;
      events_.release();
    }
    return n;
  }
  PolledStatistics statistics() const override {
    PolledStatistics statistics;
    statistics.polls = polls_.load();
    statistics.samples = delivered_.load();
    statistics.faults = faults_.load();
    statistics.dropped_samples = dropped_.load();
    return statistics;
  }

 private:
  static void sleep_until(std::int64_t ns) {
    const timespec at{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) != 0) {
    }
  }
  void poll() {
    const auto period_ns = static_cast<std::int64_t>(options_.period_s * 1e9);
    const auto latency_ns = static_cast<std::int64_t>(options_.latency_s * 1e9);
    std::int64_t next = monotonic_now_ns();
    std::uint64_t index = 0;
    while (running_.load(std::memory_order_relaxed)) {
      for (std::uint32_t c = 0; c < options_.names.size(); ++c) {
        PolledSample sample;
        sample.channel = c;
        sample.request_ns = monotonic_now_ns();
        sleep_until(sample.request_ns + latency_ns);
        sample.response_ns = monotonic_now_ns();
        polls_.fetch_add(1, std::memory_order_relaxed);
        sample.raw = options_.counter ? static_cast<double>(index)
                                      : fake_sine(options_, sample.midpoint_ns());
        if (PolledSample* slot = samples_.producer_slot()) {
          *slot = sample;
          samples_.publish();
          delivered_.fetch_add(1, std::memory_order_relaxed);
        } else {
          dropped_.fetch_add(1, std::memory_order_relaxed);
        }
      }
      ++index;
      if (options_.fault_every > 0 && index % options_.fault_every == 0) {
        if (PolledEvent* event = events_.producer_slot()) {
          event->monotonic_ns = monotonic_now_ns();
          std::snprintf(event->kind, sizeof event->kind, "fault");
          std::snprintf(event->channel, sizeof event->channel, "%s", options_.names[0].c_str());
          std::snprintf(event->detail, sizeof event->detail, "injected timeout after poll %llu",
                        static_cast<unsigned long long>(index));
          events_.publish();
          faults_.fetch_add(1, std::memory_order_relaxed);
        }
      }
      next += period_ns;
      sleep_until(next);
    }
  }

  FakePolledOptions options_;
  std::string volts_ = std::string(1, 'V');
  SpscRing<PolledSample> samples_;
  SpscRing<PolledEvent> events_;
  std::atomic<bool> running_{false};
  std::thread thread_;
  std::atomic<std::uint64_t> polls_{0}, delivered_{0}, faults_{0}, dropped_{0};
};

}  // namespace doorbench::testing
