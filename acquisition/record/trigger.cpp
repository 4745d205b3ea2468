// Triggering: the stage between the recorder's rings and its journal (trigger.h,
// docs/triggering.md). Everything is sized in the constructor; the per-block paths only
// index preallocated buffers and call the sink. The options, the level detector and the
// summary's report are trigger_options.cpp.
#include "acquisition/record/trigger.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "acquisition/rig/rig_file.h"
#include "core/number_format.h"

namespace doorbench {
namespace {

constexpr std::int32_t kGapCount = kGapFillCount;

template <std::size_t N>
void copy_text(char (&into)[N], std::string_view text) {
  const std::size_t n = std::min(text.size(), N - 1);
  std::memcpy(into, text.data(), n);
  into[n] = '\0';
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The stage

TriggerStage::TriggerStage(const TriggerOptions& options,
                           std::span<const ChannelInfo> scan_channels, double scan_rate_hz,
                           std::size_t max_block_scans,
                           std::span<const ChannelInfo> polled_channels,
                           std::span<const CalibrationRecord> calibrations, RecordingSink& sink)
    : options_(options),
      sink_(sink),
      scan_channels_(scan_channels.begin(), scan_channels.end()),
      polled_channels_(polled_channels.begin(), polled_channels.end()),
      rate_hz_(scan_rate_hz),
      max_block_scans_(max_block_scans) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("trigger options: " + problem);
  }
  if (scan_channels_.empty() && polled_channels_.empty()) {
    throw std::invalid_argument("trigger stage: no channels");
  }
  if (!scan_channels_.empty()) {
    if (!(scan_rate_hz > 0) || !std::isfinite(scan_rate_hz)) {
      throw std::invalid_argument("trigger stage: scan_rate_hz must be > 0 (got " +
                                  format_number(scan_rate_hz) + ")");
    }
    if (max_block_scans == 0) {
      throw std::invalid_argument("trigger stage: max_block_scans must be >= 1");
    }
  } else {
    rate_hz_ = 0.0;
  }
  for (const ChannelInfo& channel : scan_channels_) {
    if (channel.raw_type != RawType::kCounts) {
      throw std::invalid_argument("trigger stage: scan channel " + channel.name +
                                  " must hold counts");
    }
    scan_convert_.emplace_back(channel, calibrations);
  }
  for (const ChannelInfo& channel : polled_channels_) {
    polled_convert_.emplace_back(channel, calibrations);
  }

  auto unit_of = [&](const Target& target) {
    return target.polled ? polled_channels_[target.index].unit : scan_channels_[target.index].unit;
  };
  if (options_.start == TriggerOptions::Start::kLevel) {
    start_target_ = resolve(options_.start_level, "start");
    start_detector_ = LevelDetector(options_.start_level);
    trigger_detail_ = "level " + options_.start_level.describe(unit_of(start_target_));
  } else if (options_.start == TriggerOptions::Start::kManual) {
    trigger_detail_ = "manual";
  } else if (options_.start == TriggerOptions::Start::kExternal) {
    trigger_detail_ = "external " + options_.external_source;
  } else {
    trigger_detail_ = "immediate";
  }
  if (options_.stop == TriggerOptions::Stop::kLevel) {
    stop_target_ = resolve(options_.stop_level, "stop");
    stop_detector_ = LevelDetector(options_.stop_level);
    stop_detail_ = "level " + options_.stop_level.describe(unit_of(stop_target_));
    if (options_.stop_level.hold_s > 0) {
      stop_detail_.append(" held ").append(format_number(options_.stop_level.hold_s)).append(" s");
    }
    stop_channel_ = options_.stop_level.channel;
  } else if (options_.stop == TriggerOptions::Stop::kManual) {
    stop_detail_ = "manual";
  }
  duration_detail_ = "duration " + format_number(options_.duration_s) + " s";
  if (options_.strokes) {
    stroke_target_ = resolve(*options_.strokes, "strokes");
    stroke_detector_ = LevelDetector(*options_.strokes);
    stroke_channel_ = options_.strokes->channel;
  }

