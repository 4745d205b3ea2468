// A comedi device emulator: the comedilib functions doorbench's comedi backend and
// `doorbench devices` use, with comedilib's documented behaviour, on no hardware. Built
// as libdoorbench_comedi_emulator.so; doorbench loads it in place of libcomedi when
// $DOORBENCH_COMEDI_LIBRARY names it (sensors/comedi_api.h). docs/comedi.md lists what it
// reproduces and what it does not.
//
// An emulated device is a text file (the path given to comedi_open) of `key = value`
// lines describing the board; docs/comedi.md lists the keys. Samples are made on
// demand from the time elapsed since the start trigger (CLOCK_MONOTONIC), so the emulated
// card runs in real time: reads block until the board would have transferred the data,
// the kernel buffer overruns when the reader falls behind by more than its size (read
// then drains what is left and fails with EPIPE), and read returns 0 (EOF) after the
// stop count.
#include <comedilib.h>
#include <errno.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

struct comedi_t_struct {
  // The board.
  std::string path, driver = "ni_pcimio", board = "pci-6221";
  unsigned ai_channels = 16, ao_channels = 2, dio_channels = 24;
  lsampl_t maxdata = 65535;
  bool lsampl = false, simultaneous = false;
  std::vector<comedi_range> ranges;
  int aref_flags = SDF_GROUND | SDF_COMMON | SDF_DIFF | SDF_OTHER;
  unsigned base_clock_ns = 50, min_convert_ns = 4000;
  unsigned buffer_bytes = 65536, transfer_bytes = 4096;
  unsigned external_line = 0;
  double external_delay_s = 0.1;  // < 0: the line never fires
  std::string calibration_file;
  struct Signal {
    std::string kind = "sine";  // sine | monotonic_sine | counter | constant
    double amplitude_V = 1, frequency_hz = 0, offset_V = 0;  // frequency 0: channel + 1 Hz
  };
  std::vector<Signal> signals;
  comedi_range ao_range{-10, 10, UNIT_volt}, dio_range{0, 1, UNIT_none};

  // The running command.
  bool busy = false, triggered = false, overrun = false;
  comedi_cmd cmd{};
  std::vector<unsigned> chanlist;
  comedi_calibration_t* calibration = nullptr;  // for generating counts
  std::int64_t command_ns = 0, t0_ns = 0;
  std::uint64_t consumed_bytes = 0, visible_bytes = 0;
};

namespace {

thread_local int g_errno = 0;
thread_local std::string g_message;
constexpr int kDeviceFileError = 0x1000;  // comedi_strerror gives g_message

int fail(int error) {
  g_errno = error;
  errno = error;
  return -1;
}

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r") - first + 1);
}

bool valid_subdevice(comedi_t* it, unsigned subdevice) {
  if (it == nullptr || subdevice > 2) {
    fail(EINVAL);
    return false;
  }
  return true;
}

unsigned sample_bytes(const comedi_t* it) {
  return it->lsampl ? sizeof(lsampl_t) : sizeof(sampl_t);
}

unsigned round_ns(unsigned ns, unsigned base, unsigned flags) {
  const std::uint64_t below = ns / base * base;
  std::uint64_t value = below;
  switch (flags & CMDF_ROUND_MASK) {
    case CMDF_ROUND_DOWN:
      value = below;
      break;
    case CMDF_ROUND_UP:
      value = below == ns ? ns : below + base;
      break;
    default:
      value = (ns - below) * 2 >= base ? below + base : below;
      break;
  }
  if (value == 0) value = base;
  return static_cast<unsigned>(std::min<std::uint64_t>(value, 0xffffffffu / base * base));
}

