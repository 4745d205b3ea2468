#pragma once
// The one clock doorbench times its stages with (fit, loop, design, benchmarks) and the haptic
// path stamps its ticks with: steady, never adjusted. Not for a recording's sample times (the
// session clock is the recorder's).
#include <chrono>

namespace doorbench {

using StageClock = std::chrono::steady_clock;

// Seconds elapsed since `start`.
inline double seconds_since(StageClock::time_point start) {
  return std::chrono::duration<double>(StageClock::now() - start).count();
}

// The steady clock (CLOCK_MONOTONIC on Linux) in seconds since its arbitrary origin: the clock
// the haptic path stamps its ticks, device readings and start-up with, and the one the
// HapticMaster emulator's event log uses. Real-time safe: no allocation, lock or I/O.
inline double monotonic_now_s() noexcept {
  return std::chrono::duration<double>(StageClock::now().time_since_epoch()).count();
}

}  // namespace doorbench