  // Buffers: the pre-trigger span, one block (the block that triggers is buffered whole
  // first) and the lookahead for a trigger from a polled channel that lags the scans.
  if (!scan_channels_.empty()) {
    pre_scans_ = static_cast<std::size_t>(std::llround(options_.pre_trigger_s * rate_hz_));
    scan_capacity_ = pre_scans_ + max_block_scans_ +
                     static_cast<std::size_t>(std::ceil(options_.lookahead_s * rate_hz_));
    scan_buffer_.assign(scan_channels_.size() * scan_capacity_, 0);
  }
  if (!polled_channels_.empty()) {
    timed_capacity_ =
        static_cast<std::size_t>(std::ceil(options_.max_poll_rate_hz *
                                           (options_.pre_trigger_s + options_.lookahead_s))) +
        16;
    const std::size_t total = polled_channels_.size() * timed_capacity_;
    timed_time_.assign(total, 0.0);
    timed_latency_.assign(total, 0.0);
    timed_raw_.assign(total, 0.0);
    timed_head_.assign(polled_channels_.size(), 0);
    timed_count_.assign(polled_channels_.size(), 0);
  }
  event_buffer_.resize(kEventSlots);
  counters_.buffer_bytes = scan_buffer_.size() * sizeof(std::int32_t) +
                           3 * timed_time_.size() * sizeof(double) +
                           event_buffer_.size() * sizeof(EventSlot);
}

TriggerStage::Target TriggerStage::resolve(const LevelCondition& condition,
                                           std::string_view what) const {
  Target target;
  for (std::size_t c = 0; c < scan_channels_.size(); ++c) {
    if (scan_channels_[c].name == condition.channel) {
      target.index = c;
      target.convert = &scan_convert_[c];
      target.first_time_s = scan_channels_[c].first_sample_time_s;
      return target;
    }
  }
  for (std::size_t c = 0; c < polled_channels_.size(); ++c) {
    if (polled_channels_[c].name == condition.channel) {
      target.polled = true;
      target.index = c;
      target.convert = &polled_convert_[c];
      return target;
    }
  }
  std::string names;
  for (const ChannelInfo& channel : scan_channels_)
    names.append(names.empty() ? "" : ", ").append(channel.name);
  for (const ChannelInfo& channel : polled_channels_)
    names.append(names.empty() ? "" : ", ").append(channel.name);
  throw std::invalid_argument(std::string("trigger options: ")
                                  .append(what)
                                  .append(" condition names channel \"")
                                  .append(condition.channel)
                                  .append("\", which is not in the session (channels: ")
                                  .append(names)
                                  .append(")"));
}

std::optional<std::uint64_t> TriggerStage::first_forwarded_scan() const {
  if (state_ == State::kArmed || scan_channels_.empty()) return std::nullopt;
  return first_kept_scan_;
}

std::optional<double> TriggerStage::first_forwarded_time_s() const {
  if (state_ == State::kArmed || scan_channels_.empty()) return std::nullopt;
  return scan_time_s(first_kept_scan_);
}

std::optional<double> TriggerStage::trigger_time_s() const {
  if (state_ == State::kArmed) return std::nullopt;
  return trigger_time_;
}

TriggerSummary TriggerStage::summary() const {
  TriggerSummary summary = counters_;
  summary.state = state_ == State::kArmed       ? "armed"
                  : state_ == State::kTriggered ? "triggered"
                                                : "stopped";
  if (state_ != State::kArmed) summary.trigger_time_s = trigger_time_;
  if (state_ == State::kStopped) summary.stop_time_s = stop_time_;
  summary.first_forwarded_scan = first_kept_scan_;
  summary.strokes = strokes_;
  return summary;
}

void TriggerStage::send_event(double time_s, std::string_view kind, std::string_view channel,
                              std::string_view detail) {
  sink_.event(time_s, kind, channel, detail);
  ++counters_.forwarded_events;
}

// --- input: scans

void TriggerStage::scans(std::uint64_t first_scan, std::size_t count, const std::int32_t* counts,
                         std::size_t stride) {
  if (scan_channels_.empty()) {
    throw std::invalid_argument("trigger stage: scans() in a session without scan channels");
  }
  if (count > max_block_scans_ || (count > 0 && stride < count)) {
    throw std::invalid_argument("trigger stage: a block of " + std::to_string(count) +
                                " scans (stride " + std::to_string(stride) +
                                ") exceeds max_block_scans " + std::to_string(max_block_scans_));
  }
  if (first_scan < next_scan_) {
    throw std::invalid_argument("trigger stage: scans from " + std::to_string(first_scan) +
                                " go back (the next scan is " + std::to_string(next_scan_) + ")");
  }
  if (count == 0) return;

  if (state_ == State::kArmed) {
    buffer_scans(first_scan, count, counts, stride);
    next_scan_ = first_scan + count;
    if (options_.start == TriggerOptions::Start::kImmediate ||
        options_.start == TriggerOptions::Start::kExternal ||
        (options_.start == TriggerOptions::Start::kManual && manual(options_.manual_start))) {
      const std::uint64_t at =
          options_.start == TriggerOptions::Start::kManual ? first_scan : buffer_first_;
      fire_trigger(scan_time_s(at), at, trigger_detail_);
      return;
    }
    if (options_.start == TriggerOptions::Start::kLevel && !start_target_.polled) {
      const std::size_t c = start_target_.index;
      for (std::size_t s = 0; s < count; ++s) {
        const std::int32_t raw = counts[c * stride + s];
        if (raw == kGapCount) continue;
        if (start_detector_.fire((*start_target_.convert)(raw))) {
          const std::uint64_t scan = first_scan + s;
          fire_trigger(start_target_.first_time_s + scan_time_s(scan), scan, trigger_detail_);
          return;
        }
      }
    }
    return;
  }
  next_scan_ = first_scan + count;
  if (state_ == State::kTriggered && options_.stop == TriggerOptions::Stop::kManual &&
      manual(options_.manual_stop)) {
    stop_scan_ = first_scan;
    stop_now(scan_time_s(first_scan), stop_detail_, "", false);
    return;
  }
  forward_scans(first_scan, count, counts, stride);
}

void TriggerStage::buffer_scans(std::uint64_t first_scan, std::size_t count,
                                const std::int32_t* counts, std::size_t stride) {
  if (first_scan != buffer_first_ + buffer_count_) {
    // Scans were lost (a ring overflow): the history before the gap is not contiguous
    // with what follows, so the pre-trigger buffer starts again after it.
    buffer_first_ = first_scan;
    buffer_count_ = 0;
  }
  const std::size_t channels = scan_channels_.size();
  std::size_t done = 0;
  while (done < count) {
    const std::size_t position = static_cast<std::size_t>((first_scan + done) % scan_capacity_);
    const std::size_t n = std::min(count - done, scan_capacity_ - position);
    for (std::size_t c = 0; c < channels; ++c) {
      std::memcpy(&scan_buffer_[c * scan_capacity_ + position], counts + c * stride + done,
                  n * sizeof(std::int32_t));
    }
    done += n;
  }
  buffer_count_ += count;
  if (buffer_count_ > scan_capacity_) {
    buffer_first_ += buffer_count_ - scan_capacity_;
    buffer_count_ = scan_capacity_;
  }
}

// --- input: polled samples

void TriggerStage::timed_samples(std::uint32_t channel, std::span<const double> time_s,
                                 std::span<const double> latency_s, std::span<const double> raw) {
  if (channel >= polled_channels_.size()) {
    throw std::invalid_argument("trigger stage: polled channel " + std::to_string(channel) +
                                " does not exist (there are " +
                                std::to_string(polled_channels_.size()) + ")");
  }
  if (latency_s.size() != time_s.size() || raw.size() != time_s.size()) {
    throw std::invalid_argument("trigger stage: time_s, latency_s and raw differ in length");
  }
  if (time_s.empty()) return;
  if (state_ != State::kArmed) {
    if (state_ == State::kTriggered && scan_channels_.empty() &&
        options_.stop == TriggerOptions::Stop::kManual && manual(options_.manual_stop)) {
      stop_now(time_s.front(), stop_detail_, "", false);
      return;
    }
    forward_timed(channel, time_s, latency_s, raw);
    return;
  }
  // Armed. Without scan channels the polled samples drive the start.
  if (scan_channels_.empty() &&
      (options_.start == TriggerOptions::Start::kImmediate ||
       options_.start == TriggerOptions::Start::kExternal ||
       (options_.start == TriggerOptions::Start::kManual && manual(options_.manual_start)))) {
    fire_trigger(time_s.front(), 0, trigger_detail_);
    forward_timed(channel, time_s, latency_s, raw);
    return;
  }
  const bool detect = options_.start == TriggerOptions::Start::kLevel && start_target_.polled &&
                      start_target_.index == channel;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    buffer_timed(channel, time_s.subspan(i, 1), latency_s.subspan(i, 1), raw.subspan(i, 1));
    if (detect && start_detector_.fire((*start_target_.convert)(raw[i]))) {
      // The first scan at or after the crossing.
      const double at = std::max(0.0, std::ceil(time_s[i] * rate_hz_ - 1e-9));
      fire_trigger(time_s[i], static_cast<std::uint64_t>(at), trigger_detail_);
      if (i + 1 < time_s.size()) {
        forward_timed(channel, time_s.subspan(i + 1), latency_s.subspan(i + 1), raw.subspan(i + 1));
      }
      return;
    }
  }
}

