// The recorder's reading side (recorder.h: RecorderRings, RealtimeReader): the real-time
// thread's loop from the backend into the rings, without allocation or locks.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "acquisition/record/internal/recorder_common.h"
#include "acquisition/record/recorder.h"

namespace doorbench {

using namespace record_detail;

RecorderRings::RecorderRings(std::size_t channels, std::size_t block_scans, std::size_t scan_slots,
                             std::size_t event_slots)
    : scans(scan_slots,
            ScanSlot{0, 0, block_scans, std::vector<std::int32_t>(channels * block_scans)}),
      events(event_slots, EventSlot{}) {}

RealtimeReader::RealtimeReader(AcquisitionBackend& backend, RecorderRings& rings,
                               std::size_t channels, std::size_t block_scans,
                               std::uint64_t total_scans, RingFullPolicy when_full)
    : backend_(backend),
      rings_(rings),
      block_(channels, block_scans),
      channels_(channels),
      total_scans_(total_scans),
      when_full_(when_full),
      scan_rate_hz_(backend.scan_rate_hz()) {
  if (rings.scans.capacity() == 0 || rings.scans.consumer_slot() != nullptr ||  // must start empty
      block_scans > rings.scans.producer_slot()->capacity) {
    throw std::invalid_argument("the ring's blocks are smaller than the reader's");
  }
}

void RealtimeReader::start() {
  backend_.start();
  const ClockOrigin origin = sample_clock_origin();
  rings_.start_realtime_ns.store(origin.realtime_ns, std::memory_order_relaxed);
  rings_.start_monotonic_ns.store(origin.monotonic_ns, std::memory_order_release);
}

void RealtimeReader::push_event(double time_s, const char* kind, const char* channel,
                                const char* detail) {
  EventSlot* slot = rings_.events.producer_slot();
  if (slot == nullptr) {
    rings_.dropped_events.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  slot->time_s = time_s;
  copy_text(slot->kind, kind);
  copy_text(slot->channel, channel);
  copy_text(slot->detail, detail);
  rings_.events.publish();
}

bool RealtimeReader::step() {
  if (scans_ >= total_scans_ || rings_.stop.load(std::memory_order_relaxed)) return false;
  block_.events.clear();
  const std::size_t got = backend_.read(block_);
  if (got == 0) return false;
  const std::size_t keep =
      static_cast<std::size_t>(std::min<std::uint64_t>(got, total_scans_ - scans_));

  ScanSlot* slot = rings_.scans.producer_slot();
  while (slot == nullptr && when_full_ == RingFullPolicy::kWait) {
    // Only for sources that compute scans on demand: waiting costs them nothing.
    if (rings_.stop.load(std::memory_order_relaxed)) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    slot = rings_.scans.producer_slot();
  }
  if (slot != nullptr) {
    slot->first_scan = scans_;
    slot->scan_count = keep;
    for (std::size_t c = 0; c < channels_; ++c) {
      std::memcpy(slot->counts.data() + c * slot->capacity, block_.counts[c].data(),
                  keep * sizeof(std::int32_t));
    }
    rings_.scans.publish();
    overflowing_ = false;
  } else {
    rings_.dropped_scans.fetch_add(keep, std::memory_order_relaxed);
    if (!overflowing_) {
      // One fault per overflow; the session's gap event gives the exact extent.
      rings_.overflows.fetch_add(1, std::memory_order_relaxed);
      char detail[sizeof EventSlot::detail];
      std::snprintf(detail, sizeof detail,
                    "ring buffer overflow: the writer fell behind; scans from %llu dropped",
                    static_cast<unsigned long long>(scans_));
      push_event(static_cast<double>(scans_) / scan_rate_hz_, "fault", "", detail);
      overflowing_ = true;
    }
  }
  for (const SessionEvent& event : block_.events) {
    EventSlot* event_slot = rings_.events.producer_slot();
    if (event_slot == nullptr) {
      rings_.dropped_events.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    event_slot->time_s = event.time_s;
    copy_text(event_slot->kind, event.kind);
    copy_text(event_slot->channel, event.channel);
    copy_text(event_slot->detail, event.detail);
    rings_.events.publish();
  }
  scans_ += keep;
  rings_.scans_read.store(scans_, std::memory_order_relaxed);
  return true;
}

}  // namespace doorbench
