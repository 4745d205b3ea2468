#include "viewer/live_journal.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "acquisition/record/recovery.h"
#include "viewer/session_data.h"

namespace doorbench::viewer {

namespace fs = std::filesystem;

std::string LiveOptions::validate() const {
  if (!(window_s > 0.0) || !std::isfinite(window_s)) {
    return "window_s must be a positive number of seconds";
  }
  if (capacity_samples < 2) return "capacity_samples must be at least 2";
  if (max_events < 1) return "max_events must be at least 1";
  if (max_plot_samples < 4) return "max_plot_samples must be at least 4";
  return "";
}

const char* to_string(LiveState state) {
  switch (state) {
    case LiveState::kWaiting:
      return "waiting";
    case LiveState::kRecording:
      return "recording";
    case LiveState::kEnded:
      return "ended";
    case LiveState::kGone:
      return "gone";
  }
  return "?";
}

SampleRing::SampleRing(std::size_t capacity)
    : time_(std::max<std::size_t>(capacity, 1)), value_(time_.size()) {}

void SampleRing::push(double time_s, double value) {
  const std::size_t slot = (begin_ + size_) % time_.size();
  time_[slot] = time_s;
  value_[slot] = value;
  if (size_ < time_.size()) {
    ++size_;
  } else {
    begin_ = (begin_ + 1) % time_.size();
  }
  ++pushed_;
}

namespace {

// The journal's inode, 0 when it does not exist.
std::uint64_t inode_of(const fs::path& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return 0;
  return static_cast<std::uint64_t>(status.st_ino);
}

}  // namespace

LiveJournal::LiveJournal(const fs::path& path, const LiveOptions& options) : options_(options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("live view: " + problem);
  }
  const std::string name = path.filename().string();
  const std::string suffix = kJournalSuffix;
  if (name.size() > suffix.size() && name.ends_with(suffix)) {
    journal_ = path;
    session_ = path.parent_path() / name.substr(0, name.size() - suffix.size());
  } else {
    journal_ = journal_path_for(path);
    session_ = path;
  }
  waiting_reason_ = "no journal yet";
}

const JournalHeader& LiveJournal::header() const {
  if (!reader_) throw std::logic_error(journal_.string() + ": the journal is not open yet");
  return reader_->header();
}

std::uint64_t LiveJournal::valid_bytes() const {
  return reader_ ? reader_->valid_bytes() : 0;
}

bool LiveJournal::open() {
  const std::uint64_t inode = inode_of(journal_);
  if (inode == 0) {
    waiting_reason_ = "no journal yet (" + journal_.string() + ")";
    return false;
  }
  // The size before the reader looks: the writer only appends, so the reader saw at least
  // this many bytes. A size taken after the reader failed would not do: the writer may
  // have written the whole header in between, and an empty file read a moment earlier
  // would then be taken for one that is not a journal (docs/viewer.md, "Live: following a
  // running recording").
  std::error_code size_error;
  const std::uintmax_t size_before = fs::file_size(journal_, size_error);
  try {
    reader_ = std::make_unique<JournalReader>(journal_);
  } catch (const JournalError& error) {
    // A header still being written is "not yet" (the writer writes magic, version, length
    // and CRC in the same write() as the JSON; a file shorter than that is brand new, and
    // one gone again is not there yet); anything else is not a journal.
    const std::string text = error.what();
    if (text.find("header is incomplete") != std::string::npos || size_error ||
        size_before < sizeof(kJournalMagic) - 1 + 12) {
      waiting_reason_ = "the journal's header is being written";
      return false;
    }
    throw;
  }
  inode_ = inode;
  const JournalHeader& header = reader_->header();
  const std::size_t channels = header.channels.size();
  rings_.assign(channels, SampleRing(options_.capacity_samples));
  latency_channel_.assign(channels, -1);
  calib_.assign(channels, nullptr);
  calibration_problems_.clear();
  for (std::size_t c = 0; c < channels; ++c) {
    for (std::size_t l = 0; l < channels; ++l) {
      if (header.channels[l].sensor_kind == "poll_latency" &&
          header.channels[l].name == header.channels[c].name + "_latency") {
        latency_channel_[c] = static_cast<int>(l);
      }
    }
    const std::string& id = header.channels[c].calibration_id;
    if (id.empty()) continue;
    for (const CalibrationRecord& record : header.calibrations) {
      if (record.id == id) calib_[c] = &record;
    }
    if (!calib_[c]) {
      // Shown uncalibrated (the signal), and said so, rather than not at all.
      calibration_problems_.push_back("channel " + header.channels[c].name +
                                      " uses calibration record " + id +
                                      ", which is not in the journal (signal shown)");
    }
  }
  state_ = LiveState::kRecording;
  return true;
}

double LiveJournal::physical(std::size_t c, double raw) const {
  const ChannelInfo& info = reader_->header().channels[c];
  const double signal = info.raw_offset + info.raw_scale * raw;
  return calib_[c] ? calib_[c]->apply(signal) : signal;
}