void TriggerStage::buffer_timed(std::uint32_t channel, std::span<const double> time_s,
                                std::span<const double> latency_s, std::span<const double> raw) {
  const std::size_t base = channel * timed_capacity_;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    std::size_t& head = timed_head_[channel];  // the oldest
    std::size_t& count = timed_count_[channel];
    std::size_t slot = (head + count) % timed_capacity_;
    if (count == timed_capacity_) {
      slot = head;
      head = (head + 1) % timed_capacity_;
      ++counters_.timed_overwritten;
    } else {
      ++count;
    }
    timed_time_[base + slot] = time_s[i];
    timed_latency_[base + slot] = latency_s[i];
    timed_raw_[base + slot] = raw[i];
  }
}

// --- input: events

void TriggerStage::event(double time_s, std::string_view kind, std::string_view channel,
                         std::string_view detail) {
  char text[sizeof EventSlot::detail];
  if (kind == "trigger") {
    // The backend's own start of the acquisition; the session's trigger is the stage's.
    std::snprintf(text, sizeof text, "acquisition started (%.*s)", static_cast<int>(detail.size()),
                  detail.data());
    kind = "mark";
    detail = text;
    if (state_ != State::kStopped) send_event(time_s, kind, channel, detail);
    return;
  }
  if (state_ == State::kStopped) {
    // Faults about data that was kept (e.g. a late poll's) still count; nothing after.
    if ((kind == "fault" || kind == "gap") && time_s <= stop_time_) {
      send_event(time_s, kind, channel, detail);
    }
    return;
  }
  if (state_ == State::kTriggered || kind == "fault" || kind == "gap") {
    send_event(time_s, kind, channel, detail);
    return;
  }
  std::size_t slot = (event_head_ + event_count_) % kEventSlots;
  if (event_count_ == kEventSlots) {
    slot = event_head_;
    event_head_ = (event_head_ + 1) % kEventSlots;
    ++counters_.events_overwritten;
  } else {
    ++event_count_;
  }
  EventSlot& held = event_buffer_[slot];
  held.time_s = time_s;
  copy_text(held.kind, kind);
  copy_text(held.channel, channel);
  copy_text(held.detail, detail);
}

