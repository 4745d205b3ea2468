#include "haptic/realtime_runner.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <sstream>
#include <stdexcept>

namespace doorbench::haptic {
namespace {

timespec to_timespec(std::int64_t ns) {
  timespec time{};
  time.tv_sec = static_cast<time_t>(ns / 1000000000);
  time.tv_nsec = static_cast<long>(ns % 1000000000);
  return time;
}

std::int64_t now_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec;
}

}  // namespace

std::string RealTimeOptions::validate() const {
  if (fifo_priority < 1 || fifo_priority > 99) return "fifo_priority must be in [1, 99]";
  if (!(duration_s >= 0.0) || !std::isfinite(duration_s)) return "duration_s must be >= 0";
  return "";
}

void RealTimeRunner::Histogram::add(double us) noexcept {
  if (!(us >= 0.0)) us = 0.0;
  const int bin = us >= kBins - 1 ? kBins - 1 : static_cast<int>(us);
  ++bins[bin];
  ++count;
  sum_us += us;
  if (us > max_us) max_us = us;
}

TimingStatistics RealTimeRunner::Histogram::statistics() const {
  TimingStatistics statistics;
  statistics.count = count;
  if (count == 0) return statistics;
  statistics.max_us = max_us;
  statistics.mean_us = sum_us / static_cast<double>(count);
  auto quantile = [&](double q) {
    const std::uint64_t rank =
        static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count)));
    std::uint64_t seen = 0;
    for (int bin = 0; bin < kBins; ++bin) {
      seen += bins[bin];
      // The bin's upper edge: the quantile is at most this (1 µs resolution).
      if (seen >= rank) return bin == kBins - 1 ? max_us : static_cast<double>(bin + 1);
    }
    return max_us;
  };
  statistics.p50_us = quantile(0.5);
  statistics.p99_us = quantile(0.99);
  return statistics;
}

std::uint64_t RealTimeRunner::Histogram::count_at_least(int microseconds) const {
  std::uint64_t total = 0;
  for (int bin = std::min(microseconds, kBins - 1); bin < kBins; ++bin) total += bins[bin];
  return total;
}

std::string TimingReport::brief_report() const {
  std::ostringstream text;
  text.precision(4);
  text << ticks << " ticks in " << elapsed_s << " s (" << achieved_rate_hz << " Hz, "
       << (fifo ? "SCHED_FIFO" : "best effort") << "); interval p50/p99/max " << interval.p50_us
       << "/" << interval.p99_us << "/" << interval.max_us << " µs; lateness p50/p99/max "
       << lateness.p50_us << "/" << lateness.p99_us << "/" << lateness.max_us
       << " µs; tick cost p50/p99/max " << tick_cost.p50_us << "/" << tick_cost.p99_us << "/"
       << tick_cost.max_us << " µs; " << intervals_over_5ms << " intervals over 5 ms; "
       << skipped_deadlines << " deadlines skipped";
  return text.str();
}

RealTimeRunner::RealTimeRunner(RenderLoop& loop, const RealTimeOptions& options)
    : loop_(loop),
      options_(options),
      lateness_(std::make_unique<Histogram>()),
      interval_(std::make_unique<Histogram>()),
      cost_(std::make_unique<Histogram>()) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument("real-time runner: " + problem);
  }
}

RealTimeRunner::~RealTimeRunner() {
  stop(0.5);
}

void RealTimeRunner::start() {
  if (running_.exchange(true)) return;
  quit_.store(false);
  finished_.store(false);
  start_time_s_ = monotonic_now_s();
  first_tick_s_.store(kNaN, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
  if (options_.request_fifo) {
    sched_param parameter{};
    parameter.sched_priority = options_.fifo_priority;
    const int error = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &parameter);
    if (error == 0) {
      fifo_ = true;
    } else {
      warning_ = std::string("SCHED_FIFO not permitted (") + std::strerror(error) +
                 "): the render loop runs best effort, so its timing depends on the machine's "
                 "load; grant CAP_SYS_NICE or an rtprio limit for real-time scheduling";
    }
  } else {
    warning_ = "SCHED_FIFO not requested: the render loop runs best effort";
  }
}

void RealTimeRunner::stop(double timeout_s) {
  if (!running_.load()) return;
  loop_.request_stop();
  const double give_up = monotonic_now_s() + timeout_s;
  while (!loop_.stopped() && !finished_.load() && monotonic_now_s() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
  running_.store(false);
}

void RealTimeRunner::run() noexcept {
  const std::int64_t period_ns =
      static_cast<std::int64_t>(std::llround(1e9 / loop_.options().rate_hz));
  const std::int64_t start_ns = now_ns();
  const double start_s = static_cast<double>(start_ns) * 1e-9;
  std::int64_t deadline_ns = start_ns;
  std::int64_t previous_start_ns = -1;
  bool stop_sent = false;
  while (!quit_.load(std::memory_order_acquire)) {
    const timespec wake = to_timespec(deadline_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR) {
    }
    const std::int64_t tick_start_ns = now_ns();
    lateness_->add(static_cast<double>(tick_start_ns - deadline_ns) * 1e-3);
    if (previous_start_ns >= 0) {
      interval_->add(static_cast<double>(tick_start_ns - previous_start_ns) * 1e-3);
    } else {
      first_tick_s_.store(static_cast<double>(tick_start_ns) * 1e-9, std::memory_order_release);
    }
    previous_start_ns = tick_start_ns;
    const double loop_time_s = static_cast<double>(tick_start_ns) * 1e-9 - start_s;
    if (options_.duration_s > 0.0 && loop_time_s >= options_.duration_s && !stop_sent) {
      loop_.request_stop();
      stop_sent = true;
    }
    loop_.tick(loop_time_s);
    const std::int64_t tick_end_ns = now_ns();
    cost_->add(static_cast<double>(tick_end_ns - tick_start_ns) * 1e-3);
    ticks_.fetch_add(1, std::memory_order_relaxed);
    elapsed_s_.store(loop_time_s, std::memory_order_relaxed);
    if (loop_.stopped()) {
      finished_.store(true, std::memory_order_release);
      break;
    }
    deadline_ns += period_ns;
    if (tick_end_ns > deadline_ns) {
      // Late by more than a period: skip to the next deadline in the future (no burst).
      const std::int64_t missed = (tick_end_ns - deadline_ns) / period_ns + 1;
      skipped_.fetch_add(static_cast<std::uint64_t>(missed), std::memory_order_relaxed);
      deadline_ns += missed * period_ns;
    }
  }
}

TimingReport RealTimeRunner::report() const {
  TimingReport report;
  report.ticks = ticks_.load();
  report.elapsed_s = elapsed_s_.load();
  report.achieved_rate_hz =
      report.elapsed_s > 0.0 && report.ticks > 1 ? (report.ticks - 1) / report.elapsed_s : 0.0;
  report.skipped_deadlines = skipped_.load();
  report.lateness = lateness_->statistics();
  report.interval = interval_->statistics();
  report.tick_cost = cost_->statistics();
  report.intervals_over_5ms = interval_->count_at_least(5000);
  report.first_tick_s = first_tick_s_.load(std::memory_order_acquire);
  report.fifo = fifo_;
  return report;
}

}  // namespace doorbench::haptic
