#include "sensors/comedi_backend.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "core/number_format.h"
#include "sensors/rig_channel.h"

namespace doorbench::sensors {

namespace {

std::string number(double value) {
  return format_significant(value, 10);
}

std::string range_text(double min, double max) {
  return "[" + number(min) + ", " + number(max) + "] V";
}

std::string trig_name(unsigned src) {
  std::string names;
  const std::pair<unsigned, const char*> known[] = {
      {TRIG_NONE, "TRIG_NONE"}, {TRIG_NOW, "TRIG_NOW"},     {TRIG_FOLLOW, "TRIG_FOLLOW"},
      {TRIG_TIME, "TRIG_TIME"}, {TRIG_TIMER, "TRIG_TIMER"}, {TRIG_COUNT, "TRIG_COUNT"},
      {TRIG_EXT, "TRIG_EXT"},   {TRIG_INT, "TRIG_INT"},     {TRIG_OTHER, "TRIG_OTHER"}};
  for (const auto& [bit, name] : known) {
    if (src & bit) names.append(names.empty() ? "" : "|").append(std::string(name));
  }
  return names.empty() ? "none" : names;
}

// comedi_command_test's documented return values.
std::string test_result_meaning(int result) {
  switch (result) {
    case 0:
      return "valid";
    case 1:
      return "a trigger source is not supported (its bits were cleared)";
    case 2:
      return "the combination of trigger sources is not supported";
    case 3:
      return "an argument was out of range and was changed";
    case 4:
      return "an argument was adjusted (e.g. a timer rounded to the board's clock)";
    case 5:
      return "the channel list is not valid";
    default:
      return "error";
  }
}

unsigned aref_of(const std::string& name) {
  if (name == "common") return AREF_COMMON;
  if (name == "diff") return AREF_DIFF;
  if (name == "other") return AREF_OTHER;
  return AREF_GROUND;
}

int aref_flag(unsigned aref) {
  switch (aref) {
    case AREF_COMMON:
      return SDF_COMMON;
    case AREF_DIFF:
      return SDF_DIFF;
    case AREF_OTHER:
      return SDF_OTHER;
    default:
      return SDF_GROUND;
  }
}

bool parse_unsigned(std::string_view text, unsigned& value) {
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && !text.empty();
}

// "0/3" → subdevice 0, channel 3.
bool parse_address(const std::string& address, unsigned& subdevice, unsigned& channel) {
  const auto slash = address.find('/');
  if (slash == std::string::npos) return false;
  return parse_unsigned(std::string_view(address).substr(0, slash), subdevice) &&
         parse_unsigned(std::string_view(address).substr(slash + 1), channel);
}

}  // namespace

std::string ComediOptions::validate() const {
  if (!(duration_s >= 0) || !std::isfinite(duration_s)) {
    return "comedi duration_s must be >= 0 (got " + number(duration_s) + ")";
  }
  if (read_buffer_bytes < 64) {
    return "comedi read_buffer_bytes must be >= 64 (got " + std::to_string(read_buffer_bytes) + ")";
  }
  return "";
}

std::string ComediSetup::brief_report() const {
  std::ostringstream out;
  out << device << ": " << driver << " " << board << ", subdevice " << subdevice << ", "
      << channels.size() << " channels, scan rate " << number(achieved_scan_rate_hz)
      << " Hz (requested " << number(requested_scan_rate_hz) << " Hz), convert "
      << (achieved_convert_interval_s > 0 ? number(achieved_convert_interval_s * 1e9) + " ns"
                                          : std::string("TRIG_NOW"))
      << ", start " << start << ", stop "
      << (stop_scans ? std::to_string(stop_scans) + " scans" : std::string("by hand")) << "\n";
  for (const std::string& line : adjustments) out << "  adjusted: " << line << "\n";
  for (const std::string& line : warnings) out << "  warning: " << line << "\n";
  for (const Channel& c : channels) {
    out << "  " << c.name << ": channel " << c.channel << ", range " << c.range << " "
        << range_text(c.range_min_V, c.range_max_V) << ", aref " << comedi_aref_name(c.aref) << ", "
        << c.conversion;
    if (c.conversion == "softcal") out << " (line within " << number(c.line_deviation_V) << " V)";
    out << "\n";
  }
  return out.str();
}

namespace {

// The channels' numbers on their subdevice: all on one, so that one command samples them.
std::vector<unsigned> channel_numbers(const RigDefinition& rig, unsigned& subdevice) {
  std::vector<unsigned> numbers;
  for (std::size_t i = 0; i < rig.channels.size(); ++i) {
    const RigChannel& rc = rig.channels[i];
    if (rc.backend != "comedi") {
      throw std::invalid_argument(rig.source + ": channel " + rc.name + " uses backend " +
                                  rc.backend + "; the comedi backend records comedi channels only");
    }
    unsigned on = 0, channel = 0;
    if (!parse_address(rc.address, on, channel)) {
      throw std::invalid_argument(rig.source + ": channel " + rc.name + ": address \"" +
                                  rc.address +
                                  "\" is not a comedi address SUBDEVICE/CHANNEL, e.g. \"0/3\"");
    }
    if (i == 0) subdevice = on;
    if (on != subdevice) {
      throw std::invalid_argument(rig.source + ": channel " + rc.name + " is on subdevice " +
                                  std::to_string(on) + " but channel " + rig.channels[0].name +
                                  " on subdevice " + std::to_string(subdevice) +
                                  "; one command samples one subdevice");
    }
    numbers.push_back(channel);
  }
  return numbers;
}

// A count range's ends clamped into a command argument (1 .. 2^32 − 1).
unsigned command_argument(long long value) {
  return static_cast<unsigned>(std::clamp(value, 1LL, 0xffffffffLL));
}

}  // namespace

ComediBackend::ComediBackend(const RigDefinition& rig, const ComediApi& api,
                             const ComediOptions& options)
    : api_(api), options_(options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  if (rig.channels.empty()) throw std::invalid_argument(rig.source + ": no channels");
  setup_.device = rig.daq_device;
  const std::vector<unsigned> numbers = channel_numbers(rig, setup_.subdevice);
  open_device();
  try {
    const int flags = check_subdevice();
    const int n_channels = api_.get_n_channels(device_, setup_.subdevice);
    load_soft_calibration(flags);
    for (std::size_t i = 0; i < rig.channels.size(); ++i) {
      setup_.channels.push_back(configure_channel(rig.channels[i], numbers[i], flags,
                                                  rig.daq_resolution_bits, n_channels));
    }
    build_command(rig);
  } catch (...) {
    if (calibration_) api_.cleanup_calibration(calibration_);
    api_.close(device_);
    throw;
  }
  describe_session_channels(rig);
}

std::string ComediBackend::where() const {
  return setup_.device + " subdevice " + std::to_string(setup_.subdevice);
}

void ComediBackend::open_device() {
  device_ = api_.open(setup_.device.c_str());
  if (device_ != nullptr) return;
  const int error = api_.errno_value();
  std::string message = setup_.device + ": cannot open the comedi device: " + api_.last_error();
  if (error == ENOENT) {
    message +=
        " (no such device file: is a card installed, its comedi driver loaded and the "
        "device configured? A USB cDAQ-9172 has no comedi driver)";
  }
  throw ComediError(message);
}

int ComediBackend::check_subdevice() {
  const char* driver = api_.get_driver_name(device_);
  const char* board = api_.get_board_name(device_);
  setup_.driver = driver ? driver : "?";
  setup_.board = board ? board : "?";
  const unsigned subdevice = setup_.subdevice;
  const int subdevices = api_.get_n_subdevices(device_);
  if (subdevices < 0 || subdevice >= static_cast<unsigned>(subdevices)) {
    throw ComediError(setup_.device + ": no subdevice " + std::to_string(subdevice) +
                      " (the board has " + std::to_string(std::max(subdevices, 0)) + ")");
  }
  if (api_.get_subdevice_type(device_, subdevice) != COMEDI_SUBD_AI) {
    throw ComediError(where() + " is " +
                      comedi_subdevice_type_name(api_.get_subdevice_type(device_, subdevice)) +
                      ", not analog input");
  }
  const int flags = api_.get_subdevice_flags(device_, subdevice);
  if (flags < 0 || !(flags & SDF_CMD_READ)) {
    throw ComediError(where() + " cannot run input commands (no SDF_CMD_READ)");
  }
  setup_.sample_bytes = (flags & SDF_LSAMPL) ? 4 : 2;
  return flags;
}

void ComediBackend::load_soft_calibration(int flags) {
  if (!(flags & SDF_SOFT_CALIBRATED)) return;
  char* path = api_.get_default_calibration_path(device_);
  if (path == nullptr) {
    setup_.warnings.push_back(
        "the board is soft-calibrated but comedilib names no calibration file; "
        "converting with comedi_to_phys");
    return;
  }
  calibration_ = api_.parse_calibration_file(path);
  if (calibration_ == nullptr) {
    setup_.warnings.push_back(
        "the board is soft-calibrated but its calibration file " + std::string(path) +
        " cannot be read (run comedi_soft_calibrate); converting with comedi_to_phys");
  }
  std::free(path);
}

ComediSetup::Channel ComediBackend::configure_channel(const RigChannel& rc, unsigned number,
                                                      int flags, int resolution_bits,
                                                      int n_channels) {
  ComediSetup::Channel c;
  c.name = rc.name;
  c.channel = number;
  const std::string label = "channel " + rc.name + " (" + rc.address + ")";
  if (n_channels < 0 || c.channel >= static_cast<unsigned>(n_channels)) {
    throw ComediError(where() + ": " + label + ": no channel " + std::to_string(c.channel) +
                      " (the subdevice has " + std::to_string(std::max(n_channels, 0)) + ")");
  }
  const std::uint32_t expected_maxdata = (std::uint32_t{1} << resolution_bits) - 1;
  c.maxdata = api_.get_maxdata(device_, setup_.subdevice, c.channel);
  if (c.maxdata != expected_maxdata) {
    throw ComediError(where() + ": " + label + ": maxdata is " + std::to_string(c.maxdata) +
                      " but the rig says resolution_bits = " + std::to_string(resolution_bits) +
                      " (maxdata " + std::to_string(expected_maxdata) + ")");
  }
  choose_range(rc, label, c);
  c.aref = aref_of(rc.aref);
  if (!(flags & aref_flag(c.aref))) {
    throw ComediError(where() + ": " + label + ": aref " + comedi_aref_name(c.aref) +
                      " is not supported by the subdevice");
  }
  chanlist_.push_back(CR_PACK(c.channel, c.range, c.aref));
  convert_counts_to_volts(label, c);
  return c;
}

// The board's range equal to the rig's range_V.
void ComediBackend::choose_range(const RigChannel& rc, const std::string& label,
                                 ComediSetup::Channel& c) {
  const int n_ranges = api_.get_n_ranges(device_, setup_.subdevice, c.channel);
  std::string available;
  for (int r = 0; r < n_ranges; ++r) {
    const comedi_range* range = api_.get_range(device_, setup_.subdevice, c.channel, r);
    if (range == nullptr || range->unit != UNIT_volt) continue;
    const double tolerance = 1e-9 * std::max(1.0, std::abs(range->max - range->min));
    if (std::abs(range->min - rc.range_min_V) <= tolerance &&
        std::abs(range->max - rc.range_max_V) <= tolerance) {
      c.range = static_cast<unsigned>(r);
      c.range_min_V = range->min;
      c.range_max_V = range->max;
      return;
    }
    available.append(available.empty() ? "" : ", ").append(range_text(range->min, range->max));
  }
  throw ComediError(where() + ": " + label + ": the board has no range " +
                    range_text(rc.range_min_V, rc.range_max_V) + "; its voltage ranges are " +
                    (available.empty() ? "none" : available));
}

// Counts → volts, as the session will store it: a line, from the soft calibration where
// the calibration file has one for the channel's range, else from comedi_to_phys.
void ComediBackend::convert_counts_to_volts(const std::string& label, ComediSetup::Channel& c) {
  comedi_polynomial_t polynomial{};
  if (calibration_ != nullptr &&
      api_.get_softcal_converter(setup_.subdevice, c.channel, c.range, COMEDI_TO_PHYSICAL,
                                 calibration_, &polynomial) == 0) {
    line_through_soft_calibration(label, polynomial, c);
    return;
  }
  if (calibration_ != nullptr) {
    setup_.warnings.push_back(label +
                              ": the calibration file has no soft calibration for "
                              "range " +
                              std::to_string(c.range) + "; using comedi_to_phys");
  }
  c.conversion = "comedi_to_phys";
  // comedi_to_phys is linear (min + (max − min) · data / maxdata); it gives NaN at 0
  // and maxdata by default, so the line is taken through two inner points.
  comedi_range* range = api_.get_range(device_, setup_.subdevice, c.channel, c.range);
  const lsampl_t low = 1, high = c.maxdata - 1;
  const double v_low = api_.to_phys(low, range, c.maxdata);
  const double v_high = api_.to_phys(high, range, c.maxdata);
  c.raw_scale_V = (v_high - v_low) / static_cast<double>(high - low);
  c.raw_offset_V = v_low - c.raw_scale_V * low;
  if (!std::isfinite(c.raw_scale_V) || !std::isfinite(c.raw_offset_V)) {
    throw ComediError(where() + ": " + label + ": comedi_to_phys gives no finite values");
  }
}

// The least-squares line through the soft calibration's polynomial over the whole count
// range, and how far the polynomial strays from it.
void ComediBackend::line_through_soft_calibration(const std::string& label,
                                                  const comedi_polynomial_t& polynomial,
                                                  ComediSetup::Channel& c) const {
  c.conversion = "softcal";
  c.polynomial.assign(polynomial.coefficients, polynomial.coefficients + polynomial.order + 1);
  c.polynomial_origin = polynomial.expansion_origin;
  const int points = 1025;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  std::vector<double> xs(points), ys(points);
  for (int k = 0; k < points; ++k) {
    xs[k] = std::round(static_cast<double>(c.maxdata) * k / (points - 1));
    ys[k] = api_.to_physical(static_cast<lsampl_t>(xs[k]), &polynomial);
    sx += xs[k];
    sy += ys[k];
    sxx += xs[k] * xs[k];
    sxy += xs[k] * ys[k];
  }
  c.raw_scale_V = (points * sxy - sx * sy) / (points * sxx - sx * sx);
  c.raw_offset_V = (sy - c.raw_scale_V * sx) / points;
  for (int k = 0; k < points; ++k) {
    c.line_deviation_V =
        std::max(c.line_deviation_V, std::abs(c.raw_offset_V + c.raw_scale_V * xs[k] - ys[k]));
  }
  if (!std::isfinite(c.raw_scale_V) || !std::isfinite(c.raw_offset_V)) {
    throw ComediError(where() + ": " + label + ": the soft calibration gives no finite values");
  }
}

// The command: start, scan and convert timers, stop count; settled with the driver.
void ComediBackend::build_command(const RigDefinition& rig) {
  setup_.requested_scan_rate_hz = rig.sample_rate_hz;
  setup_.requested_convert_interval_s = rig.convert_interval_s;
  command_.subdev = setup_.subdevice;
  command_.flags = 0;
  choose_start(rig);
  command_.scan_begin_src = TRIG_TIMER;
  command_.scan_begin_arg = command_argument(std::llround(1e9 / rig.sample_rate_hz));
  if (rig.convert_interval_s > 0) {
    command_.convert_src = TRIG_TIMER;
    command_.convert_arg = command_argument(std::llround(rig.convert_interval_s * 1e9));
  } else {
    command_.convert_src = TRIG_NOW;
    command_.convert_arg = 0;
  }
  command_.scan_end_src = TRIG_COUNT;
  command_.scan_end_arg = static_cast<unsigned>(chanlist_.size());
  if (options_.duration_s > 0) {
    command_.stop_src = TRIG_COUNT;
    command_.stop_arg = command_argument(std::llround(options_.duration_s * rig.sample_rate_hz));
  } else {
    command_.stop_src = TRIG_NONE;
    command_.stop_arg = 0;
  }
  command_.chanlist = chanlist_.data();
  command_.chanlist_len = static_cast<unsigned>(chanlist_.size());
  settle_command(1);
  setup_.achieved_scan_rate_hz = 1e9 / command_.scan_begin_arg;
  if (options_.duration_s > 0) settle_stop_count();
  setup_.achieved_convert_interval_s =
      command_.convert_src == TRIG_TIMER ? command_.convert_arg * 1e-9 : 0.0;
}

// Software start (TRIG_INT 0), or the rig's daq.start_trigger: an external line.
void ComediBackend::choose_start(const RigDefinition& rig) {
  command_.start_src = TRIG_INT;
  command_.start_arg = 0;
  setup_.start = "software (TRIG_INT 0)";
  if (rig.daq_start_trigger.empty()) return;
  const auto trigger =
      std::find_if(rig.triggers.begin(), rig.triggers.end(),
                   [&](const RigTrigger& t) { return t.name == rig.daq_start_trigger; });
  if (trigger == rig.triggers.end()) {
    throw std::invalid_argument(rig.source + ": daq.start_trigger \"" + rig.daq_start_trigger +
                                "\" names no trigger");
  }
  if (trigger->kind != "external") {
    setup_.start = "software, trigger " + trigger->name + " (TRIG_INT 0)";
    return;
  }
  unsigned line = 0;
  command_.start_src = TRIG_EXT;
  if (trigger->source.rfind("PFI", 0) == 0 &&
      parse_unsigned(std::string_view(trigger->source).substr(3), line)) {
    // NI boards: channel n of the start argument is PFI n; CR_EDGE: on the rising edge.
    command_.start_arg = line | CR_EDGE;
  } else if (parse_unsigned(trigger->source, line)) {
    command_.start_arg = line;  // a driver-specific TRIG_EXT argument, as it is
  } else {
    throw std::invalid_argument(rig.source + ": trigger " + trigger->name + ": source \"" +
                                trigger->source +
                                "\" is neither PFIn nor a number (the TRIG_EXT argument)");
  }
  setup_.start =
      "external " + trigger->source + " (TRIG_EXT " + std::to_string(command_.start_arg) + ")";
}

// The stop count from the rate the board will really run at.
void ComediBackend::settle_stop_count() {
  const long long wanted =
      std::max(1LL, std::llround(options_.duration_s * setup_.achieved_scan_rate_hz));
  if (wanted <= 0xffffffffLL && command_.stop_arg != wanted) {
    command_.stop_arg = static_cast<unsigned>(wanted);
    settle_command(2);
  }
  if (wanted > 0xffffffffLL || command_.stop_arg < wanted) {
    // The board counts fewer scans than asked (NI boards: 2^24 − 1): acquire
    // continuously; the recorder stops after its duration and stop() cancels.
    setup_.warnings.push_back("the board's stop count holds at most " +
                              std::to_string(command_.stop_arg) + " scans, fewer than the " +
                              std::to_string(wanted) +
                              " asked for: acquiring with stop TRIG_NONE instead");
    command_.stop_src = TRIG_NONE;
    command_.stop_arg = 0;
    settle_command(3);
  }
  setup_.achieved_scan_rate_hz = 1e9 / command_.scan_begin_arg;
  setup_.stop_scans = command_.stop_src == TRIG_COUNT ? command_.stop_arg : 0;
}

// What the session gets: the channels, their calibration records, the read buffers.
void ComediBackend::describe_session_channels(const RigDefinition& rig) {
  for (std::size_t i = 0; i < rig.channels.size(); ++i) {
    const RigChannel& rc = rig.channels[i];
    const ComediSetup::Channel& c = setup_.channels[i];
    const CalibrationRecord record = rig_channel_calibration(rig, rc);
    calibrations_.push_back(record);
    channels_.push_back(counts_channel_info(
        rc, record,
        {.raw_offset_V = c.raw_offset_V,
         .raw_scale_V = c.raw_scale_V,
         .range_min_V = c.range_min_V,
         .range_max_V = c.range_max_V,
         .sample_rate_hz = setup_.achieved_scan_rate_hz,
         .first_sample_time_s = static_cast<double>(i) * setup_.achieved_convert_interval_s}));
  }
  scan_bytes_ = static_cast<std::size_t>(setup_.sample_bytes) * chanlist_.size();
  // At least one scan, and whole samples (a read never splits one).
  staging_.resize(std::max(options_.read_buffer_bytes / scan_bytes_, std::size_t{1}) * scan_bytes_);
  rail_.assign(chanlist_.size(), 0);
  rail_samples_.assign(chanlist_.size(), 0);
}

void ComediBackend::settle_command(int round) {
  const std::string& dev = setup_.device;
  for (int test = 1;; ++test) {
    const comedi_cmd before = command_;
    const std::vector<unsigned> chanlist_before = chanlist_;
    const int result = api_.command_test(device_, &command_);
    std::string line = "round " + std::to_string(round) + ", test " + std::to_string(test) +
                       ": comedi_command_test returned " + std::to_string(result) + " (" +
                       test_result_meaning(result) + ")";
    if (result < 0) {
      setup_.tests.push_back(line);
      throw ComediError(dev + " subdevice " + std::to_string(setup_.subdevice) +
                        ": comedi_command_test failed: " + api_.last_error());
    }
    std::vector<std::string> changes;
    auto compare_src = [&](const char* name, unsigned was, unsigned is) {
      if (was != is)
        changes.push_back(std::string(name) + " " + trig_name(was) + " -> " + trig_name(is));
    };
    auto compare_arg = [&](const char* name, unsigned was, unsigned is, const char* unit) {
      if (was != is) {
        changes.push_back(std::string(name) + " " + std::to_string(was) + " -> " +
                          std::to_string(is) + unit);
      }
    };
    compare_src("start_src", before.start_src, command_.start_src);
    compare_arg("start_arg", before.start_arg, command_.start_arg, "");
    compare_src("scan_begin_src", before.scan_begin_src, command_.scan_begin_src);
    compare_arg("scan_begin_arg", before.scan_begin_arg, command_.scan_begin_arg,
                command_.scan_begin_src == TRIG_TIMER ? " ns" : "");
    compare_src("convert_src", before.convert_src, command_.convert_src);
    compare_arg("convert_arg", before.convert_arg, command_.convert_arg,
                command_.convert_src == TRIG_TIMER ? " ns" : "");
    compare_src("scan_end_src", before.scan_end_src, command_.scan_end_src);
    compare_arg("scan_end_arg", before.scan_end_arg, command_.scan_end_arg, "");
    compare_src("stop_src", before.stop_src, command_.stop_src);
    compare_arg("stop_arg", before.stop_arg, command_.stop_arg, "");
    for (std::size_t i = 0; i < chanlist_.size(); ++i) {
      if (chanlist_[i] != chanlist_before[i]) {
        changes.push_back("chanlist[" + std::to_string(i) + "] " +
                          std::to_string(chanlist_before[i]) + " -> " +
                          std::to_string(chanlist_[i]));
      }
    }
    for (const std::string& change : changes) {
      line += "; " + change;
      setup_.adjustments.push_back(change + " (test " + std::to_string(test) + " returned " +
                                   std::to_string(result) + ")");
    }
    setup_.tests.push_back(line);
    const std::string where = dev + " subdevice " + std::to_string(setup_.subdevice) + " (" +
                              setup_.driver + " " + setup_.board + ")";
    switch (result) {
      case 0:
        return;
      case 1: {
        std::string refused;
        for (const std::string& change : changes)
          refused.append(refused.empty() ? "" : "; ").append(change);
        throw ComediError(where + " refuses the command: " + test_result_meaning(1) + ": " +
                          refused);
      }
      case 2:
        throw ComediError(where + " refuses the command: " + test_result_meaning(2) + " (start " +
                          trig_name(command_.start_src) + ", scan_begin " +
                          trig_name(command_.scan_begin_src) + ", convert " +
                          trig_name(command_.convert_src) + ", stop " +
                          trig_name(command_.stop_src) + ")");
      case 5:
        throw ComediError(where + " refuses the command: " + test_result_meaning(5) +
                          " (channels, ranges and arefs of the rig)");
      case 3:
      case 4:
        if (test == 5) {
          throw ComediError(where +
                            ": comedi_command_test still changed arguments after 5 "
                            "tests: " +
                            line);
        }
        break;
      default:
        throw ComediError(where + ": comedi_command_test returned " + std::to_string(result));
    }
  }
}

ComediBackend::~ComediBackend() {
  if (running_) api_.cancel(device_, setup_.subdevice);
  if (calibration_) api_.cleanup_calibration(calibration_);
  if (device_) api_.close(device_);
}

std::string ComediBackend::description() const {
  return "comedi " + setup_.device + " (" + setup_.driver + " " + setup_.board + "), subdevice " +
         std::to_string(setup_.subdevice) + ", " + std::to_string(setup_.channels.size()) +
         " channels at " + number(setup_.achieved_scan_rate_hz) + " Hz (requested " +
         number(setup_.requested_scan_rate_hz) + " Hz)";
}

void ComediBackend::start() {
  if (running_ || finished_) throw std::logic_error(setup_.device + ": the command already ran");
  comedi_cmd command = command_;
  if (api_.command(device_, &command) < 0) {
    throw ComediError(setup_.device + " subdevice " + std::to_string(setup_.subdevice) +
                      ": comedi_command failed: " + api_.last_error());
  }
  running_ = true;
  end_reason_ = "running";
  if (command_.start_src == TRIG_INT &&
      api_.internal_trigger(device_, setup_.subdevice, command_.start_arg) < 0) {
    const std::string why = api_.last_error();
    api_.cancel(device_, setup_.subdevice);
    running_ = false;
    throw ComediError(setup_.device + " subdevice " + std::to_string(setup_.subdevice) +
                      ": comedi_internal_trigger failed: " + why);
  }
}

void ComediBackend::push_event(ScanBlock& block, double time_s, const std::string& channel,
                               const std::string& detail) {
  // The recorder reserved the events' room; past it, count instead of allocating.
  if (block.events.size() >= block.events.capacity()) {
    ++dropped_events_;
    return;
  }
  block.events.push_back({.time_s = time_s, .kind = "fault", .channel = channel, .detail = detail});
}

void ComediBackend::check_rails(ScanBlock& block, std::size_t first_scan, std::size_t scans) {
  for (std::size_t c = 0; c < chanlist_.size(); ++c) {
    const std::int32_t top = static_cast<std::int32_t>(setup_.channels[c].maxdata);
    const std::int32_t* counts = block.counts[c].data() + first_scan;
    for (std::size_t s = 0; s < scans; ++s) {
      const int rail = counts[s] == 0 ? -1 : counts[s] == top ? 1 : 0;
      if (rail == rail_[c]) {
        if (rail != 0) ++rail_samples_[c];
        continue;
      }
      const double time_s =
          static_cast<double>(scans_read_ + first_scan + s) / setup_.achieved_scan_rate_hz +
          channels_[c].first_sample_time_s;
      if (rail_[c] != 0) {
        push_event(
            block, time_s, channels_[c].name,
            "back in range after " + std::to_string(rail_samples_[c]) + " samples out of range");
      }
      if (rail != 0) {
        push_event(block, time_s, channels_[c].name,
                   std::string("out of range: ") +
                       (rail > 0 ? "at maxdata " + std::to_string(top) + " counts (above " +
                                       number(setup_.channels[c].range_max_V) + " V)"
                                 : "at 0 counts (below " + number(setup_.channels[c].range_min_V) +
                                       " V)"));
      }
      rail_[c] = rail;
      rail_samples_[c] = rail != 0 ? 1 : 0;
    }
  }
}

std::size_t ComediBackend::read(ScanBlock& block) {
  if (!running_ && !finished_) throw std::logic_error(setup_.device + ": read before start()");
  block.scan_count = 0;
  if (!announced_start_) {
    announced_start_ = true;
    block.events.push_back(
        {.time_s = 0.0, .kind = "trigger", .channel = "", .detail = "start: " + setup_.start});
  }
  if (dropped_events_ > 0 && block.events.size() < block.events.capacity()) {
    push_event(block, static_cast<double>(scans_read_) / setup_.achieved_scan_rate_hz, "",
               std::to_string(dropped_events_) + " earlier events were dropped (too many)");
    dropped_events_ = 0;
  }
  const std::size_t channels = chanlist_.size();
  const std::size_t capacity = block.capacity();
  while (!finished_) {
    const std::size_t complete = staged_bytes_ / scan_bytes_;
    if (complete > 0) {
      const std::size_t scans = std::min(complete, capacity);
      const unsigned char* p = staging_.data();
      for (std::size_t s = 0; s < scans; ++s) {
        for (std::size_t c = 0; c < channels; ++c) {
          if (setup_.sample_bytes == 2) {
            sampl_t sample;
            std::memcpy(&sample, p, sizeof sample);
            block.counts[c][s] = sample;
          } else {
            lsampl_t sample;
            std::memcpy(&sample, p, sizeof sample);
            block.counts[c][s] = static_cast<std::int32_t>(sample);
          }
          p += setup_.sample_bytes;
        }
      }
      const std::size_t used = scans * scan_bytes_;
      std::memmove(staging_.data(), staging_.data() + used, staged_bytes_ - used);
      staged_bytes_ -= used;
      check_rails(block, 0, scans);
      scans_read_ += scans;
      block.scan_count = scans;
      return scans;
    }
    const ssize_t got =
        api_.read(device_, staging_.data() + staged_bytes_, staging_.size() - staged_bytes_);
    if (got > 0) {
      staged_bytes_ += static_cast<std::size_t>(got);
      continue;
    }
    const double time_s = static_cast<double>(scans_read_) / setup_.achieved_scan_rate_hz;
    if (got == 0) {
      // EOF: the command ended (its stop count) and the buffer is drained.
      finished_ = true;
      running_ = false;
      end_reason_ = "end of acquisition after " + std::to_string(scans_read_) + " scans";
      if (setup_.stop_scans != 0 && scans_read_ != setup_.stop_scans) {
        push_event(block, time_s, "",
                   "comedi acquisition ended after " + std::to_string(scans_read_) +
                       " scans, before its stop count " + std::to_string(setup_.stop_scans));
      }
      break;
    }
    const int error = errno;
    if (error == EINTR) {
      if (!stop_requested_.load()) continue;
      end_reason_ = "stopped on request after " + std::to_string(scans_read_) + " scans";
      finished_ = true;
      break;
    }
    finished_ = true;
    running_ = error != EPIPE;  // after an overrun the command is over; else cancel it
    if (error == EPIPE) {
      overran_ = true;
      end_reason_ = "buffer overrun after " + std::to_string(scans_read_) + " scans (" +
                    number(time_s) + " s)";
      push_event(block, time_s, "",
                 "comedi buffer overrun on " + setup_.device + " subdevice " +
                     std::to_string(setup_.subdevice) + " after " + std::to_string(scans_read_) +
                     " scans: the board filled the kernel buffer before doorbench read it; the "
                     "acquisition stopped and the recording ends here");
    } else {
      end_reason_ = std::string("read failed: ") + std::strerror(error);
      push_event(block, time_s, "",
                 "reading " + setup_.device + " failed after " + std::to_string(scans_read_) +
                     " scans: " + std::strerror(error) + "; the recording ends here");
    }
  }
  return 0;
}

void ComediBackend::stop() {
  if (running_) {
    api_.cancel(device_, setup_.subdevice);
    running_ = false;
    if (!finished_) end_reason_ = "stopped after " + std::to_string(scans_read_) + " scans";
  }
}

void ComediBackend::write_extras(SessionWriter& writer, double /*session_origin_s*/) {
  const std::string group = "acquisition/comedi";
  auto joined = [](const std::vector<std::string>& lines) {
    std::string text;
    for (const std::string& line : lines) text.append(line).append("\n");
    return text;
  };
  writer.write_group_attribute(group, "about",
                               "the comedi command that acquired this session: what was asked, "
                               "what comedi_command_test settled on, and how counts convert");
  writer.write_group_attribute(group, "device", setup_.device);
  writer.write_group_attribute(group, "driver", setup_.driver);
  writer.write_group_attribute(group, "board", setup_.board);
  writer.write_group_attribute(group, "subdevice", std::to_string(setup_.subdevice));
  writer.write_group_attribute(group, "requested_scan_rate_hz",
                               number(setup_.requested_scan_rate_hz));
  writer.write_group_attribute(group, "achieved_scan_rate_hz",
                               number(setup_.achieved_scan_rate_hz));
  writer.write_group_attribute(group, "requested_convert_interval_s",
                               number(setup_.requested_convert_interval_s));
  writer.write_group_attribute(group, "achieved_convert_interval_s",
                               number(setup_.achieved_convert_interval_s));
  writer.write_group_attribute(group, "start", setup_.start);
  writer.write_group_attribute(group, "stop_scans", std::to_string(setup_.stop_scans));
  writer.write_group_attribute(group, "command_tests", joined(setup_.tests));
  writer.write_group_attribute(group, "adjustments", joined(setup_.adjustments));
  writer.write_group_attribute(group, "warnings", joined(setup_.warnings));
  writer.write_group_attribute(group, "scans_read", std::to_string(scans_read_));
  writer.write_group_attribute(group, "end", end_reason_);
  for (const ComediSetup::Channel& c : setup_.channels) {
    std::string text =
        "channel " + std::to_string(c.channel) + ", range " + std::to_string(c.range) + " " +
        range_text(c.range_min_V, c.range_max_V) + ", aref " + comedi_aref_name(c.aref) +
        ", maxdata " + std::to_string(c.maxdata) + ", conversion " + c.conversion +
        "; session: V = " + number(c.raw_offset_V) + " + " + number(c.raw_scale_V) + " * counts";
    if (c.conversion == "softcal") {
      text +=
          "; soft calibration V = sum c[i] * (counts - " + number(c.polynomial_origin) + ")^i, c =";
      for (double coefficient : c.polynomial) text.append(" ").append(number(coefficient));
      text += "; the line is within " + number(c.line_deviation_V) + " V of it";
    }
    writer.write_group_attribute(group, "channel_" + c.name, text);
  }
}

}  // namespace doorbench::sensors