// --- the trigger

void TriggerStage::fire_trigger(double time_s, std::uint64_t trigger_scan,
                                std::string_view detail) {
  state_ = State::kTriggered;
  trigger_time_ = time_s;
  trigger_scan_ = trigger_scan;
  first_kept_scan_ = std::max<std::uint64_t>(
      trigger_scan >= pre_scans_ ? trigger_scan - pre_scans_ : 0, buffer_first_);
  first_kept_time_ = time_s - options_.pre_trigger_s;
  if (options_.duration_s > 0) {
    duration_end_s_ = time_s + options_.duration_s;
    if (!scan_channels_.empty()) {
      duration_scan_ =
          trigger_scan + static_cast<std::uint64_t>(std::llround(options_.duration_s * rate_hz_));
      stop_scan_ = duration_scan_;
    }
  }

  // 1. Events held back that fall in the pre-trigger window.
  for (std::size_t i = 0; i < event_count_; ++i) {
    const EventSlot& held = event_buffer_[(event_head_ + i) % kEventSlots];
    if (held.time_s >= first_kept_time_) {
      send_event(held.time_s, held.kind, held.channel, held.detail);
    }
  }
  event_count_ = 0;

  // 2. Buffered scans before the trigger scan, then polled samples before the trigger.
  auto forward_buffered_scans = [&](std::uint64_t from, std::uint64_t to) {
    while (from < to && state_ != State::kStopped) {
      const std::size_t position = static_cast<std::size_t>(from % scan_capacity_);
      const std::size_t n =
          static_cast<std::size_t>(std::min<std::uint64_t>(to - from, scan_capacity_ - position));
      forward_scans(from, n, scan_buffer_.data() + position, scan_capacity_);
      from += n;
    }
  };
  const std::uint64_t buffer_end = buffer_first_ + buffer_count_;
  if (!scan_channels_.empty()) {
    forward_buffered_scans(std::max(first_kept_scan_, buffer_first_),
                           std::min(trigger_scan, buffer_end));
  }
  auto forward_buffered_timed = [&](bool before_trigger) {
    for (std::size_t c = 0; c < polled_channels_.size(); ++c) {
      const std::size_t base = c * timed_capacity_;
      const std::size_t head = timed_head_[c];
      const std::size_t count = timed_count_[c];
      // The buffer is at most two runs in memory; each is split at the trigger time.
      for (std::size_t done = 0; done < count;) {
        const std::size_t position = (head + done) % timed_capacity_;
        const std::size_t n = std::min(count - done, timed_capacity_ - position);
        const double* times = &timed_time_[base + position];
        const std::size_t split =
            static_cast<std::size_t>(std::lower_bound(times, times + n, time_s) - times);
        const std::size_t from = before_trigger ? 0 : split;
        const std::size_t to = before_trigger ? split : n;
        if (from < to) {
          forward_timed(static_cast<std::uint32_t>(c),
                        std::span<const double>(times + from, to - from),
                        std::span<const double>(&timed_latency_[base + position + from], to - from),
                        std::span<const double>(&timed_raw_[base + position + from], to - from));
        }
        done += n;
      }
    }
  };
  forward_buffered_timed(true);

  // 3. The trigger, then what was buffered from the trigger on (it is live data).
  send_event(time_s, "trigger",
             options_.start == TriggerOptions::Start::kLevel
                 ? std::string_view(options_.start_level.channel)
                 : std::string_view(),
             detail);
  if (!scan_channels_.empty()) {
    forward_buffered_scans(std::max(trigger_scan, buffer_first_), buffer_end);
  }
  forward_buffered_timed(false);
  buffer_count_ = 0;
  for (std::size_t c = 0; c < polled_channels_.size(); ++c) timed_count_[c] = 0;
}

