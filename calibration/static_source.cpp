#include "calibration/static_source.h"

#include <numbers>
#include <stdexcept>

#include "calibration/procedure.h"
#include "sensors/rig_channel.h"

namespace doorbench::calibration {

namespace {

// The sensor model's parameters, with errors of this library's kind.
template <typename Parameters>
Parameters parameters_of(const RigChannel& channel) {
  try {
    return sensors::parameters_of<Parameters>(channel);
  } catch (const std::invalid_argument& error) {
    throw CalibrationError(error.what());
  }
}

sensors::Daq daq_of(const RigDefinition& rig, const RigChannel& channel) {
  DaqParameters parameters;
  parameters.range_min_V = channel.range_min_V;
  parameters.range_max_V = channel.range_max_V;
  parameters.resolution_bits = rig.daq_resolution_bits;
  parameters.sample_rate_hz = rig.sample_rate_hz;
  parameters.convert_interval_s = rig.convert_interval_s;
  return sensors::Daq(parameters);
}

using Sensor = std::variant<sensors::LoadCell, sensors::Inclinometer, sensors::Gyroscope>;

Sensor make_sensor(const RigDefinition& rig, const RigChannel& channel, std::uint64_t seed) {
  if (channel.sensor == "load_cell") return sensors::LoadCell(load_cell_parameters(channel), seed);
  if (channel.sensor == "inclinometer") {
    sensors::Inclinometer inclinometer(inclinometer_parameters(channel), rig.sample_rate_hz, seed);
    inclinometer.settle(0.0);
    return inclinometer;
  }
  if (channel.sensor == "gyroscope") {
    return sensors::Gyroscope(gyroscope_parameters(channel), rig.sample_rate_hz, seed);
  }
  throw CalibrationError("channel " + channel.name + ": no sensor model for " + channel.sensor);
}

}  // namespace

LoadCellParameters load_cell_parameters(const RigChannel& channel) {
  return parameters_of<LoadCellParameters>(channel);
}
InclinometerParameters inclinometer_parameters(const RigChannel& channel) {
  return parameters_of<InclinometerParameters>(channel);
}
GyroscopeParameters gyroscope_parameters(const RigChannel& channel) {
  return parameters_of<GyroscopeParameters>(channel);
}

SimulatedStaticSource::SimulatedStaticSource(const RigDefinition& rig, const RigChannel& channel,
                                             std::uint64_t seed)
    : description_("simulated " + channel.sensor + " " + channel.serial + " (channel " +
                   channel.name + " of " + rig.name + ")"),
      sample_rate_hz_(rig.sample_rate_hz),
      sensor_(make_sensor(rig, channel, seed)),
      daq_(daq_of(rig, channel)) {}

std::string SimulatedStaticSource::description() const {
  return description_;
}

std::vector<double> SimulatedStaticSource::read_V(std::size_t samples) {
  std::vector<double> volts(samples);
  for (double& v : volts) {
    const double signal =
        std::visit([&](auto& sensor) { return sensor.sample_V(reference_); }, sensor_);
    v = daq_.to_volts(daq_.to_counts(signal));
  }
  return volts;
}

std::unique_ptr<StaticSignalSource> live_source(const RigDefinition& rig,
                                                const RigChannel& channel) {
  if (channel.backend == "simulated") {
    const std::uint64_t seed = rig.simulation ? rig.simulation->seed : 1;
    // A seed of its own, apart from the recordings' (which use seed · 1000003 + index).
    return std::make_unique<SimulatedStaticSource>(rig, channel, seed * 7919u + 17u);
  }
  throw CalibrationError("channel " + channel.name + " uses backend " + channel.backend +
                         ", which doorbench cannot read live yet (only simulated); calibrate "
                         "from a recording with --from SESSION");
}

const RigChannel& find_rig_channel(const RigDefinition& rig, const std::string& sensor_kind,
                                   const std::string& name) {
  std::vector<const RigChannel*> candidates;
  for (const RigChannel& channel : rig.channels) {
    if (channel.sensor == sensor_kind) candidates.push_back(&channel);
  }
  std::string listed;
  for (const RigChannel* c : candidates) listed += (listed.empty() ? "" : ", ") + c->name;
  if (!name.empty()) {
    for (const RigChannel* c : candidates) {
      if (c->name == name) return *c;
    }
    throw CalibrationError(
        rig.source + ": no " + sensor_kind + " channel " + name +
        (listed.empty() ? "" : " (" + sensor_kind + " channels: " + listed + ")"));
  }
  if (candidates.empty()) throw CalibrationError(rig.source + ": no " + sensor_kind + " channel");
  if (candidates.size() > 1) {
    throw CalibrationError(rig.source + ": several " + sensor_kind + " channels (" + listed +
                           "); choose one with --channel");
  }
  return *candidates.front();
}

}  // namespace doorbench::calibration
