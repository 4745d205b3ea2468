#pragma once
// Where a guided calibration gets its readings: one channel's signal (V) while a static
// reference (a load, a tilt) is applied. A live bench's source only reads; the simulated
// one also applies the reference the operator was asked for, through the channel's sensor
// model and the rig's DAQ, so that the procedure runs without hardware (and in tests).
#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "sensors/sensor_models.h"

namespace doorbench::calibration {

class StaticSignalSource {
 public:
  virtual ~StaticSignalSource() = default;
  virtual std::string description() const = 0;
  virtual double sample_rate_hz() const = 0;
  // Told after each prompt which reference the operator was asked to apply (in the
  // channel's unit: N, rad or rad/s). A live source ignores it: the operator applies it.
  virtual void expect_reference(double reference) = 0;
  // The next `samples` readings of the signal in volts, in time order.
  virtual std::vector<double> read_V(std::size_t samples) = 0;
};

// The sensor model of a rig channel (its [channels.parameters]) behind the rig's DAQ,
// held at a static reference: a force on the load cell (N), a tilt of the inclinometer
// (rad) or a rate on a turntable for the gyroscope (rad/s). Readings are DAQ counts turned
// back into volts, so quantization is included. The inclinometer's filter starts settled
// at 0 and follows each new reference with its lag; the load cell's hysteresis follows the
// loading order.
class SimulatedStaticSource final : public StaticSignalSource {
 public:
  SimulatedStaticSource(const RigDefinition& rig, const RigChannel& channel, std::uint64_t seed);
  std::string description() const override;
  double sample_rate_hz() const override { return sample_rate_hz_; }
  void expect_reference(double reference) override { reference_ = reference; }
  std::vector<double> read_V(std::size_t samples) override;

 private:
  std::string description_;
  double sample_rate_hz_;
  std::variant<sensors::LoadCell, sensors::Inclinometer, sensors::Gyroscope> sensor_;
  sensors::Daq daq_;
  double reference_ = 0.0;
};

// The source for a live guided procedure on `channel`: the simulated one for a simulated
// channel (seeded by the rig's [simulation] seed). Other backends throw CalibrationError
// (doorbench has no comedi or Modbus driver yet: calibrate from a recording instead).
std::unique_ptr<StaticSignalSource> live_source(const RigDefinition& rig,
                                                const RigChannel& channel);

// The channel's sensor-model parameters from the rig (defaults for those not given).
LoadCellParameters load_cell_parameters(const RigChannel& channel);
InclinometerParameters inclinometer_parameters(const RigChannel& channel);
GyroscopeParameters gyroscope_parameters(const RigChannel& channel);

// The rig's channel of that sensor kind named `name`, or its only one when `name` is
// empty. Throws CalibrationError naming the candidates.
const RigChannel& find_rig_channel(const RigDefinition& rig, const std::string& sensor_kind,
                                   const std::string& name);

}  // namespace doorbench::calibration