const comedi_polynomial_t* find_polynomial(const comedi_calibration_t* calibration,
                                           unsigned subdevice, unsigned channel, unsigned range,
                                           bool to_physical) {
  if (calibration == nullptr) return nullptr;
  for (unsigned i = 0; i < calibration->num_settings; ++i) {
    const comedi_calibration_setting_t& s = calibration->settings[i];
    if (s.subdevice != subdevice) continue;
    // An empty channel or range list matches every channel or range.
    bool channel_ok = s.num_channels == 0, range_ok = s.num_ranges == 0;
    for (unsigned k = 0; k < s.num_channels; ++k) channel_ok |= s.channels[k] == channel;
    for (unsigned k = 0; k < s.num_ranges; ++k) range_ok |= s.ranges[k] == range;
    if (!channel_ok || !range_ok) continue;
    const comedi_polynomial_t* p =
        to_physical ? s.soft_calibration.to_phys : s.soft_calibration.from_phys;
    if (p != nullptr) return p;
  }
  return nullptr;
}

double evaluate(const comedi_polynomial_t& p, double x) {
  double value = 0, power = 1;
  for (unsigned i = 0; i <= p.order && i < COMEDI_MAX_NUM_POLYNOMIAL_COEFFICIENTS; ++i) {
    value += p.coefficients[i] * power;
    power *= x - p.expansion_origin;
  }
  return value;
}

// The board's raw count for `volts` on chanlist entry k of scan `scan`.
lsampl_t sample_counts(const comedi_t* it, std::uint64_t scan, unsigned k) {
  const unsigned entry = it->chanlist[k];
  const unsigned channel = CR_CHAN(entry), range_index = CR_RANGE(entry);
  const comedi_t::Signal& signal =
      channel < it->signals.size() ? it->signals[channel] : comedi_t::Signal{};
  if (signal.kind == "counter") {
    // Never 0 or maxdata (those mean out of range): 1 … maxdata − 1, then again.
    return static_cast<lsampl_t>(1 + (scan + 7 * channel) % (it->maxdata - 1));
  }
  double volts = signal.offset_V;
  if (signal.kind == "monotonic_sine") {
    // The phase runs on absolute CLOCK_MONOTONIC time: scan k's conversion k·period (+ the
    // converter's skew) after the acquisition began (t0, the trigger), so that a test can
    // compare it with another source of the same signal of the same clock.
    const std::int64_t t_ns =
        it->t0_ns + static_cast<std::int64_t>(scan * it->cmd.scan_begin_arg) +
        (it->cmd.convert_src == TRIG_TIMER ? std::int64_t{k} * it->cmd.convert_arg : 0);
    volts += signal.amplitude_V * std::sin(2 * std::numbers::pi * signal.frequency_hz *
                                           (static_cast<double>(t_ns) * 1e-9));
  } else if (signal.kind == "sine") {
    const double period_s = it->cmd.scan_begin_arg * 1e-9;
    const double skew_s = it->cmd.convert_src == TRIG_TIMER ? k * it->cmd.convert_arg * 1e-9 : 0;
    const double t = static_cast<double>(scan) * period_s + skew_s;
    volts += signal.amplitude_V * std::sin(2 * std::numbers::pi * signal.frequency_hz * t);
  }
  const comedi_range& range = it->ranges[range_index];
  double x = (volts - range.min) / (range.max - range.min) * it->maxdata;
  // A soft-calibrated board's raw counts are what its polynomial maps to the true volts.
  if (const comedi_polynomial_t* p =
          find_polynomial(it->calibration, 0, channel, range_index, true)) {
    for (int iteration = 0; iteration < 8; ++iteration) {
      double slope = 0, power = 1;
      for (unsigned i = 1; i <= p->order; ++i) {
        slope += i * p->coefficients[i] * power;
        power *= x - p->expansion_origin;
      }
      if (slope == 0) break;
      x -= (evaluate(*p, x) - volts) / slope;
    }
  }
  if (!(x > 0)) return 0;
  if (x >= it->maxdata) return it->maxdata;
  return static_cast<lsampl_t>(std::lround(x));
}

