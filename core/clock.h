#pragma once
// The one clock doorbench times its stages with (fit, loop, design, benchmarks): steady,
// never adjusted. Not for sample times (the session clock is the recorder's).
#include <chrono>

namespace doorbench {

using StageClock = std::chrono::steady_clock;

// Seconds elapsed since `start`.
inline double seconds_since(StageClock::time_point start) {
  return std::chrono::duration<double>(StageClock::now() - start).count();
}

}  // namespace doorbench
