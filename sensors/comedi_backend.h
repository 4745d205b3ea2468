#pragma once
// Hardware-timed, synchronized multi-channel analog input from a comedi DAQ card (NI
// M-series boards with the ni_pcimio driver, among others) through a comedi command:
// scan_begin TRIG_TIMER (the rig's sample rate), convert TRIG_TIMER (the rig's
// convert_interval_s) or TRIG_NOW (convert_interval_s = 0, simultaneous-sampling
// boards), scan_end TRIG_COUNT (the channels), stop TRIG_COUNT (a set duration) or
// TRIG_NONE (until stop()); started by software (TRIG_INT) or an external digital line
// (TRIG_EXT, e.g. PFI0) as the rig's [daq] start_trigger says.
//
// The command is settled by comedi_command_test in the constructor (up to five tests, its
// documented return codes 0-5); every argument the driver changed is reported in
// setup().adjustments, and the scan rate the board will really run at (never the
// requested one) is what channels() and scan_rate_hz() give the session.
//
// Conversion: the session stores raw counts with a linear mapping to volts
// (ChannelInfo::raw_offset + raw_scale · counts), then the sensor's calibration record.
// The backend derives that mapping from comedilib: from comedi_to_phys for hardware-
// calibrated boards, from the board's soft calibration (comedi_get_softcal_converter)
// where it has one. A soft calibration polynomial of order > 1 cannot be stored as a
// line: the session gets its least-squares line over the whole count range, the largest
// deviation is reported, and the full polynomial is kept in the session (group
// acquisition/comedi). docs/comedi.md explains it.
//
// Samples at 0 or maxdata (the input is out of range) become "fault" events when a
// channel reaches the rail and when it leaves it. A buffer overrun (read fails with EPIPE
// once the buffer is drained) becomes a "fault" event at the time of the last scan
// received and ends the recording; the end of the acquisition (EOF at the stop count)
// ends it too. read() allocates nothing except for those events.
//
// Every comedilib call goes through a ComediApi (comedi_api.h), so the backend runs on
// Debian's libcomedi or on the device emulator in tests/comedi_emulator. One thread.
#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/record/backend.h"
#include "acquisition/rig/rig_file.h"
#include "sensors/comedi_api.h"

namespace doorbench::sensors {

class ComediError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;  // messages name the device (and channel)
};

struct ComediOptions {
  // > 0: stop TRIG_COUNT after this long (converted to scans at the achieved rate); 0:
  // stop TRIG_NONE, acquire until stop().
  double duration_s = 0.0;
  // doorbench's own read buffer; each read(2) asks for at most this much.
  std::size_t read_buffer_bytes = 1 << 16;
  std::string validate() const;  // empty when usable
};

// What the command test settled on, and how the channels convert.
struct ComediSetup {
  std::string device, driver, board;
  unsigned subdevice = 0;
  int sample_bytes = 2;  // 2 (sampl_t) or 4 (lsampl_t, SDF_LSAMPL)
  double requested_scan_rate_hz = 0, achieved_scan_rate_hz = 0;
  double requested_convert_interval_s = 0, achieved_convert_interval_s = 0;  // 0: TRIG_NOW
  std::size_t stop_scans = 0;                                                // 0: TRIG_NONE
  std::string start;               // "software (TRIG_INT 0)" or "external PFI0 (TRIG_EXT ...)"
  std::vector<std::string> tests;  // one line per comedi_command_test call
  std::vector<std::string> adjustments;  // every argument the driver changed
  std::vector<std::string> warnings;     // e.g. soft calibration file missing
  struct Channel {
    std::string name;
    unsigned channel = 0, range = 0, aref = 0;
    double range_min_V = 0, range_max_V = 0;
    std::uint32_t maxdata = 0;
    std::string conversion;          // "comedi_to_phys" or "softcal"
    std::vector<double> polynomial;  // softcal: to_phys coefficients about the origin
    double polynomial_origin = 0;
    double raw_offset_V = 0, raw_scale_V = 0;  // what the session stores
    double line_deviation_V = 0;               // largest |polynomial − line| over the count range
  };
  std::vector<Channel> channels;
  std::string brief_report() const;  // a few lines for the command line
};

class ComediBackend final : public AcquisitionBackend {
 public:
  // Opens rig.daq_device and settles the command. Every channel must use the comedi
  // backend, with address "SUBDEVICE/CHANNEL" (all on one analog-input subdevice).
  // `api` must outlive the backend. Throws ComediError (device, channel, problem) or
  // std::invalid_argument (rig, options).
  ComediBackend(const RigDefinition& rig, const ComediApi& api, const ComediOptions& options = {});
  ~ComediBackend() override;
  ComediBackend(const ComediBackend&) = delete;
  ComediBackend& operator=(const ComediBackend&) = delete;

  std::string description() const override;
  std::vector<ChannelInfo> channels() const override { return channels_; }
  std::vector<CalibrationRecord> calibrations() const override { return calibrations_; }
  double scan_rate_hz() const override { return setup_.achieved_scan_rate_hz; }
  void start() override;  // comedi_command, then the internal trigger for a software start
  std::size_t read(ScanBlock& block) override;
  void stop() override;  // comedi_cancel
  void write_extras(SessionWriter& writer, double session_origin_s) override;

  const ComediSetup& setup() const { return setup_; }
  std::size_t scans_read() const { return scans_read_; }
  bool overran() const { return overran_; }
  const std::string& end_reason() const { return end_reason_; }
  // From a signal handler or another thread: an interrupted read (EINTR) ends the
  // recording instead of waiting on.
  void request_stop() { stop_requested_.store(true); }

 private:
  // The set-up's stages, in the constructor's order.
  void open_device();
  int check_subdevice();  // the subdevice's flags
  void load_soft_calibration(int flags);
  ComediSetup::Channel configure_channel(const RigChannel& rc, unsigned number, int flags,
                                         int resolution_bits, int n_channels);
  void choose_range(const RigChannel& rc, const std::string& label, ComediSetup::Channel& c);
  void convert_counts_to_volts(const std::string& label, ComediSetup::Channel& c);
  void line_through_soft_calibration(const std::string& label,
                                     const comedi_polynomial_t& polynomial,
                                     ComediSetup::Channel& c) const;
  void build_command(const RigDefinition& rig);
  void choose_start(const RigDefinition& rig);
  void settle_stop_count();
  void describe_session_channels(const RigDefinition& rig);
  std::string where() const;  // "DEVICE subdevice N", for messages
  void settle_command(int round);
  void push_event(ScanBlock& block, double time_s, const std::string& channel,
                  const std::string& detail);
  void check_rails(ScanBlock& block, std::size_t first_scan, std::size_t scans);

  const ComediApi& api_;
  ComediOptions options_;
  comedi_t* device_ = nullptr;
  comedi_calibration_t* calibration_ = nullptr;
  ComediSetup setup_;
  std::vector<unsigned> chanlist_;
  comedi_cmd command_{};
  std::vector<ChannelInfo> channels_;
  std::vector<CalibrationRecord> calibrations_;

  std::vector<unsigned char> staging_;
  std::size_t staged_bytes_ = 0;
  std::size_t scan_bytes_ = 0;
  std::size_t scans_read_ = 0;
  bool running_ = false, finished_ = false, overran_ = false, announced_start_ = false;
  std::vector<int> rail_;  // per channel: 0 in range, −1 at 0, +1 at maxdata
  std::vector<std::size_t> rail_samples_;
  std::size_t dropped_events_ = 0;
  std::string end_reason_ = "not started";
  std::atomic<bool> stop_requested_{false};
};

}  // namespace doorbench::sensors