// How many bytes the board has put in the buffer by `now`; detects an overrun.
void update(comedi_t* it, std::int64_t now) {
  if (!it->triggered) {
    if (it->cmd.start_src == TRIG_EXT && it->external_delay_s >= 0 &&
        CR_CHAN(it->cmd.start_arg) == it->external_line) {
      const auto fires = it->command_ns + static_cast<std::int64_t>(it->external_delay_s * 1e9);
      if (now >= fires) {
        it->triggered = true;
        it->t0_ns = fires;
      }
    }
    if (!it->triggered) return;
  }
  if (it->overrun) return;  // the acquisition stopped; what is in the buffer stays
  const std::uint64_t scan_bytes = sample_bytes(it) * it->chanlist.size();
  // Scan k is complete one period after it began.
  std::uint64_t scans = static_cast<std::uint64_t>(std::max<std::int64_t>(now - it->t0_ns, 0)) /
                        it->cmd.scan_begin_arg;
  bool ended = false;
  if (it->cmd.stop_src == TRIG_COUNT && scans >= it->cmd.stop_arg) {
    scans = it->cmd.stop_arg;
    ended = true;
  }
  const std::uint64_t produced = scans * scan_bytes;
  // Data reach the buffer in transfers (DMA blocks); the last one may be short.
  const std::uint64_t visible =
      ended ? produced : produced / it->transfer_bytes * it->transfer_bytes;
  if (visible - it->consumed_bytes > it->buffer_bytes) {
    it->overrun = true;
    it->visible_bytes = it->consumed_bytes + it->buffer_bytes / scan_bytes * scan_bytes;
    return;
  }
  it->visible_bytes = std::max(it->visible_bytes, visible);
}

bool stop_count_reached(const comedi_t* it) {
  const std::uint64_t scan_bytes = sample_bytes(it) * it->chanlist.size();
  return it->cmd.stop_src == TRIG_COUNT &&
         it->consumed_bytes >= static_cast<std::uint64_t>(it->cmd.stop_arg) * scan_bytes;
}

// When the next transfer will be in the buffer.
std::int64_t next_data_ns(const comedi_t* it, std::int64_t now) {
  if (!it->triggered) {
    if (it->cmd.start_src == TRIG_EXT && it->external_delay_s >= 0 &&
        CR_CHAN(it->cmd.start_arg) == it->external_line) {
      return it->command_ns + static_cast<std::int64_t>(it->external_delay_s * 1e9);
    }
    return now + 10000000;  // nothing will come: look again in 10 ms
  }
  const std::uint64_t scan_bytes = sample_bytes(it) * it->chanlist.size();
  const std::uint64_t want = it->visible_bytes + it->transfer_bytes;
  std::uint64_t scans = (want + scan_bytes - 1) / scan_bytes;
  if (it->cmd.stop_src == TRIG_COUNT) scans = std::min<std::uint64_t>(scans, it->cmd.stop_arg);
  return it->t0_ns + static_cast<std::int64_t>(scans * it->cmd.scan_begin_arg);
}

