#pragma once
// Whether a CPU of the machine stopped running threads for a while: one thread of the test
// process per CPU it may run on, each pinned to its CPU at SCHED_FIFO priority 90 (above a
// play's tick and I/O threads), sleeps 1 ms at a time and keeps each gap between its wake-ups
// longer than `report_above_s`, with the CLOCK_MONOTONIC time it ended. A busy machine does not
// delay such a thread by more than a few milliseconds; a gap of 100 ms means that CPU itself was
// held (a virtual CPU its host did not run), which no program on it can prevent and which a
// play's stall checks rightly stop on. A host may hold one virtual CPU while the other runs: a
// single unpinned watcher, on the CPU that ran, would not see it.
//
// Without permission for SCHED_FIFO the watch cannot tell a held CPU from a busy one: fifo()
// is false and held_during() always false. Thread safety: longest_gap_s() and held_during() may
// be called from any thread while the watch runs.
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "core/clock.h"

namespace doorbench::testing {

class PauseWatch {
 public:
  struct Gap {
    int cpu = -1;
    double ended_at_s = 0.0;  // monotonic_now_s() when the thread woke
    double length_s = 0.0;
  };

  explicit PauseWatch(double report_above_s = 0.05) : report_above_s_(report_above_s) {
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) CPU_SET(0, &allowed);
    fifo_ = true;
    try {
      for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (!CPU_ISSET(cpu, &allowed)) continue;
        threads_.emplace_back([this, cpu] { watch(cpu); });
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(cpu, &one);
        pthread_setaffinity_np(threads_.back().native_handle(), sizeof one, &one);
        sched_param parameter{};
        parameter.sched_priority = 90;
        fifo_ =
            pthread_setschedparam(threads_.back().native_handle(), SCHED_FIFO, &parameter) == 0 &&
            fifo_;
      }
    } catch (...) {
      stop_watching();  // a thread that could not start: the started ones end before the throw
      throw;
    }
  }
  ~PauseWatch() { stop_watching(); }
  PauseWatch(const PauseWatch&) = delete;
  PauseWatch& operator=(const PauseWatch&) = delete;

  bool fifo() const { return fifo_; }
  std::size_t cpus() const { return threads_.size(); }

  // Whether a gap of at least `at_least_s` on any CPU overlapped `from_s` to `until_s`
  // (monotonic).
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
  void stop_watching() {
    stop_ = true;
    for (std::thread& thread : threads_) thread.join();
  }

  void watch(int cpu) {
    double last_s = monotonic_now_s();
    while (!stop_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const double now_s = monotonic_now_s();
      if (now_s - last_s > report_above_s_) {
        const std::lock_guard lock(mutex_);
        gaps_.push_back({cpu, now_s, now_s - last_s});
      }
      last_s = now_s;
    }
  }

  const double report_above_s_;
  std::atomic<bool> stop_{false};
  bool fifo_ = false;
  mutable std::mutex mutex_;
  std::vector<Gap> gaps_;
  std::vector<std::thread> threads_;
};

}  // namespace doorbench::testing