void TriggerStage::stop_now(double time_s, std::string_view detail, std::string_view channel,
                            bool inclusive) {
  state_ = State::kStopped;
  stop_time_ = time_s;
  stop_end_s_ =
      inclusive ? std::nextafter(time_s, std::numeric_limits<double>::infinity()) : time_s;
  send_event(time_s, "stop", channel, detail);
}

// --- forwarding

void TriggerStage::strokes_at(bool polled, std::size_t channel, double time_s, double raw) {
  if (!options_.strokes || stroke_target_.polled != polled || stroke_target_.index != channel) {
    return;
  }
  const double value = (*stroke_target_.convert)(raw);
  char detail[32];
  auto announce = [&] {
    ++strokes_;
    std::snprintf(detail, sizeof detail, "stroke %llu", static_cast<unsigned long long>(strokes_));
    send_event(stroke_start_, "stroke_start", stroke_channel_, detail);
    stroke_announced_ = true;
  };
  if (!in_stroke_) {
    if (stroke_detector_.fire(value)) {
      in_stroke_ = true;
      stroke_announced_ = false;
      stroke_start_ = time_s;
    }
    return;
  }
  const bool long_enough = time_s - stroke_start_ >= options_.min_stroke_s - 1e-9;
  if (stroke_detector_.released(value)) {
    if (!stroke_announced_ && long_enough) announce();
    if (stroke_announced_) send_event(time_s, "stroke_end", stroke_channel_, "");
    in_stroke_ = false;
    stroke_detector_.fire(value);  // re-arms: the value is beyond the hysteresis
    return;
  }
  if (!stroke_announced_ && long_enough) announce();
}

bool TriggerStage::stop_at(bool polled, std::size_t channel, double time_s, double raw, bool live) {
  if (!live || options_.stop != TriggerOptions::Stop::kLevel || stop_target_.polled != polled ||
      stop_target_.index != channel) {
    return false;
  }
  const double value = (*stop_target_.convert)(raw);
  if (!holding_) {
    if (!stop_detector_.fire(value)) return false;
    if (options_.stop_level.hold_s <= 0) return true;
    holding_ = true;
    hold_since_ = time_s;
    return false;
  }
  if (!stop_detector_.on_fired_side(value)) {
    holding_ = false;
    stop_detector_.fire(value);  // re-arms
    return false;
  }
  return time_s - hold_since_ >= options_.stop_level.hold_s - 1e-9;
}