void LiveJournal::read_frames(LivePoll& result) {
  const JournalHeader& header = reader_->header();
  const std::size_t scan_channels = scan_channel_count(header);
  while (reader_->next(frame_)) {
    ++result.frames;
    ++frames_;
    switch (frame_.type) {
      case FrameType::kStart:
        break;
      case FrameType::kScans: {
        const double nan = std::numeric_limits<double>::quiet_NaN();
        for (std::size_t c = 0; c < scan_channels; ++c) {
          const ChannelInfo& info = header.channels[c];
          const double dt = 1.0 / info.sample_rate_hz;
          // Scans the writer lost (a gap): one NaN breaks the line where they were.
          if (frame_.first_scan > next_scan_ && next_scan_ > 0) {
            rings_[c].push(info.first_sample_time_s + static_cast<double>(next_scan_) * dt, nan);
          }
          const std::int32_t* counts = frame_.counts.data() + c * frame_.scan_count;
          for (std::size_t s = 0; s < frame_.scan_count; ++s) {
            const double t =
                info.first_sample_time_s + static_cast<double>(frame_.first_scan + s) * dt;
            rings_[c].push(t, counts[s] == kGapFillCount ? nan : physical(c, counts[s]));
          }
          if (frame_.scan_count > 0) {
            latest_s_ = std::max(
                latest_s_, info.first_sample_time_s +
                               static_cast<double>(frame_.first_scan + frame_.scan_count - 1) * dt);
          }
        }
        next_scan_ = frame_.first_scan + frame_.scan_count;
        result.scans += frame_.scan_count;
        scans_ += frame_.scan_count;
        break;
      }
      case FrameType::kTimed: {
        const std::size_t c = frame_.channel;
        const int l = latency_channel_[c];
        for (std::size_t i = 0; i < frame_.scan_count; ++i) {
          const double t = static_cast<double>(frame_.time_ns[i]) * 1e-9;
          // Polled samples out of order are dropped, as in the session (recovery.cpp).
          if (rings_[c].size() > 0 && t <= rings_[c].time(rings_[c].size() - 1)) continue;
          rings_[c].push(t, physical(c, frame_.raw[i]));
          if (l >= 0) {
            const auto lc = static_cast<std::size_t>(l);
            rings_[lc].push(t, physical(lc, static_cast<double>(frame_.latency_ns[i]) * 1e-9));
          }
          latest_s_ = std::max(latest_s_, t);
          ++result.timed_samples;
        }
        break;
      }
      case FrameType::kEvent:
        events_.push_back(frame_.event);
        if (events_.size() > options_.max_events) events_.pop_front();
        ++result.events;
        break;
      case FrameType::kEnd:
        if (state_ != LiveState::kEnded) {
          state_ = LiveState::kEnded;
          result.state_changed = true;
        }
        break;
    }
  }
}

LivePoll LiveJournal::poll() {
  LivePoll result;
  const LiveState before = state_;
  if (!reader_) {
    if (state_ == LiveState::kGone) return result;
    if (!open()) {
      // A journal that never showed up while the session exists: the recording is over.
      std::error_code ignored;
      if (fs::exists(session_, ignored) && fs::is_regular_file(session_, ignored)) {
        state_ = LiveState::kGone;
        gone_reason_ = "no journal: " + session_.string() + " is a finished session (open it " +
                       "without --live)";
      }
      result.state_changed = state_ != before;
      return result;
    }
  }
  // Read the name before the data: a journal removed after this check is noticed at the
  // next poll, and its last frames are read then, through the open file.
  const std::uint64_t inode = inode_of(journal_);
  reader_->refresh();
  read_frames(result);
  stop_reason_ = reader_->stop_reason();
  if (inode != inode_ && state_ != LiveState::kGone) {
    std::error_code ignored;
    state_ = LiveState::kGone;
    gone_reason_ = fs::exists(session_, ignored)
                       ? "the journal was converted to " + session_.string()
                       : "the journal was removed";
    if (inode != 0) gone_reason_ = "the journal was replaced (a new recording?)";
  }
  if (result.frames > 0) ++revision_;
  result.state_changed = result.state_changed || state_ != before;
  return result;
}

std::string LiveJournal::status() const {
  char text[160];
  std::string line = to_string(state_);
  if (reader_) {
    std::snprintf(text, sizeof text, ": %.3f s, %llu scans, %llu frames, %zu events", latest_s_,
                  static_cast<unsigned long long>(scans_), static_cast<unsigned long long>(frames_),
                  events_.size());
    line += text;
  }
  switch (state_) {
    case LiveState::kWaiting:
      line.append(" (").append(waiting_reason_).append(")");
      break;
    case LiveState::kRecording:
      if (!stop_reason_.empty() && stop_reason_.rfind("incomplete", 0) != 0) {
        line.append("; waiting at ").append(stop_reason_);
      }
      break;
    case LiveState::kEnded:
      line += "; the recording ended";
      break;
    case LiveState::kGone:
      line.append("; ").append(gone_reason_);
      break;
  }
  for (const std::string& problem : calibration_problems_) line.append("; ").append(problem);
  return line;
}