bool parse_device(comedi_t* it, std::istream& in) {
  std::string line;
  int number = 0;
  std::vector<comedi_range> ranges;
  while (std::getline(in, line)) {
    ++number;
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const auto equals = line.find('=');
    auto bad = [&](const std::string& why) {
      g_message = it->path + ":" + std::to_string(number) + ": " + why;
      return false;
    };
    if (equals == std::string::npos) return bad("expected key = value");
    const std::string key = trim(line.substr(0, equals));
    const std::string value = trim(line.substr(equals + 1));
    std::istringstream v(value);
    if (key == "driver") {
      it->driver = value;
    } else if (key == "board") {
      it->board = value;
    } else if (key == "ai_channels") {
      v >> it->ai_channels;
    } else if (key == "ao_channels") {
      v >> it->ao_channels;
    } else if (key == "dio_channels") {
      v >> it->dio_channels;
    } else if (key == "maxdata") {
      v >> it->maxdata;
    } else if (key == "lsampl") {
      int flag = 0;
      v >> flag;
      it->lsampl = flag != 0;
    } else if (key == "simultaneous") {
      int flag = 0;
      v >> flag;
      it->simultaneous = flag != 0;
    } else if (key == "ranges") {  // "-10 10, -5 5, ..."
      std::string item;
      while (std::getline(v, item, ',')) {
        std::istringstream r(item);
        comedi_range range{0, 0, UNIT_volt};
        if (!(r >> range.min >> range.max)) return bad("ranges: expected MIN MAX, ...");
        ranges.push_back(range);
      }
    } else if (key == "arefs") {
      it->aref_flags = 0;
      std::string name;
      while (v >> name) {
        if (name == "ground")
          it->aref_flags |= SDF_GROUND;
        else if (name == "common")
          it->aref_flags |= SDF_COMMON;
        else if (name == "diff")
          it->aref_flags |= SDF_DIFF;
        else if (name == "other")
          it->aref_flags |= SDF_OTHER;
        else
          return bad("arefs: unknown " + name);
      }
    } else if (key == "base_clock_ns") {
      v >> it->base_clock_ns;
    } else if (key == "min_convert_ns") {
      v >> it->min_convert_ns;
    } else if (key == "buffer_bytes") {
      v >> it->buffer_bytes;
    } else if (key == "transfer_bytes") {
      v >> it->transfer_bytes;
    } else if (key == "external_trigger_line") {
      v >> it->external_line;
    } else if (key == "external_trigger_delay_s") {
      v >> it->external_delay_s;
    } else if (key == "calibration_file") {
      it->calibration_file = value;
    } else if (key.rfind("signal.", 0) == 0) {
      const unsigned channel = static_cast<unsigned>(std::atoi(key.c_str() + 7));
      comedi_t::Signal signal;
      v >> signal.kind;
      if (signal.kind == "sine" || signal.kind == "monotonic_sine") {
        v >> signal.amplitude_V >> signal.frequency_hz >> signal.offset_V;
      } else if (signal.kind == "constant") {
        v >> signal.offset_V;
      } else if (signal.kind != "counter") {
        return bad(
            "signal: sine AMPLITUDE_V FREQUENCY_HZ OFFSET_V | monotonic_sine AMPLITUDE_V "
            "FREQUENCY_HZ OFFSET_V | constant V | counter");
      }
      if (v.fail()) return bad("signal: missing numbers");
      if (it->signals.size() <= channel) it->signals.resize(channel + 1);
      it->signals[channel] = signal;
    } else {
      return bad("unknown key " + key);
    }
    if (v.fail() && key != "ranges" && key != "arefs") return bad(key + ": bad value " + value);
  }
  if (!ranges.empty()) it->ranges = ranges;
  if (it->ranges.empty()) {  // the PCI-6221's
    it->ranges = {
        {-10, 10, UNIT_volt}, {-5, 5, UNIT_volt}, {-1, 1, UNIT_volt}, {-0.2, 0.2, UNIT_volt}};
  }
  // Unlisted channels: a 1 V sine at (channel + 1) Hz.
  if (it->signals.size() < it->ai_channels) it->signals.resize(it->ai_channels);
  for (unsigned c = 0; c < it->signals.size(); ++c) {
    if (it->signals[c].kind == "sine" && it->signals[c].frequency_hz == 0) {
      it->signals[c].frequency_hz = c + 1.0;
    }
  }
  return true;
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) ssize_t doorbench_comedi_read(comedi_t* it, void* buffer,
                                                                     size_t bytes);

comedi_t* comedi_open(const char* path) {
  std::ifstream in(path ? path : "");
  if (!in) {
    fail(errno ? errno : ENOENT);
    return nullptr;
  }
  auto* it = new comedi_t;
  it->path = path;
  if (!parse_device(it, in)) {
    delete it;
    fail(kDeviceFileError);
    return nullptr;
  }
  return it;
}

int comedi_close(comedi_t* it) {
  if (it == nullptr) return fail(EINVAL);
  if (it->calibration) comedi_cleanup_calibration(it->calibration);
  delete it;
  return 0;
}

int comedi_errno(void) {
  return g_errno;
}

