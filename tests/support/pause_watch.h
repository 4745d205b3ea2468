#pragma once
// Whether the whole machine stopped running threads for a while: a thread of the test process
// at SCHED_FIFO priority 90 (above a play's tick and I/O threads) sleeps 1 ms at a time and
// keeps the longest gap between its wake-ups, with the CLOCK_MONOTONIC time it ended. A busy
// machine does not delay such a thread by more than a few milliseconds; a gap of 100 ms means
// the machine itself was held (a virtual machine paused by its host), which no program on it
// can prevent and which a play's stall check rightly stops on.
//
// Without permission for SCHED_FIFO the watch cannot tell a held machine from a busy one:
// fifo() is false and held_during() always false. Thread safety: longest_gap_s() and
// held_during() may be called from any thread while the watch runs.
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "core/clock.h"

namespace doorbench::testing {

class PauseWatch {
 public:
  struct Gap {
    double ended_at_s = 0.0;  // monotonic_now_s() when the thread woke
    double length_s = 0.0;
  };

  explicit PauseWatch(double report_above_s = 0.05) : report_above_s_(report_above_s) {
    thread_ = std::thread([this] { watch(); });
    sched_param parameter{};
    parameter.sched_priority = 90;
    fifo_ = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &parameter) == 0;
  }
  ~PauseWatch() {
    stop_ = true;
    thread_.join();
  }
  PauseWatch(const PauseWatch&) = delete;
  PauseWatch& operator=(const PauseWatch&) = delete;

  bool fifo() const { return fifo_; }

  // Whether a gap of at least `at_least_s` ended between `from_s` and `until_s` (monotonic).
  bool held_during(double from_s, double until_s, double at_least_s) const {
    if (!fifo_) return false;
    const std::lock_guard lock(mutex_);
    for (const Gap& gap : gaps_) {
      if (gap.length_s >= at_least_s && gap.ended_at_s >= from_s &&
          gap.ended_at_s - gap.length_s <= until_s)
        return true;
    }
    return false;
  }

  double longest_gap_s() const {
    const std::lock_guard lock(mutex_);
    double longest = 0.0;
    for (const Gap& gap : gaps_) longest = std::max(longest, gap.length_s);
    return longest;
  }

 private:
  void watch() {
    double last_s = monotonic_now_s();
    while (!stop_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const double now_s = monotonic_now_s();
      if (now_s - last_s > report_above_s_) {
        const std::lock_guard lock(mutex_);
        gaps_.push_back({now_s, now_s - last_s});
      }
      last_s = now_s;
    }
  }

  const double report_above_s_;
  std::atomic<bool> stop_{false};
  bool fifo_ = false;
  mutable std::mutex mutex_;
  std::vector<Gap> gaps_;
  std::thread thread_;
};

}  // namespace doorbench::testing
