#pragma once
// Runs a RenderLoop's tick on its own thread at the loop's rate, on absolute deadlines
// (clock_nanosleep on CLOCK_MONOTONIC, TIMER_ABSTIME), so that a late tick does not shift the
// ones after it. The thread asks for SCHED_FIFO at the given priority; when that is not
// permitted (no CAP_SYS_NICE / rtprio limit) it runs best effort and says so in warning().
//
// Timing is measured on the thread without allocation: each tick's wake-up lateness (the time
// from its deadline to the start of the tick) and the interval between tick starts go into
// fixed histograms of 1 µs bins (up to 20 ms; beyond is counted in the last bin with the exact
// maximum kept), from which TimingReport gives p50, p99 and max.
//
// A tick that starts more than one period late makes the runner skip the deadlines it missed
// (it never bursts to catch up); the safety layer sees the long interval as a missed deadline.
//
// Thread safety: start/stop/report from one control thread.
#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "haptic/render_loop.h"

namespace doorbench::haptic {

struct RealTimeOptions {
  bool request_fifo = true;
  int fifo_priority = 80;   // 1..99
  double duration_s = 0.0;  // > 0: stop the loop (safety ramp-down) after this long
  std::string validate() const;
};

struct TimingStatistics {
  std::uint64_t count = 0;
  double p50_us = 0.0, p99_us = 0.0, max_us = 0.0, mean_us = 0.0;
};

struct TimingReport {
  std::uint64_t ticks = 0;
  double elapsed_s = 0.0;
  double achieved_rate_hz = 0.0;
  std::uint64_t skipped_deadlines = 0;
  TimingStatistics lateness;   // tick start − deadline
  TimingStatistics interval;   // between tick starts
  TimingStatistics tick_cost;  // time spent inside tick()
  // Intervals between tick starts longer than 5 ms (what the safety layer's default
  // max_tick_interval_s calls a missed deadline).
  std::uint64_t intervals_over_5ms = 0;
  double first_tick_s = kNaN;  // monotonic_now_s() at the first tick's start; NaN before it
  bool fifo = false;
  std::string brief_report() const;
};

class RealTimeRunner {
 public:
  RealTimeRunner(RenderLoop& loop, const RealTimeOptions& options);  // throws invalid_argument
  ~RealTimeRunner();
  RealTimeRunner(const RealTimeRunner&) = delete;
  RealTimeRunner& operator=(const RealTimeRunner&) = delete;

  void start();
  // Asks the loop to ramp down, waits until the safety layer has stopped (or `timeout_s`), then
  // ends the thread.
  void stop(double timeout_s = 1.0);
  bool running() const { return running_.load(std::memory_order_acquire); }
  // True once the loop stopped by itself (a trip, or the duration ran out).
  bool finished() const { return finished_.load(std::memory_order_acquire); }
  const std::string& warning() const { return warning_; }
  // Loop time (s since start()) of the newest tick; the clock the ticks are stamped with.
  double start_time_s() const { return start_time_s_; }
  // Consistent once the thread has ended; during the run an approximate snapshot.
  TimingReport report() const;

 private:
  static constexpr int kBins = 20000;  // 1 µs each
  struct Histogram {
    std::array<std::uint32_t, kBins> bins{};
    std::uint64_t count = 0;
    double max_us = 0.0, sum_us = 0.0;
    void add(double us) noexcept;
    TimingStatistics statistics() const;
    std::uint64_t count_at_least(int microseconds) const;
  };
  void run() noexcept;

  RenderLoop& loop_;
  RealTimeOptions options_;
  std::thread thread_;
  std::atomic<bool> running_{false}, quit_{false}, finished_{false};
  std::string warning_;
  bool fifo_ = false;
  double start_time_s_ = 0.0;
  std::unique_ptr<Histogram> lateness_, interval_, cost_;
  std::atomic<std::uint64_t> ticks_{0}, skipped_{0};
  std::atomic<double> elapsed_s_{0.0};
  std::atomic<double> first_tick_s_{kNaN};
};

}  // namespace doorbench::haptic