const char* comedi_strerror(int error) {
  if (error == kDeviceFileError) return g_message.c_str();
  return std::strerror(error);
}

int comedi_fileno(comedi_t* it) {
  (void)it;
  return fail(ENOTSUP);  // no file descriptor: doorbench_comedi_read reads
}

const char* comedi_get_driver_name(comedi_t* it) {
  return it ? it->driver.c_str() : nullptr;
}

const char* comedi_get_board_name(comedi_t* it) {
  return it ? it->board.c_str() : nullptr;
}

int comedi_get_n_subdevices(comedi_t* it) {
  return it ? 3 : fail(EINVAL);
}

int comedi_get_subdevice_type(comedi_t* it, unsigned subdevice) {
  if (!valid_subdevice(it, subdevice)) return -1;
  const int types[] = {COMEDI_SUBD_AI, COMEDI_SUBD_AO, COMEDI_SUBD_DIO};
  return types[subdevice];
}

int comedi_find_subdevice_by_type(comedi_t* it, int type, unsigned start) {
  for (unsigned s = start; s < 3; ++s) {
    if (comedi_get_subdevice_type(it, s) == type) return static_cast<int>(s);
  }
  return fail(ENODEV);
}

int comedi_get_subdevice_flags(comedi_t* it, unsigned subdevice) {
  if (!valid_subdevice(it, subdevice)) return -1;
  if (subdevice == 0) {
    int flags = SDF_READABLE | SDF_CMD_READ | SDF_CMD | it->aref_flags;
    if (it->lsampl) flags |= SDF_LSAMPL;
    if (!it->calibration_file.empty()) flags |= SDF_SOFT_CALIBRATED;
    if (it->busy) flags |= SDF_BUSY | SDF_BUSY_OWNER | SDF_RUNNING;
    return flags;
  }
  if (subdevice == 1) return SDF_WRITABLE | SDF_GROUND;
  return SDF_READABLE | SDF_WRITABLE;
}

int comedi_get_n_channels(comedi_t* it, unsigned subdevice) {
  if (!valid_subdevice(it, subdevice)) return -1;
  const unsigned counts[] = {it->ai_channels, it->ao_channels, it->dio_channels};
  return static_cast<int>(counts[subdevice]);
}

lsampl_t comedi_get_maxdata(comedi_t* it, unsigned subdevice, unsigned channel) {
  if (!valid_subdevice(it, subdevice) ||
      channel >= static_cast<unsigned>(comedi_get_n_channels(it, subdevice))) {
    fail(EINVAL);
    return 0;
  }
  return subdevice == 2 ? 1 : it->maxdata;
}

int comedi_get_n_ranges(comedi_t* it, unsigned subdevice, unsigned channel) {
  if (!valid_subdevice(it, subdevice) ||
      channel >= static_cast<unsigned>(comedi_get_n_channels(it, subdevice))) {
    return fail(EINVAL);
  }
  return subdevice == 0 ? static_cast<int>(it->ranges.size()) : 1;
}

comedi_range* comedi_get_range(comedi_t* it, unsigned subdevice, unsigned channel, unsigned range) {
  if (range >= static_cast<unsigned>(std::max(comedi_get_n_ranges(it, subdevice, channel), 0))) {
    fail(EINVAL);
    return nullptr;
  }
  if (subdevice == 0) return &it->ranges[range];
  return subdevice == 1 ? &it->ao_range : &it->dio_range;
}

int comedi_get_buffer_size(comedi_t* it, unsigned subdevice) {
  if (!valid_subdevice(it, subdevice)) return -1;
  return subdevice == 0 ? static_cast<int>(it->buffer_bytes) : 0;
}

