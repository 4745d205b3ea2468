#pragma once
// What the recorder's reading side (realtime_reader.cpp) and writer side
// (session_recording.cpp) share (acquisition/record/ only): the clocks' common origin and
// the copying of a text into a fixed buffer. No allocation; safe on any thread.
#include <time.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace doorbench::record_detail {

inline std::int64_t clock_ns(clockid_t clock) {
  timespec now{};
  ::clock_gettime(clock, &now);
  return std::int64_t{now.tv_sec} * 1000000000 + now.tv_nsec;
}

// CLOCK_MONOTONIC and CLOCK_REALTIME of one moment: the realtime clock read on either side
// of the monotonic one, averaged (both reads take well under a microsecond).
struct ClockOrigin {
  std::int64_t monotonic_ns = 0;
  std::int64_t realtime_ns = 0;
};
inline ClockOrigin sample_clock_origin() {
  const std::int64_t before = clock_ns(CLOCK_REALTIME);
  const std::int64_t monotonic = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t after = clock_ns(CLOCK_REALTIME);
  return {monotonic, before + (after - before) / 2};
}

// Copies `text` into `out` (size bytes, NUL-terminated); a text that does not fit ends
// in "...". No allocation.
inline void copy_text(char* out, std::size_t size, const char* text, std::size_t length) {
  if (length < size) {
    std::memcpy(out, text, length);
    out[length] = '\0';
    return;
  }
  std::memcpy(out, text, size - 4);
  std::memcpy(out + size - 4, "...", 4);
}

template <std::size_t N>
void copy_text(char (&out)[N], const std::string& text) {
  copy_text(out, N, text.data(), text.size());
}

template <std::size_t N>
void copy_text(char (&out)[N], const char* text) {
  copy_text(out, N, text, std::strlen(text));
}

}  // namespace doorbench::record_detail
