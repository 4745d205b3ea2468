#include "sensors/modbus_source.h"

#include <modbus.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <thread>

#include "acquisition/record/ring_buffer.h"
#include "sensors/modbus_decode.h"

namespace doorbench::sensors {

namespace {

constexpr std::int64_t kNsPerS = 1000000000;

// Copies `text` into a fixed field, cut with "..." when it does not fit; no allocation.
template <std::size_t N>
void copy_text(char (&field)[N], const char* text) {
  const std::size_t length = std::strlen(text);
  if (length < N) {
    std::memcpy(field, text, length + 1);
    return;
  }
  std::memcpy(field, text, N - 4);
  std::memcpy(field + N - 4, "...", 4);
}

void sleep_until_ns(std::int64_t deadline_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline_ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(deadline_ns % kNsPerS);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Sleeps until `deadline_ns`, waking at least every 50 ms to see `stop` (a slow channel or a
// long back-off must not hold up stop()); false when stopped.
bool sleep_unless_stopped(std::int64_t deadline_ns, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSliceNs = 50000000;
  for (std::int64_t now = monotonic_now_ns(); now < deadline_ns; now = monotonic_now_ns()) {
    if (stop.load(std::memory_order_relaxed)) return false;
    sleep_until_ns(std::min(deadline_ns, now + kSliceNs));
  }
  return !stop.load(std::memory_order_relaxed);
}

bool is_exception_reply(int error) {
  return error >= EMBXILFUN && error <= EMBXGTAR;
}

// Errors after which the request/reply stream is still usable (the server answered, or
// may answer the next request): everything else means the connection is gone.
bool connection_survives(int error) {
  return error == ETIMEDOUT || is_exception_reply(error) || error == EMBBADCRC ||
         error == EMBBADDATA || error == EMBBADEXC || error == EMBUNKEXC || error == EMBMDATA ||
         error == EMBBADSLAVE;
}

// What a failed poll was, for a fault's detail (static texts: no allocation).
const char* error_kind(int error) {
  if (error == ETIMEDOUT) return "timeout (no reply)";
  if (is_exception_reply(error)) return "exception reply";
  if (error == EMBBADCRC) return "CRC error";
  if (connection_survives(error)) return "bad reply";
  return "connection lost";
}

std::string lower_first(std::string text) {
  if (!text.empty() && text[0] >= 'A' && text[0] <= 'Z') text[0] = static_cast<char>(text[0] + 32);
  return text;
}

char parity_letter(const std::string& parity) {
  if (parity == "even") return 'E';
  if (parity == "odd") return 'O';
  return 'N';
}

struct ModbusContext {
  modbus_t* ctx = nullptr;
  ModbusContext() = default;
  ModbusContext(const ModbusContext&) = delete;
  ModbusContext& operator=(const ModbusContext&) = delete;
  ~ModbusContext() { reset(); }
  void reset() {
    if (ctx) {
      modbus_close(ctx);
      modbus_free(ctx);
      ctx = nullptr;
    }
  }
};

// A new libmodbus context for `device` (not connected); throws naming the device.
modbus_t* new_context(const RigModbusDevice& device) {
  modbus_t* ctx = nullptr;
  if (device.transport == "tcp") {
    ctx = modbus_new_tcp(device.host.c_str(), device.port);
  } else {
    ctx = modbus_new_rtu(device.device.c_str(), device.baud, parity_letter(device.parity),
                         device.data_bits, device.stop_bits);
  }
  if (!ctx) {
    throw ModbusError(modbus_device_label(device) + ": cannot create a libmodbus context: " +
                      lower_first(modbus_strerror(errno)));
  }
  const double timeout_s = device.response_timeout_s;
  const auto seconds = static_cast<std::uint32_t>(timeout_s);
  const auto microseconds = static_cast<std::uint32_t>(std::lround((timeout_s - seconds) * 1e6));
  modbus_set_response_timeout(ctx, seconds, microseconds);
  return ctx;
}

// One channel's request, decoded as in the rig.
struct ChannelPlan {
  std::uint32_t index = 0;  // into the source's channels
  std::string name;
  int unit_id = 1;
  bool input_registers = false;
  int address = 0;
  int count = 1;
  ModbusType type = ModbusType::kUint16;
  ModbusOrder byte_order = ModbusOrder::kBig;
  ModbusOrder word_order = ModbusOrder::kBig;
  std::int64_t period_ns = 0;
  // Polling state (the device's thread only).
  std::int64_t next_ns = 0;
  int failing_error = 0;  // the error of the current run of failed polls, 0 when answering
  std::uint64_t failed_polls = 0;
};

ChannelPlan plan_for(const RigChannel& channel, std::uint32_t index) {
  const RigModbusChannel& m = *channel.modbus;
  ChannelPlan plan;
  plan.index = index;
  plan.name = channel.name;
  plan.unit_id = m.unit_id;
  plan.input_registers = m.kind == "input";
  plan.address = m.address;
  plan.type = *modbus_type_from_name(m.type);
  plan.count = modbus_register_count(plan.type);
  plan.byte_order = *modbus_order_from_name(m.byte_order);
  plan.word_order =
      m.word_order.empty() ? ModbusOrder::kBig : *modbus_order_from_name(m.word_order);
  plan.period_ns = std::max<std::int64_t>(1, std::llround(1e9 / m.poll_rate_hz));
  return plan;
}

// One request for a channel: the decoded value, or -1 with errno set (libmodbus').
int read_once(modbus_t* ctx, const ChannelPlan& plan, double& value) {
  std::array<std::uint16_t, 2> registers{};
  modbus_set_slave(ctx, plan.unit_id);
  const int rc = plan.input_registers
                     ? modbus_read_input_registers(ctx, plan.address, plan.count, registers.data())
                     : modbus_read_registers(ctx, plan.address, plan.count, registers.data());
  if (rc != plan.count) {
    if (rc >= 0) errno = EMBMDATA;
    return -1;
  }
  value = decode_modbus_value(std::span<const std::uint16_t>(registers.data(), plan.count),
                              plan.type, plan.byte_order, plan.word_order);
  return 0;
}

}  // namespace

std::string ModbusSourceOptions::validate() const {
  if (sample_ring_slots < 16) return "sample_ring_slots must be >= 16";
  if (event_ring_slots < 16) return "event_ring_slots must be >= 16";
  return "";
}

std::string modbus_device_label(const RigModbusDevice& device) {
  std::string label = std::string("modbus device ").append(device.name).append(" (");
  if (device.transport == "tcp") {
    label.append("tcp ").append(device.host).append(":").append(std::to_string(device.port));
  } else {
    label.append("rtu ")
        .append(device.device)
        .append(" ")
        .append(std::to_string(device.baud))
        .append(" ")
        .append(std::to_string(device.data_bits))
        .append(1, parity_letter(device.parity))
        .append(std::to_string(device.stop_bits));
  }
  return label.append(")");
}

struct ModbusSource::Device {
  Device(const RigModbusDevice& rig_device, const ModbusSourceOptions& options)
      : config(rig_device),
        label(modbus_device_label(rig_device)),
        samples(options.sample_ring_slots, PolledSample{}),
        events(options.event_ring_slots, PolledEvent{}) {}

  RigModbusDevice config;
  std::string label;
  std::vector<ChannelPlan> plans;
  ModbusContext context;
  std::thread thread;
  SpscRing<PolledSample> samples;
  SpscRing<PolledEvent> events;
  std::atomic<std::uint64_t> polls{0};
  std::atomic<std::uint64_t> delivered{0};
  std::atomic<std::uint64_t> faults{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<std::uint64_t> dropped_samples{0};
  std::atomic<std::uint64_t> dropped_events{0};

  // Polling thread only from here on.
  void event(const char* kind, const char* channel, const char* detail) {
    if (std::strcmp(kind, "fault") == 0) faults.fetch_add(1, std::memory_order_relaxed);
    PolledEvent* slot = events.producer_slot();
    if (!slot) {
      dropped_events.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    slot->monotonic_ns = monotonic_now_ns();
    copy_text(slot->kind, kind);
    copy_text(slot->channel, channel);
    copy_text(slot->detail, detail);
    events.publish();
  }

  void poll(ChannelPlan& plan, bool& connected) {
    double value = 0;
    const std::int64_t request_ns = monotonic_now_ns();
    const int rc = read_once(context.ctx, plan, value);
    const std::int64_t response_ns = monotonic_now_ns();
    polls.fetch_add(1, std::memory_order_relaxed);
    char detail[256];
    if (rc == 0) {
      if (plan.failing_error != 0) {
        std::snprintf(detail, sizeof detail,
                      "%s: unit %d %s register %d answers again after %llu failed poll(s)",
                      label.c_str(), plan.unit_id, plan.input_registers ? "input" : "holding",
                      plan.address, static_cast<unsigned long long>(plan.failed_polls));
        event("mark", plan.name.c_str(), detail);
        plan.failing_error = 0;
        plan.failed_polls = 0;
      }
      PolledSample* slot = samples.producer_slot();
      if (!slot) {
        dropped_samples.fetch_add(1, std::memory_order_relaxed);
        return;
      }
      slot->channel = plan.index;
      slot->request_ns = request_ns;
      slot->response_ns = response_ns;
      slot->raw = value;
      samples.publish();
      delivered.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    const int error = errno;
    ++plan.failed_polls;
    if (!connection_survives(error)) {
      std::snprintf(detail, sizeof detail, "%s: unit %d %s register %d: %s: %s", label.c_str(),
                    plan.unit_id, plan.input_registers ? "input" : "holding", plan.address,
                    error_kind(error), modbus_strerror(error));
      event("fault", plan.name.c_str(), detail);
      modbus_close(context.ctx);
      connected = false;
      return;
    }
    // Discard whatever is left of a late or broken reply so the next one is read whole.
    modbus_flush(context.ctx);
    if (error == plan.failing_error && !is_exception_reply(error)) return;  // same run
    plan.failing_error = error;
    std::snprintf(detail, sizeof detail, "%s: unit %d %s register %d: %s: %s", label.c_str(),
                  plan.unit_id, plan.input_registers ? "input" : "holding", plan.address,
                  error_kind(error), modbus_strerror(error));
    event("fault", plan.name.c_str(), detail);
  }

  // Reconnects with back-off until connected or stopped.
  void reconnect(const std::atomic<bool>& stop) {
    double backoff_s = config.reconnect_min_s;
    char detail[256];
    while (!stop.load(std::memory_order_relaxed)) {
      const std::int64_t wake_ns = monotonic_now_ns() + std::llround(backoff_s * 1e9);
      if (!sleep_unless_stopped(wake_ns, stop)) return;
      if (modbus_connect(context.ctx) == 0) {
        reconnects.fetch_add(1, std::memory_order_relaxed);
        std::snprintf(detail, sizeof detail, "%s: reconnected", label.c_str());
        event("mark", "", detail);
        const std::int64_t now = monotonic_now_ns();
        for (ChannelPlan& plan : plans) {
          plan.next_ns = now;
          plan.failing_error = 0;
          plan.failed_polls = 0;
        }
        return;
      }
      modbus_close(context.ctx);
      backoff_s = std::min(backoff_s * 2, config.reconnect_max_s);
    }
  }

  void run(const std::atomic<bool>& stop) {
    bool connected = true;
    const std::int64_t start_ns = monotonic_now_ns();
    for (ChannelPlan& plan : plans) plan.next_ns = start_ns;
    while (!stop.load(std::memory_order_relaxed)) {
      if (!connected) {
        reconnect(stop);
        connected = true;
        continue;
      }
      ChannelPlan* due = &plans.front();
      for (ChannelPlan& plan : plans) {
        if (plan.next_ns < due->next_ns) due = &plan;
      }
      if (!sleep_unless_stopped(due->next_ns, stop)) break;
      poll(*due, connected);
      // The next deadline on the channel's grid. After a slow reply, the latest deadline
      // that has passed is polled at once and any before it are skipped: no burst of
      // catch-up requests, and the grid does not drift.
      const std::int64_t now = monotonic_now_ns();
      due->next_ns += due->period_ns;
      if (due->next_ns <= now) {
        due->next_ns += ((now - due->next_ns) / due->period_ns) * due->period_ns;
      }
    }
  }
};

ModbusSource::ModbusSource(const RigDefinition& rig, ModbusSourceOptions options) {
  if (const std::string message = options.validate(); !message.empty()) {
    throw ModbusError("modbus source options: " + message);
  }
  for (const RigChannel& rc : rig.channels) {
    if (rc.backend != "modbus" || !rc.modbus) continue;
    const RigModbusDevice* rig_device = rig.find_modbus_device(rc.modbus->device);
    if (!rig_device) {
      throw ModbusError(rig.source + ": channel " + rc.name + ": no modbus device " +
                        rc.modbus->device);
    }
    auto found = std::find_if(devices_.begin(), devices_.end(),
                              [&](const auto& d) { return d->config.name == rig_device->name; });
    if (found == devices_.end()) {
      devices_.push_back(std::make_unique<Device>(*rig_device, options));
      found = devices_.end() - 1;
    }
    (*found)->plans.push_back(plan_for(rc, static_cast<std::uint32_t>(channels_.size())));

    ChannelInfo info;
    info.name = rc.name;
    info.sensor_kind = rc.sensor;
    info.sensor_serial = rc.serial;
    info.raw_type = RawType::kValues;
    // The signal (raw_offset + raw_scale · raw) is the physical value already.
    info.raw_unit = rc.unit;
    info.raw_offset = rc.modbus->offset;
    info.raw_scale = rc.modbus->scale;
    info.range_min = rc.modbus->range_min;
    info.range_max = rc.modbus->range_max;
    info.unit = rc.unit;
    info.calibration_id = "";
    info.sample_rate_hz = 0.0;
    channels_.push_back(std::move(info));
  }
  if (channels_.empty()) throw ModbusError(rig.source + ": the rig has no modbus channels");
}

ModbusSource::~ModbusSource() {
  stop();
}

std::string ModbusSource::description() const {
  std::string text = "Modbus:";
  for (const auto& device : devices_) {
    text.append(" ").append(device->label).append(" ").append(std::to_string(device->plans.size()));
    text.append(device->plans.size() == 1 ? " channel;" : " channels;");
  }
  text.pop_back();
  return text;
}

std::vector<ChannelInfo> ModbusSource::channels() const {
  return channels_;
}

void ModbusSource::start() {
  if (running_) throw ModbusError("modbus source: start() while running");
  // Connect every device first, so that a device that cannot be reached fails the start.
  for (auto& device : devices_) {
    device->context.reset();
    device->context.ctx = new_context(device->config);
    if (modbus_connect(device->context.ctx) != 0) {
      const int error = errno;
      for (auto& other : devices_) other->context.reset();
      throw ModbusError(device->label + ": " + lower_first(modbus_strerror(error)));
    }
  }
  stop_requested_.store(false);
  for (auto& device : devices_) {
    Device* d = device.get();
    d->thread = std::thread([d, this] { d->run(stop_requested_); });
  }
  running_ = true;
}

std::size_t ModbusSource::take_samples(std::span<PolledSample> out) {
  std::size_t taken = 0;
  for (auto& device : devices_) {
    while (taken < out.size()) {
      const PolledSample* slot = device->samples.consumer_slot();
      if (!slot) break;
      out[taken++] = *slot;
      device->samples.release();
    }
  }
  return taken;
}

std::size_t ModbusSource::take_events(std::span<PolledEvent> out) {
  std::size_t taken = 0;
  for (auto& device : devices_) {
    while (taken < out.size()) {
      const PolledEvent* slot = device->events.consumer_slot();
      if (!slot) break;
      out[taken++] = *slot;
      device->events.release();
    }
  }
  return taken;
}

void ModbusSource::stop() {
  if (!running_) return;
  stop_requested_.store(true);
  for (auto& device : devices_) {
    if (device->thread.joinable()) device->thread.join();
    device->context.reset();
  }
  running_ = false;
}

PolledStatistics ModbusSource::statistics() const {
  PolledStatistics total;
  for (const auto& device : devices_) {
    total.polls += device->polls.load(std::memory_order_relaxed);
    total.samples += device->delivered.load(std::memory_order_relaxed);
    total.faults += device->faults.load(std::memory_order_relaxed);
    total.reconnects += device->reconnects.load(std::memory_order_relaxed);
    total.dropped_samples += device->dropped_samples.load(std::memory_order_relaxed);
  }
  return total;
}

std::string modbus_probe_report(const RigDefinition& rig) {
  std::ostringstream out;
  if (rig.modbus_devices.empty()) return "no Modbus devices in " + rig.source + "\n";
  for (const RigModbusDevice& device : rig.modbus_devices) {
    out << modbus_device_label(device) << ":";
    ModbusContext context;
    try {
      context.ctx = new_context(device);
    } catch (const ModbusError& error) {
      out << " " << error.what() << "\n";
      continue;
    }
    if (modbus_connect(context.ctx) != 0) {
      out << " cannot connect: " << lower_first(modbus_strerror(errno)) << "\n";
      continue;
    }
    out << " connected\n";
    std::uint32_t index = 0;
    for (const RigChannel& channel : rig.channels) {
      if (!channel.modbus || channel.modbus->device != device.name) continue;
      const ChannelPlan plan = plan_for(channel, index++);
      double raw = 0;
      const std::int64_t request_ns = monotonic_now_ns();
      const int rc = read_once(context.ctx, plan, raw);
      const std::int64_t response_ns = monotonic_now_ns();
      out << "  " << channel.name << " (unit " << plan.unit_id << ", " << channel.modbus->kind
          << " register " << plan.address << ", " << channel.modbus->type << "): ";
      if (rc != 0) {
        const int error = errno;
        out << error_kind(error) << ": " << modbus_strerror(error) << "\n";
        if (!connection_survives(error)) break;
        modbus_flush(context.ctx);
        continue;
      }
      const double value = channel.modbus->offset + channel.modbus->scale * raw;
      char line[160];
      std::snprintf(line, sizeof line, "%.6g %s (register value %.9g), latency %.3f ms\n", value,
                    channel.unit.c_str(), raw, static_cast<double>(response_ns - request_ns) / 1e6);
      out << line;
    }
  }
  return out.str();
}

}  // namespace doorbench::sensors