// The five stages of a driver's cmdtest, as comedi_command_test documents them.
int comedi_command_test(comedi_t* it, comedi_cmd* cmd) {
  if (it == nullptr || cmd == nullptr) return fail(EINVAL);
  if (cmd->subdev != 0) return fail(EIO);  // only the analog input runs commands
  // Stage 1: each source must be one the board has; unsupported bits are cleared.
  bool error = false;
  auto only = [&](unsigned& src, unsigned allowed) {
    const unsigned was = src;
    src &= allowed;
    error |= src == 0 || src != was;
  };
  only(cmd->start_src, TRIG_NOW | TRIG_INT | TRIG_EXT);
  only(cmd->scan_begin_src, TRIG_TIMER | TRIG_EXT);
  only(cmd->convert_src, TRIG_TIMER | (it->simultaneous ? TRIG_NOW : 0u));
  only(cmd->scan_end_src, TRIG_COUNT);
  only(cmd->stop_src, TRIG_COUNT | TRIG_NONE);
  if (error) return 1;
  // Stage 2: one source each, in a combination the board supports.
  for (unsigned src :
       {cmd->start_src, cmd->scan_begin_src, cmd->convert_src, cmd->scan_end_src, cmd->stop_src}) {
    if (src & (src - 1)) error = true;
  }
  if (error) return 2;
  // Stage 3: arguments in range; the out-of-range ones are set to the nearest valid value.
  auto at_least = [&](unsigned& arg, unsigned min) {
    if (arg < min) {
      arg = min;
      error = true;
    }
  };
  auto at_most = [&](unsigned& arg, unsigned max) {
    if (arg > max) {
      arg = max;
      error = true;
    }
  };
  auto equal = [&](unsigned& arg, unsigned value) {
    if (arg != value) {
      arg = value;
      error = true;
    }
  };
  if (cmd->start_src == TRIG_EXT) {
    if (CR_CHAN(cmd->start_arg) > 15) {  // PFI0 … PFI15
      cmd->start_arg = (cmd->start_arg & (CR_EDGE | CR_INVERT)) | 15;
      error = true;
    }
  } else {
    equal(cmd->start_arg, 0);
  }
  const unsigned n = std::max(cmd->chanlist_len, 1u);
  const unsigned max_timer_ns = it->base_clock_ns * 0xffffffu;
  if (cmd->convert_src == TRIG_TIMER) {
    at_least(cmd->convert_arg, it->min_convert_ns);
    at_most(cmd->convert_arg, it->base_clock_ns * 0xffffu);
  } else {
    equal(cmd->convert_arg, 0);
  }
  if (cmd->scan_begin_src == TRIG_TIMER) {
    at_least(cmd->scan_begin_arg, it->min_convert_ns * n);  // the converter's top speed
    at_most(cmd->scan_begin_arg, max_timer_ns);
  }
  equal(cmd->scan_end_arg, cmd->chanlist_len);
  if (cmd->stop_src == TRIG_COUNT) {
    at_least(cmd->stop_arg, 1);
    at_most(cmd->stop_arg, 0x00ffffffu);
  } else {
    equal(cmd->stop_arg, 0);
  }
  if (error) return 3;
  // Stage 4: timers rounded to the board's clock; a scan must hold its conversions.
  auto round = [&](unsigned& arg) {
    const unsigned rounded = round_ns(arg, it->base_clock_ns, cmd->flags);
    if (rounded != arg) {
      arg = rounded;
      error = true;
    }
  };
  if (cmd->convert_src == TRIG_TIMER) round(cmd->convert_arg);
  if (cmd->scan_begin_src == TRIG_TIMER) {
    round(cmd->scan_begin_arg);
    if (cmd->convert_src == TRIG_TIMER) at_least(cmd->scan_begin_arg, cmd->convert_arg * n);
  }
  if (error) return 4;
  // Stage 5: the channel list.
  if (cmd->chanlist == nullptr || cmd->chanlist_len == 0 || cmd->chanlist_len > 4096) return 5;
  for (unsigned i = 0; i < cmd->chanlist_len; ++i) {
    const unsigned entry = cmd->chanlist[i];
    if (CR_CHAN(entry) >= it->ai_channels || CR_RANGE(entry) >= it->ranges.size()) return 5;
    const int aref_flags[] = {SDF_GROUND, SDF_COMMON, SDF_DIFF, SDF_OTHER};
    if (!(it->aref_flags & aref_flags[CR_AREF(entry)])) return 5;
  }
  return 0;
}