void TriggerStage::forward_scans(std::uint64_t first_scan, std::size_t count,
                                 const std::int32_t* counts, std::size_t stride) {
  const std::uint64_t begin = std::max(first_scan, first_kept_scan_);
  const std::uint64_t end = std::min<std::uint64_t>(first_scan + count, stop_scan_);
  if (begin >= end) {
    if (state_ == State::kTriggered && begin >= duration_scan_) {
      stop_now(duration_end_s_, duration_detail_, "", false);
    }
    return;
  }
  std::uint64_t cut = end;
  double stop_time = 0.0;
  bool stop = false;
  if (state_ == State::kTriggered) {
    const bool stroke_scan = options_.strokes && !stroke_target_.polled;
    const bool stop_scan = options_.stop == TriggerOptions::Stop::kLevel && !stop_target_.polled;
    for (std::uint64_t scan = begin; scan < end && (stroke_scan || stop_scan); ++scan) {
      const std::size_t s = static_cast<std::size_t>(scan - first_scan);
      if (stroke_scan) {
        const std::int32_t raw = counts[stroke_target_.index * stride + s];
        if (raw != kGapCount) {
          strokes_at(false, stroke_target_.index, stroke_target_.first_time_s + scan_time_s(scan),
                     raw);
        }
      }
      if (stop_scan) {
        const std::int32_t raw = counts[stop_target_.index * stride + s];
        const double time_s = stop_target_.first_time_s + scan_time_s(scan);
        if (raw != kGapCount &&
            stop_at(false, stop_target_.index, time_s, raw, scan >= trigger_scan_)) {
          cut = scan + 1;
          stop_time = time_s;
          stop = true;
          break;
        }
      }
    }
  }
  sink_.scans(begin - first_kept_scan_, static_cast<std::size_t>(cut - begin),
              counts + (begin - first_scan), stride);
  counters_.forwarded_scans += cut - begin;
  if (stop) {
    stop_scan_ = cut;
    stop_now(stop_time, stop_detail_, stop_channel_, true);
  } else if (state_ == State::kTriggered && cut == duration_scan_) {
    stop_now(duration_end_s_, duration_detail_, "", false);
  }
}

void TriggerStage::forward_timed(std::uint32_t channel, std::span<const double> time_s,
                                 std::span<const double> latency_s, std::span<const double> raw) {
  // Kept: from the pre-trigger window's start to the stop (inclusive for a level's or
  // manual stop, exclusive for a duration's end).
  const double end_s = state_ == State::kStopped ? stop_end_s_ : duration_end_s_;
  std::size_t begin = 0;
  while (begin < time_s.size() && time_s[begin] < first_kept_time_) ++begin;
  std::size_t cut = begin;
  bool stop = false, by_duration = false;
  double stop_time = 0.0;
  for (; cut < time_s.size(); ++cut) {
    const double t = time_s[cut];
    if (!(t < end_s)) {
      // Past a duration's end: only a session without scans stops here (scans stop by
      // their exact count).
      if (state_ == State::kTriggered && scan_channels_.empty()) {
        by_duration = true;
      }
      break;
    }
    if (state_ != State::kTriggered) continue;
    strokes_at(true, channel, t, raw[cut]);
    if (stop_at(true, channel, t, raw[cut], t >= trigger_time_)) {
      stop = true;
      stop_time = t;
      ++cut;
      break;
    }
  }
  if (cut > begin) {
    sink_.timed_samples(channel, time_s.subspan(begin, cut - begin),
                        latency_s.subspan(begin, cut - begin), raw.subspan(begin, cut - begin));
    counters_.forwarded_timed_samples += cut - begin;
  }
  if (stop) {
    // Scans up to the crossing's time are kept; later ones that already went out stay.
    if (!scan_channels_.empty()) {
      stop_scan_ = std::min<std::uint64_t>(
          stop_scan_, static_cast<std::uint64_t>(std::floor(stop_time * rate_hz_ + 1e-9)) + 1);
    }
    stop_now(stop_time, stop_detail_, stop_channel_, true);
  } else if (by_duration) {
    stop_now(duration_end_s_, duration_detail_, "", false);
  }
}

}  // namespace doorbench
