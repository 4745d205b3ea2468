#include "sensors/rig_channel.h"

#include <cmath>
#include <numbers>

#include "acquisition/rig/calibration_store.h"
#include "core/units.h"
#include "sensors/sensor_models.h"

namespace doorbench::sensors {

namespace {}  // namespace

CalibrationRecord nominal_calibration(const RigChannel& channel) {
  CalibrationRecord record;
  record.id = "nominal-" + (channel.serial.empty() ? channel.name : channel.serial);
  record.sensor_kind = channel.sensor;
  record.sensor_serial = channel.serial;
  record.unit = channel.unit;
  record.method = "nominal (datasheet figures of the sensor model)";
  if (channel.sensor == "load_cell") {
    const auto p = parameters_of<LoadCellParameters>(channel);
    record.coefficients = {0.0, 1.0 / p.volts_per_newton()};
    record.standard_uncertainty =
        (p.nonlinearity_fraction_fs + p.hysteresis_fraction_fs) * p.full_scale_N / std::sqrt(3.0);
  } else if (channel.sensor == "inclinometer") {
    const auto p = parameters_of<InclinometerParameters>(channel);
    record.coefficients = {0.0, kRadPerDeg / p.output_V_per_deg};
    record.standard_uncertainty = p.noise_rms_deg * kRadPerDeg;
  } else if (channel.sensor == "gyroscope") {
    const auto p = parameters_of<GyroscopeParameters>(channel);
    record.coefficients = {0.0, kRadPerDeg / p.output_V_per_dps};
    record.standard_uncertainty = std::abs(p.bias_dps) * kRadPerDeg;
  } else {
    throw std::invalid_argument("channel " + channel.name + ": no sensor model for " +
                                channel.sensor);
  }
  record.notes = "Before any calibration: the sensor's datasheet sensitivity, no offset.";
  return record;
}

CalibrationRecord rig_channel_calibration(const RigDefinition& rig, const RigChannel& channel) {
  if (channel.calibration == "nominal") return nominal_calibration(channel);
  try {
    return resolve_channel_record(
        CalibrationStore(calibration_store_directory(rig.calibration_store, rig.base_dir)),
        channel.calibration, channel.name, channel.sensor, channel.serial, channel.unit);
  } catch (const std::runtime_error& error) {
    throw std::invalid_argument(rig.source + ": " + error.what());
  }
}

ChannelInfo counts_channel_info(const RigChannel& channel, const CalibrationRecord& record,
                                const CountsChannelClock& clock) {
  ChannelInfo info;
  info.name = channel.name;
  info.sensor_kind = channel.sensor;
  info.sensor_serial = channel.serial;
  info.raw_type = RawType::kCounts;
  info.raw_unit = "counts";
  info.raw_offset = clock.raw_offset_V;
  info.raw_scale = clock.raw_scale_V;
  info.range_min = clock.range_min_V;
  info.range_max = clock.range_max_V;
  info.unit = channel.unit;
  info.calibration_id = record.id;
  info.sample_rate_hz = clock.sample_rate_hz;
  info.first_sample_time_s = clock.first_sample_time_s;
  return info;
}

}  // namespace doorbench::sensors