int comedi_command(comedi_t* it, comedi_cmd* cmd) {
  if (it == nullptr || cmd == nullptr) return fail(EINVAL);
  if (it->busy) return fail(EBUSY);
  comedi_cmd tested = *cmd;
  if (comedi_command_test(it, &tested) != 0) {
    *cmd = tested;
    return fail(EAGAIN);  // as the kernel does for a command that does not pass its test
  }
  it->cmd = tested;
  it->chanlist.assign(cmd->chanlist, cmd->chanlist + cmd->chanlist_len);
  it->cmd.chanlist = it->chanlist.data();
  if (it->calibration) comedi_cleanup_calibration(it->calibration);
  it->calibration = it->calibration_file.empty()
                        ? nullptr
                        : comedi_parse_calibration_file(it->calibration_file.c_str());
  it->busy = true;
  it->overrun = false;
  it->consumed_bytes = it->visible_bytes = 0;
  it->command_ns = now_ns();
  it->triggered = it->cmd.start_src == TRIG_NOW;
  it->t0_ns = it->command_ns;
  return 0;
}

int comedi_internal_trigger(comedi_t* it, unsigned subdevice, unsigned trignum) {
  if (!valid_subdevice(it, subdevice)) return -1;
  if (subdevice != 0 || !it->busy || it->cmd.start_src != TRIG_INT || it->triggered ||
      trignum != it->cmd.start_arg) {
    return fail(EINVAL);
  }
  it->triggered = true;
  it->t0_ns = now_ns();
  return 0;
}

int comedi_cancel(comedi_t* it, unsigned subdevice) {
  if (!valid_subdevice(it, subdevice)) return -1;
  it->busy = false;
  it->triggered = false;
  return 0;
}

ssize_t doorbench_comedi_read(comedi_t* it, void* buffer, size_t bytes) {
  if (it == nullptr) return fail(EBADF);
  if (!it->busy) return 0;
  const unsigned size = sample_bytes(it);
  bytes -= bytes % size;
  if (bytes == 0) return fail(EINVAL);
  for (;;) {
    const std::int64_t now = now_ns();
    update(it, now);
    const std::uint64_t available = it->visible_bytes - it->consumed_bytes;
    if (available > 0) {
      const std::uint64_t take = std::min<std::uint64_t>(bytes, available);
      auto* out = static_cast<unsigned char*>(buffer);
      const std::uint64_t n = it->chanlist.size();
      for (std::uint64_t index = it->consumed_bytes / size, end = index + take / size; index < end;
           ++index) {
        const lsampl_t counts = sample_counts(it, index / n, static_cast<unsigned>(index % n));
        if (it->lsampl) {
          std::memcpy(out, &counts, sizeof counts);
        } else {
          const auto sample = static_cast<sampl_t>(counts);
          std::memcpy(out, &sample, sizeof sample);
        }
        out += size;
      }
      it->consumed_bytes += take;
      return static_cast<ssize_t>(take);
    }
    // Drained: an overrun fails with EPIPE, the stop count gives EOF; both end the command.
    if (it->overrun) {
      it->busy = false;
      return fail(EPIPE);
    }
    if (stop_count_reached(it)) {
      it->busy = false;
      return 0;
    }
    const std::int64_t wake = next_data_ns(it, now);
    timespec until{static_cast<time_t>(wake / 1000000000), static_cast<long>(wake % 1000000000)};
    const int slept = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
    if (slept == EINTR) return fail(EINTR);
  }
}

double comedi_to_phys(lsampl_t data, comedi_range* range, lsampl_t maxdata) {
  // comedilib's default out-of-range behaviour (COMEDI_OOR_NAN): the rails are NaN.
  if (range == nullptr || maxdata == 0 || data == 0 || data == maxdata) return NAN;
  return range->min + (range->max - range->min) * static_cast<double>(data) / maxdata;
}