std::size_t LiveJournal::memory_bytes() const {
  std::size_t bytes = 0;
  for (const SampleRing& ring : rings_) bytes += ring.capacity() * 2 * sizeof(double);
  for (const SessionEvent& e : events_) {
    bytes += sizeof e + e.kind.capacity() + e.channel.capacity() + e.detail.capacity();
  }
  return bytes;
}

bool LiveJournal::update_plots(std::vector<PlotView>& plots) const {
  if (!reader_) return false;
  const JournalHeader& header = reader_->header();
  const std::size_t channels = header.channels.size();
  if (plots.size() == channels && !plots.empty() && plots.front().revision == revision_) {
    return false;
  }
  const bool fresh = plots.size() != channels;
  if (fresh) {
    plots.assign(channels, PlotView{});
    for (std::size_t c = 0; c < channels; ++c) {
      const ChannelInfo& info = header.channels[c];
      plots[c].title = info.name;
      plots[c].x_label = "time";
      plots[c].y_label = info.sensor_kind;
      if (c > 0) plots[c].link_x_to(plots.front());
    }
  }
  const double x_max = std::max(latest_s_, options_.window_s * 1e-6);
  const double x_min = x_max - options_.window_s;
  for (std::size_t c = 0; c < channels; ++c) {
    const ChannelInfo& info = header.channels[c];
    const SampleRing& ring = rings_[c];
    // Only what the window shows (and one sample before it, so the line enters from the
    // left edge) becomes the plotted series.
    std::size_t low = 0, high = ring.size();  // the first sample at or after x_min
    while (low < high) {
      const std::size_t mid = low + (high - low) / 2;
      if (ring.time(mid) < x_min) {
        low = mid + 1;
      } else {
        high = mid;
      }
    }
    const std::size_t first = low > 0 ? low - 1 : 0;
    const std::size_t n = ring.size() - first;
    std::vector<double> x, y;
    x.reserve(std::min(n, options_.max_plot_samples) + 2);
    y.reserve(x.capacity());
    // Walks the storage from the window's first sample, wrapping at the end (no division
    // per sample: this runs over every plotted sample at every update).
    const std::vector<double>& times = ring.time_storage();
    const std::vector<double>& values = ring.value_storage();
    const std::size_t capacity = ring.capacity();
    std::size_t p = n > 0 ? ring.slot(first) : 0;
    const auto advance = [&] { p = p + 1 == capacity ? 0 : p + 1; };
    if (n <= options_.max_plot_samples) {
      for (std::size_t i = 0; i < n; ++i, advance()) {
        x.push_back(times[p]);
        y.push_back(values[p]);
      }
    } else {
      // Buckets of samples: each gives its min and max in the order they came, and a NaN
      // (a gap) in a bucket breaks the line after them.
      const std::size_t buckets = options_.max_plot_samples / 2 - 1;
      const std::size_t per = (n + buckets - 1) / buckets;
      for (std::size_t b = 0; b < n; b += per) {
        const std::size_t count = std::min(n - b, per);
        double low = std::numeric_limits<double>::infinity(), high = -low;
        std::size_t low_p = 0, high_p = 0, low_i = 0, high_i = 0, last_p = p;
        bool gap = false, any = false;
        for (std::size_t i = 0; i < count; ++i, advance()) {
          const double v = values[p];
          last_p = p;
          if (std::isnan(v)) {
            gap = true;
            continue;
          }
          any = true;
          if (v < low) low = v, low_p = p, low_i = i;
          if (v > high) high = v, high_p = p, high_i = i;
        }
        if (any) {
          const bool low_first = low_i <= high_i;
          x.push_back(times[low_first ? low_p : high_p]);
          y.push_back(low_first ? low : high);
          if (low_i != high_i) {
            x.push_back(times[low_first ? high_p : low_p]);
            y.push_back(low_first ? high : low);
          }
        }
        if (gap) {
          x.push_back(times[last_p]);
          y.push_back(std::numeric_limits<double>::quiet_NaN());
        }
      }
    }
    const std::string unit =
        to_display_units(calib_[c] || info.calibration_id.empty() ? info.unit : info.raw_unit, y);
    auto series =
        std::make_shared<Series>(Series::timed(info.name, unit, std::move(x), std::move(y)));
    series->colour = palette(c);
    plots[c].series.clear();
    plots[c].add(std::move(series));
    plots[c].markers = event_markers_of(events_, info.name);
    plots[c].revision = revision_;
  }
  plots.front().x->min = x_min;
  plots.front().x->max = x_max;
  for (PlotView& plot : plots) plot.fit_y();
  return true;
}

}  // namespace doorbench::viewer
