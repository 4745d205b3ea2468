// RigRecording (rig_recording.h): a rig's sources chosen and opened, its trigger armed.
#include "sensors/rig_recording.h"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>

#include "acquisition/record/trigger.h"
#include "sensors/comedi_backend.h"
#include "sensors/modbus_source.h"

namespace doorbench::sensors {

ManualKeys::ManualKeys(bool start_set, int fd) : start_(start_set) {
  if (::pipe(wake_) != 0) throw std::runtime_error("the Enter key's reader: cannot make a pipe");
  reader_ = std::thread([this, fd] { read_keys(fd); });
}

ManualKeys::~ManualKeys() {
  const char wake = 0;
  while (::write(wake_[1], &wake, 1) < 0 && errno == EINTR) {
  }
  reader_.join();
  ::close(wake_[0]);
  ::close(wake_[1]);
}

void ManualKeys::read_keys(int fd) {
  pollfd fds[2] = {{fd, POLLIN, 0}, {wake_[0], POLLIN, 0}};
  for (;;) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[1].revents != 0) return;  // woken: the recording is over
    if (fds[0].revents == 0) continue;
    char key = 0;  // one byte at a time: nothing after the last line is taken from `fd`
    const ssize_t got = ::read(fd, &key, 1);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return;  // end of input, or an error: no more keys
    if (key != '\n') continue;
    if (!start_.exchange(true)) continue;
    stop_.store(true);
  }
}

std::string RigRecordingOptions::problem(const RigDefinition& rig) const {
  if (!(duration_s >= 0) || !std::isfinite(duration_s)) {
    return "the duration must be a number of seconds >= 0";
  }
  if (!(max_wait_s >= 0) || !std::isfinite(max_wait_s)) {
    return "the armed wait must be a number of seconds >= 0";
  }
  if (!(flush_interval_s > 0)) return "the flush interval must be > 0 s";
  const bool timed = rig.daq_backend == "none" || rig.daq_backend == "comedi";
  if (timed && !(duration_s > 0) && rig.recording.line == 0) {
    return std::string(rig.daq_backend == "none" ? "a rig of polled sensors" : "a comedi rig") +
           " records for a set time: give --duration-s (or a [recording] table with its "
           "triggers)";
  }
  return "";
}

// A rig with a [recording] table records through a trigger stage: its start and stop
// conditions, pre-trigger buffer and stroke markers; the duration then counts from the
// trigger. Returns the time the acquisition may take in all (armed wait included), or 0
// when the rig has no [recording] table.
double RigRecording::configure_triggering(const RigDefinition& rig) {
  if (rig.recording.line == 0) return 0.0;
  TriggerOptions trigger = trigger_options_from_rig(rig);
  if (options_.duration_s > 0) trigger.duration_s = options_.duration_s;
  const bool manual_start = trigger.start == TriggerOptions::Start::kManual;
  const bool manual_stop = trigger.stop == TriggerOptions::Stop::kManual;
  if (manual_start || manual_stop) {
    keys_ = std::make_unique<ManualKeys>(!manual_start, options_.key_fd);
    trigger.manual_start = keys_->start();
    trigger.manual_stop = keys_->stop();
    if (options_.notice) {
      options_.notice(manual_start ? std::string("armed: press Enter to start recording") +
                                         (manual_stop ? ", Enter again to stop" : "")
                                   : "press Enter to stop recording");
    }
  }
  record_.trigger = trigger;
  // Without a duration the stop condition or a stop request ends it; an hour bounds it.
  return options_.max_wait_s + (trigger.duration_s > 0 ? trigger.duration_s : 3600.0);
}

// A source that runs until stopped (a card, polled sensors) records for the duration, or
// through the rig's triggers (then bounded by the armed wait plus their duration).
void RigRecording::set_timed_recording(const RigDefinition& rig) {
  const double triggered_limit_s = configure_triggering(rig);
  record_.duration_s = triggered_limit_s > 0 ? triggered_limit_s : options_.duration_s;
}

void RigRecording::open_daq(const RigDefinition& daq_rig, const SimulatedScansMaker& simulated) {
  if (daq_rig.daq_backend == "comedi") {
    set_timed_recording(daq_rig);
    ComediOptions comedi;
    comedi.duration_s = record_.duration_s;
    auto card = std::make_shared<ComediBackend>(daq_rig, selected_comedi_api(), comedi);
    setup_report_ = card->setup().brief_report();
    // Blocks of about 20 ms, whatever the rate.
    record_.block_scans =
        std::max<std::size_t>(1, static_cast<std::size_t>(card->scan_rate_hz() / 50));
    // The card runs on its own clock: a writer that falls behind must cost a recorded gap,
    // never a stalled read that overruns the card's buffer.
    record_.when_ring_full = RingFullPolicy::kDropAndRecordFault;
    comedi_ = card.get();
    daq_ = std::move(card);
    return;
  }
  for (const RigChannel& channel : daq_rig.channels) {
    if (channel.backend != "simulated") {
      throw std::runtime_error(daq_rig.source + ": channel " + channel.name + " uses backend " +
                               channel.backend +
                               ", which doorbench cannot record yet (only simulated)");
    }
  }
  SimulatedScans bench = simulated(daq_rig, options_.duration_s);
  record_.duration_s = bench.duration_s;
  // An unpaced simulated bench computes scans on demand and can wait for the writer; a
  // paced one stands for a DAQ that cannot (a full ring is then a recorded fault).
  record_.when_ring_full =
      bench.paced ? RingFullPolicy::kDropAndRecordFault : RingFullPolicy::kWait;
  // The bench plays its hand cycles whatever the trigger keeps of them.
  configure_triggering(daq_rig);
  daq_ = std::move(bench.backend);
}

RigRecording::RigRecording(const RigDefinition& rig, const RigRecordingOptions& options,
                           const SimulatedScansMaker& simulated)
    : options_(options) {
  if (std::string problem = options.problem(rig); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  // The rig's Modbus sensors are polled beside its DAQ (if it has one), which sees only
  // its own channels.
  RigDefinition daq_rig = rig;
  std::erase_if(daq_rig.channels,
                [](const RigChannel& channel) { return channel.backend == "modbus"; });
  if (daq_rig.channels.size() < rig.channels.size()) {
    polled_.push_back(std::make_unique<ModbusSource>(rig));
  }
  if (rig.daq_backend == "none") {
    set_timed_recording(rig);
  } else {
    open_daq(daq_rig, simulated);
  }
  record_.flush_interval_s = options.flush_interval_s;
  record_.stop_requested = options.stop_requested;
  if (record_.trigger && record_.trigger->duration_s > 0) {
    display_duration_s_ = record_.trigger->duration_s;
  } else {
    display_duration_s_ = options.duration_s > 0 ? options.duration_s : record_.duration_s;
  }
}

RigRecording::~RigRecording() = default;

RecordSummary RigRecording::record(const SessionMetadata& metadata,
                                   const std::filesystem::path& out_path,
                                   std::function<void(const RecordStatus&)> progress) {
  record_.progress = std::move(progress);
  RecordSources sources;
  sources.scans = daq_.get();
  for (const auto& source : polled_) sources.polled.push_back(source.get());
  return record_session(sources, metadata, out_path, record_);
}

std::string RigRecording::end_warning() const {
  if (comedi_ == nullptr || !comedi_->overran()) return "";
  return comedi_->end_reason() + "; the session keeps what was read before it";
}

}  // namespace doorbench::sensors