// The emulator's calibration file: lines "CHANNEL RANGE ORIGIN C0 C1 [C2 [C3]]" for
// subdevice 0, CHANNEL or RANGE "*" for all; each becomes a setting with a to_phys
// polynomial.
comedi_calibration_t* comedi_parse_calibration_file(const char* path) {
  std::ifstream in(path ? path : "");
  if (!in) {
    fail(errno ? errno : ENOENT);
    return nullptr;
  }
  auto* calibration =
      static_cast<comedi_calibration_t*>(std::calloc(1, sizeof(comedi_calibration_t)));
  calibration->driver_name = strdup("emulated");
  calibration->board_name = strdup("emulated");
  std::vector<comedi_calibration_setting_t> settings;
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string channel, range;
    auto* polynomial =
        static_cast<comedi_polynomial_t*>(std::calloc(1, sizeof(comedi_polynomial_t)));
    fields >> channel >> range >> polynomial->expansion_origin;
    unsigned order = 0;
    double coefficient = 0;
    while (order < COMEDI_MAX_NUM_POLYNOMIAL_COEFFICIENTS && fields >> coefficient) {
      polynomial->coefficients[order++] = coefficient;
    }
    polynomial->order = order == 0 ? 0 : order - 1;
    comedi_calibration_setting_t setting{};
    setting.subdevice = 0;
    if (channel != "*") {
      setting.channels = static_cast<unsigned*>(std::malloc(sizeof(unsigned)));
      setting.channels[0] = static_cast<unsigned>(std::atoi(channel.c_str()));
      setting.num_channels = 1;
    }
    if (range != "*") {
      setting.ranges = static_cast<unsigned*>(std::malloc(sizeof(unsigned)));
      setting.ranges[0] = static_cast<unsigned>(std::atoi(range.c_str()));
      setting.num_ranges = 1;
    }
    setting.soft_calibration.to_phys = polynomial;
    settings.push_back(setting);
  }
  calibration->num_settings = static_cast<unsigned>(settings.size());
  calibration->settings = static_cast<comedi_calibration_setting_t*>(
      std::calloc(std::max<std::size_t>(settings.size(), 1), sizeof(comedi_calibration_setting_t)));
  std::copy(settings.begin(), settings.end(), calibration->settings);
  return calibration;
}

char* comedi_get_default_calibration_path(comedi_t* it) {
  if (it == nullptr || it->calibration_file.empty()) return nullptr;
  return strdup(it->calibration_file.c_str());
}

void comedi_cleanup_calibration(comedi_calibration_t* calibration) {
  if (calibration == nullptr) return;
  for (unsigned i = 0; i < calibration->num_settings; ++i) {
    comedi_calibration_setting_t& s = calibration->settings[i];
    std::free(s.channels);
    std::free(s.ranges);
    std::free(s.caldacs);
    std::free(s.soft_calibration.to_phys);
    std::free(s.soft_calibration.from_phys);
  }
  std::free(calibration->settings);
  std::free(calibration->driver_name);
  std::free(calibration->board_name);
  std::free(calibration);
}

int comedi_get_softcal_converter(unsigned subdevice, unsigned channel, unsigned range,
                                 enum comedi_conversion_direction direction,
                                 const comedi_calibration_t* calibration,
                                 comedi_polynomial_t* polynomial) {
  if (calibration == nullptr || polynomial == nullptr) return fail(EINVAL);
  const comedi_polynomial_t* found =
      find_polynomial(calibration, subdevice, channel, range, direction == COMEDI_TO_PHYSICAL);
  if (found == nullptr) return fail(EINVAL);
  *polynomial = *found;
  return 0;
}

double comedi_to_physical(lsampl_t data, const comedi_polynomial_t* polynomial) {
  if (polynomial == nullptr) return NAN;
  return evaluate(*polynomial, static_cast<double>(data));
}

}  // extern "C"
