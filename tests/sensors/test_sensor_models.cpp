// The sensor models (sensors/sensor_models.h): the load cell's chain (scale, compression-only
// clamp, hysteresis, non-linearity, overload, noise), the inclinometer's low-pass, offset,
// saturation and noise, the gyroscope's bias, bias random walk, scale factor and saturation,
// the DAQ's quantization, clipping and channel skew, and the parameter lists and messages.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/units.h"
#include "sensors/sensor_models.h"

using Catch::Matchers::Equals;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DaqParameters;
using doorbench::GyroscopeParameters;
using doorbench::InclinometerParameters;
using doorbench::kRadPerDeg;
using doorbench::LoadCellParameters;
using doorbench::sensors::Daq;
using doorbench::sensors::Gyroscope;
using doorbench::sensors::Inclinometer;
using doorbench::sensors::LoadCell;

namespace {

constexpr double kPi = std::numbers::pi;

struct Statistics {
  double mean = 0.0;
  double standard_deviation = 0.0;
};

Statistics statistics(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  const double mean = sum / static_cast<double>(values.size());
  double squares = 0.0;
  for (double v : values) squares += (v - mean) * (v - mean);
  return {mean, std::sqrt(squares / static_cast<double>(values.size() - 1))};
}

LoadCellParameters ideal_load_cell() {
  LoadCellParameters p;
  p.noise_rms_N = 0.0;
  p.nonlinearity_fraction_fs = 0.0;
  p.hysteresis_fraction_fs = 0.0;
  return p;
}

}  // namespace

// --- load cell ------------------------------------------------------------------------

TEST_CASE("load cell: reference scale is 2 mV/V x 10 V x 500 over 445 N", "[sensors]") {
  const LoadCellParameters reference;
  CHECK_THAT(reference.volts_per_newton(), WithinRel(2e-3 * 10.0 * 500.0 / 445.0, 1e-15));
  CHECK_THAT(reference.volts_per_newton() * 445.0, WithinRel(10.0, 1e-15));
}

TEST_CASE("load cell: noise-free reading is exactly F x volts_per_newton", "[sensors]") {
  const LoadCellParameters p = ideal_load_cell();
  LoadCell cell(p, 1);
  for (double force : {0.0, 0.5, 12.25, 100.0, 222.5, 445.0, 600.0}) {
    CHECK(cell.sample_V(force) == force * p.volts_per_newton());
  }
}

TEST_CASE("load cell: compression only reads max(F, 0), both ways when off", "[sensors]") {
  LoadCellParameters p = ideal_load_cell();
  LoadCell compression(p, 1);
  CHECK(compression.sample_V(-50.0) == 0.0);
  CHECK(compression.sample_V(-445.0) == 0.0);
  CHECK(compression.sample_V(30.0) == 30.0 * p.volts_per_newton());

  p.compression_only = 0.0;
  LoadCell both(p, 1);
  CHECK(both.sample_V(-50.0) == -50.0 * p.volts_per_newton());
}

TEST_CASE("load cell: the output clips at the overload level", "[sensors]") {
  LoadCellParameters p = ideal_load_cell();
  p.compression_only = 0.0;
  LoadCell cell(p, 1);
  const double limit_V = 1.5 * 445.0 * p.volts_per_newton();  // 667.5 N, 15 V
  CHECK_THAT(cell.sample_V(1000.0), WithinRel(limit_V, 1e-15));
  CHECK_THAT(cell.sample_V(1000.0), WithinRel(15.0, 1e-14));
  CHECK_THAT(cell.sample_V(-1000.0), WithinRel(-limit_V, 1e-15));
  CHECK(cell.sample_V(667.0) == 667.0 * p.volts_per_newton());  // just inside
}

TEST_CASE("load cell: hysteresis separates loading and unloading by the play width", "[sensors]") {
  LoadCellParameters p = ideal_load_cell();
  p.hysteresis_fraction_fs = 3e-4;
  const double width_N = 3e-4 * 445.0;
  LoadCell cell(p, 1);
  double up_at_100 = std::numeric_limits<double>::quiet_NaN();
  double down_at_100 = up_at_100;
  for (int i = 0; i <= 400; ++i) {  // 0 → 200 N in 0.5 N steps
    const double reading_N = cell.sample_V(0.5 * i) / p.volts_per_newton();
    if (i == 200) up_at_100 = reading_N;
  }
  for (int i = 400; i >= 0; --i) {  // 200 → 0 N
    const double reading_N = cell.sample_V(0.5 * i) / p.volts_per_newton();
    if (i == 200) down_at_100 = reading_N;
  }
  CHECK_THAT(down_at_100 - up_at_100, WithinAbs(width_N, 1e-9));
  CHECK_THAT(up_at_100, WithinAbs(100.0 - width_N / 2, 1e-9));
  CHECK_THAT(down_at_100, WithinAbs(100.0 + width_N / 2, 1e-9));

  // Inside the band the output stays put.
  LoadCell fresh(p, 1);
  const double loaded_V = fresh.sample_V(50.0);
  CHECK(fresh.sample_V(50.0 - 0.9 * width_N) == loaded_V);
  CHECK(fresh.sample_V(50.0) == loaded_V);
}

TEST_CASE("load cell: non-linearity is largest at half full scale, nl x FS", "[sensors]") {
  LoadCellParameters p = ideal_load_cell();
  p.nonlinearity_fraction_fs = 5e-4;
  p.compression_only = 0.0;
  LoadCell cell(p, 1);
  double largest_N = 0.0;
  double where_N = -1.0;
  for (int i = 0; i <= 890; ++i) {  // 0 … 445 N in 0.5 N steps
    const double force = 0.5 * i;
    const double deviation_N = cell.sample_V(force) / p.volts_per_newton() - force;
    if (deviation_N > largest_N) {
      largest_N = deviation_N;
      where_N = force;
    }
  }
  CHECK_THAT(where_N, WithinAbs(222.5, 1e-12));
  CHECK_THAT(largest_N, WithinAbs(5e-4 * 445.0, 1e-9));  // 0.2225 N
  CHECK_THAT(cell.sample_V(445.0) / p.volts_per_newton(), WithinAbs(445.0, 1e-9));
  // Odd in the force.
  CHECK_THAT(cell.sample_V(-222.5) / p.volts_per_newton(), WithinAbs(-222.5 - 0.2225, 1e-9));
}

TEST_CASE("load cell: noise statistics and zero offset", "[sensors]") {
  LoadCellParameters p = ideal_load_cell();
  p.noise_rms_N = 0.2;
  p.zero_offset_N = 1.5;
  LoadCell cell(p, 42);
  const int n = 100000;
  std::vector<double> readings_N(n);
  for (double& r : readings_N) r = cell.sample_V(100.0) / p.volts_per_newton();
  const Statistics s = statistics(readings_N);
  CHECK_THAT(s.mean, WithinAbs(101.5, 4 * 0.2 / std::sqrt(n)));
  CHECK_THAT(s.standard_deviation, WithinRel(0.2, 0.02));
}

TEST_CASE("load cell: the same seed repeats, another seed differs", "[sensors]") {
  const LoadCellParameters p;
  LoadCell a(p, 7);
  LoadCell b(p, 7);
  LoadCell c(p, 8);
  int differing = 0;
  for (int i = 0; i < 100; ++i) {
    const double force = i;
    const double va = a.sample_V(force);
    CHECK(va == b.sample_V(force));
    if (va != c.sample_V(force)) ++differing;
  }
  CHECK(differing == 100);
}

// --- inclinometer ---------------------------------------------------------------------

TEST_CASE("inclinometer: step response reaches 1 - 1/e after one time constant", "[sensors]") {
  InclinometerParameters p;
  p.noise_rms_deg = 0.0;
  const double sample_rate_hz = 10000.0;
  Inclinometer inclinometer(p, sample_rate_hz, 1);
  const double tau_s = 1.0 / (2 * kPi * 10.0);  // 15.9 ms
  const int samples = static_cast<int>(std::lround(tau_s * sample_rate_hz));
  REQUIRE(samples == 159);
  double reading_V = 0.0;
  for (int i = 0; i < samples; ++i) reading_V = inclinometer.sample_V(5.0 * kRadPerDeg);
  CHECK_THAT(reading_V / p.output_V_per_deg, WithinRel(5.0 * (1 - std::exp(-1.0)), 0.01));
}

TEST_CASE("inclinometer: the low-pass is the exact discretization at 1 kHz", "[sensors]") {
  InclinometerParameters p;
  p.noise_rms_deg = 0.0;
  Inclinometer inclinometer(p, 1000.0, 1);
  for (int n = 1; n <= 50; ++n) {
    const double reading_deg = inclinometer.sample_V(5.0 * kRadPerDeg) / p.output_V_per_deg;
    const double exact_deg = 5.0 * (1 - std::exp(-2 * kPi * 10.0 * n / 1000.0));
    CHECK_THAT(reading_deg, WithinRel(exact_deg, 1e-12));
  }
}

TEST_CASE("inclinometer: saturates at +-10 degrees", "[sensors]") {
  InclinometerParameters p;
  p.noise_rms_deg = 0.0;
  Inclinometer inclinometer(p, 1000.0, 1);
  inclinometer.settle(20.0 * kRadPerDeg);
  CHECK_THAT(inclinometer.sample_V(20.0 * kRadPerDeg), WithinRel(4.0, 1e-15));
  inclinometer.settle(-20.0 * kRadPerDeg);
  CHECK_THAT(inclinometer.sample_V(-20.0 * kRadPerDeg), WithinRel(-4.0, 1e-15));
  inclinometer.settle(9.0 * kRadPerDeg);
  CHECK_THAT(inclinometer.sample_V(9.0 * kRadPerDeg), WithinRel(3.6, 1e-12));
}

TEST_CASE("inclinometer: offset and noise", "[sensors]") {
  InclinometerParameters p;
  p.noise_rms_deg = 0.0;
  p.offset_deg = 0.5;
  Inclinometer quiet(p, 1000.0, 1);
  quiet.settle(1.0 * kRadPerDeg);
  CHECK_THAT(quiet.sample_V(1.0 * kRadPerDeg), WithinRel(1.5 * 0.4, 1e-12));
  CHECK_THAT(quiet.sample_V(1.0 * kRadPerDeg), WithinRel(0.6, 1e-12));

  p.noise_rms_deg = 0.01;
  p.offset_deg = 0.0;
  Inclinometer noisy(p, 1000.0, 3);
  noisy.settle(2.0 * kRadPerDeg);
  const int n = 100000;
  std::vector<double> readings_deg(n);
  for (double& r : readings_deg) r = noisy.sample_V(2.0 * kRadPerDeg) / p.output_V_per_deg;
  const Statistics s = statistics(readings_deg);
  CHECK_THAT(s.mean, WithinAbs(2.0, 4 * 0.01 / std::sqrt(n)));
  CHECK_THAT(s.standard_deviation, WithinRel(0.01, 0.02));
}

// --- gyroscope ------------------------------------------------------------------------

TEST_CASE("gyroscope: saturates at +-100 deg/s", "[sensors]") {
  const GyroscopeParameters p;  // with the reference noise and bias
  Gyroscope gyroscope(p, 1000.0, 1);
  CHECK(gyroscope.sample_V(150.0 * kRadPerDeg) == 100.0 * 0.025);
  CHECK(gyroscope.sample_V(-150.0 * kRadPerDeg) == -100.0 * 0.025);
}

TEST_CASE("gyroscope: the bias is the mean at rest", "[sensors]") {
  GyroscopeParameters p;
  p.bias_random_walk_dps_per_sqrt_s = 0.0;
  Gyroscope gyroscope(p, 1000.0, 5);
  const int n = 100000;
  std::vector<double> readings_dps(n);
  for (double& r : readings_dps) r = gyroscope.sample_V(0.0) / p.output_V_per_dps;
  const Statistics s = statistics(readings_dps);
  CHECK_THAT(s.mean, WithinAbs(0.2, 4 * 0.05 / std::sqrt(n)));
  CHECK_THAT(s.standard_deviation, WithinRel(0.05, 0.02));
  CHECK(gyroscope.current_bias_dps() == 0.2);
}

TEST_CASE("gyroscope: the bias random walk's variance grows as rw^2 T", "[sensors]") {
  GyroscopeParameters p;
  p.bias_random_walk_dps_per_sqrt_s = 0.01;
  const double sample_rate_hz = 100.0;
  const double duration_s = 2.0;
  const int steps = static_cast<int>(duration_s * sample_rate_hz);
  std::vector<double> biases;
  for (std::uint64_t seed = 1; seed <= 2000; ++seed) {
    Gyroscope gyroscope(p, sample_rate_hz, seed);
    for (int i = 0; i < steps; ++i) gyroscope.sample_V(0.0);
    biases.push_back(gyroscope.current_bias_dps());
  }
  const Statistics s = statistics(biases);
  const double expected_variance = 0.01 * 0.01 * duration_s;
  CHECK_THAT(s.standard_deviation * s.standard_deviation, WithinRel(expected_variance, 0.2));
  CHECK_THAT(s.mean, WithinAbs(0.2, 4 * std::sqrt(expected_variance / 2000)));
}

TEST_CASE("gyroscope: scale-factor error", "[sensors]") {
  GyroscopeParameters p;
  p.noise_rms_dps = 0.0;
  p.bias_dps = 0.0;
  p.bias_random_walk_dps_per_sqrt_s = 0.0;
  p.scale_factor_error = 0.01;
  Gyroscope gyroscope(p, 1000.0, 1);
  CHECK_THAT(gyroscope.sample_V(50.0 * kRadPerDeg), WithinRel(50.5 * 0.025, 1e-12));
  CHECK_THAT(gyroscope.sample_V(-20.0 * kRadPerDeg), WithinRel(-20.2 * 0.025, 1e-12));
}

TEST_CASE("nominal scale factors per radian", "[sensors]") {
  CHECK_THAT(InclinometerParameters{}.volts_per_rad(),
             WithinRel(0.4 * doorbench::kDegPerRad, 1e-15));
  CHECK_THAT(GyroscopeParameters{}.volts_per_rad_s(),
             WithinRel(0.025 * doorbench::kDegPerRad, 1e-15));
}

// --- DAQ ------------------------------------------------------------------------------

TEST_CASE("daq: 16 bits over +-10 V", "[sensors]") {
  const Daq daq(DaqParameters{});
  CHECK(daq.max_count() == 65535);
  CHECK(daq.volts_per_count() == 20.0 / 65535.0);
  CHECK(daq.to_counts(-10.0) == 0);
  CHECK(daq.to_counts(10.0) == 65535);
  CHECK(daq.to_counts(0.0) == 32768);  // 32767.5 rounds up
  CHECK(daq.to_volts(0) == -10.0);
  CHECK_THAT(daq.to_volts(65535), WithinAbs(10.0, 1e-12));
}

TEST_CASE("daq: counts round-trip and the quantization error is half a count", "[sensors]") {
  const Daq daq(DaqParameters{});
  for (std::int32_t k : {0, 1, 2, 1000, 32767, 32768, 50000, 65534, 65535}) {
    CHECK(daq.to_counts(daq.to_volts(k)) == k);
  }
  double largest_error_V = 0.0;
  for (int i = 0; i <= 100000; ++i) {
    const double volts = -10.0 + 20.0 * i / 100000.0 + 1e-7 * std::sin(i);
    if (volts < -10.0 || volts > 10.0) continue;
    largest_error_V =
        std::max(largest_error_V, std::abs(daq.to_volts(daq.to_counts(volts)) - volts));
  }
  CHECK(largest_error_V <= daq.volts_per_count() / 2 * (1 + 1e-9));
  CHECK(largest_error_V > 0.45 * daq.volts_per_count());
}

TEST_CASE("daq: clips outside the range", "[sensors]") {
  DaqParameters p;
  p.range_min_V = 0.0;
  p.range_max_V = 5.0;
  p.resolution_bits = 12;
  const Daq daq(p);
  CHECK(daq.max_count() == 4095);
  CHECK(daq.to_counts(-0.5) == 0);
  CHECK(daq.to_counts(-1e9) == 0);
  CHECK(daq.to_counts(5.5) == 4095);
  CHECK(daq.to_counts(1e9) == 4095);
  CHECK(daq.to_counts(std::numeric_limits<double>::quiet_NaN()) == 0);
  CHECK(daq.to_counts(2.5) == 2048);  // 2047.5 rounds up
}

TEST_CASE("daq: channel skew within a scan", "[sensors]") {
  const Daq daq(DaqParameters{});
  CHECK(daq.channel_time_offset_s(0) == 0.0);
  CHECK_THAT(daq.channel_time_offset_s(1), WithinRel(10e-6, 1e-15));
  CHECK_THAT(daq.channel_time_offset_s(3), WithinRel(30e-6, 1e-15));
}

// --- parameters -----------------------------------------------------------------------

TEST_CASE("parameters: fields are the C++ names and set() sets them", "[sensors]") {
  const auto fields = LoadCellParameters::fields();
  REQUIRE(fields.size() == 10);
  CHECK(fields.front().name == "full_scale_N");
  CHECK(fields.front().unit == "N");
  CHECK(fields.back().name == "compression_only");
  CHECK(InclinometerParameters::fields().size() == 5);
  CHECK(GyroscopeParameters::fields().size() == 6);
  CHECK(DaqParameters::fields().size() == 5);

  LoadCellParameters cell;
  for (const auto& field : LoadCellParameters::fields()) CHECK(cell.set(field.name, 0.5));
  CHECK(cell.full_scale_N == 0.5);
  CHECK(cell.zero_offset_N == 0.5);
  CHECK(cell.compression_only == 0.5);
  CHECK_FALSE(cell.set("full_scale", 1.0));
  CHECK_FALSE(cell.set("", 1.0));

  InclinometerParameters inclinometer;
  CHECK(inclinometer.set("bandwidth_hz", 20.0));
  CHECK(inclinometer.bandwidth_hz == 20.0);
  CHECK_FALSE(inclinometer.set("bandwidth", 20.0));
  GyroscopeParameters gyroscope;
  CHECK(gyroscope.set("bias_random_walk_dps_per_sqrt_s", 0.1));
  CHECK(gyroscope.bias_random_walk_dps_per_sqrt_s == 0.1);
  CHECK_FALSE(gyroscope.set("range_deg", 1.0));
  DaqParameters daq;
  CHECK(daq.set("resolution_bits", 12));
  CHECK(daq.resolution_bits == 12);
  CHECK_FALSE(daq.set("RANGE_MIN_V", 0.0));

  for (const auto& field : GyroscopeParameters::fields()) {
    CHECK(GyroscopeParameters{}.set(field.name, 1.0));
    CHECK_FALSE(field.unit.empty());
    CHECK_FALSE(field.meaning.empty());
  }
}

TEST_CASE("parameters: validate() names the field and its rule", "[sensors]") {
  CHECK(LoadCellParameters{}.validate().empty());
  CHECK(InclinometerParameters{}.validate().empty());
  CHECK(GyroscopeParameters{}.validate().empty());
  CHECK(DaqParameters{}.validate().empty());

  LoadCellParameters cell;
  cell.full_scale_N = -1;
  CHECK_THAT(cell.validate(), Equals("load_cell full_scale_N = -1 must be > 0"));
  CHECK_THROWS_WITH(LoadCell(cell, 1), Equals("load_cell full_scale_N = -1 must be > 0"));
  CHECK_THROWS_AS(LoadCell(cell, 1), std::invalid_argument);
  cell = {};
  cell.noise_rms_N = -0.25;
  CHECK_THAT(cell.validate(), Equals("load_cell noise_rms_N = -0.25 must be >= 0"));
  cell = {};
  cell.compression_only = 0.5;
  CHECK_THAT(cell.validate(), Equals("load_cell compression_only = 0.5 must be 0 or 1"));
  cell = {};
  cell.zero_offset_N = std::numeric_limits<double>::infinity();
  CHECK_THAT(cell.validate(), Equals("load_cell zero_offset_N = inf must be finite"));

  InclinometerParameters inclinometer;
  inclinometer.bandwidth_hz = 0;
  CHECK_THAT(inclinometer.validate(), Equals("inclinometer bandwidth_hz = 0 must be > 0"));
  inclinometer = {};
  inclinometer.offset_deg = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(inclinometer.validate(), Equals("inclinometer offset_deg = nan must be finite"));
  CHECK_THROWS_WITH(Inclinometer(InclinometerParameters{}, 0.0, 1),
                    Equals("inclinometer sample_rate_hz = 0 must be > 0"));

  GyroscopeParameters gyroscope;
  gyroscope.scale_factor_error = -1;
  CHECK_THAT(gyroscope.validate(), Equals("gyroscope scale_factor_error = -1 must be > -1"));
  CHECK_THROWS_WITH(Gyroscope(gyroscope, 1000.0, 1),
                    Equals("gyroscope scale_factor_error = -1 must be > -1"));
  CHECK_THROWS_WITH(Gyroscope(GyroscopeParameters{}, -100.0, 1),
                    Equals("gyroscope sample_rate_hz = -100 must be > 0"));

  DaqParameters daq;
  daq.resolution_bits = 12.5;
  CHECK_THAT(daq.validate(), Equals("daq resolution_bits = 12.5 must be an integer in [8, 24]"));
  daq.resolution_bits = 32;
  CHECK_THAT(daq.validate(), Equals("daq resolution_bits = 32 must be an integer in [8, 24]"));
  daq = {};
  daq.range_min_V = 5;
  daq.range_max_V = 5;
  CHECK_THAT(daq.validate(), Equals("daq range_min_V = 5 must be < range_max_V = 5"));
  CHECK_THROWS_WITH(Daq(daq), Equals("daq range_min_V = 5 must be < range_max_V = 5"));
  daq = {};
  daq.convert_interval_s = -1e-6;
  CHECK_THAT(daq.validate(), Equals("daq convert_interval_s = -1e-06 must be >= 0"));
  daq = {};
  daq.convert_interval_s = 0;
  CHECK(daq.validate().empty());
}
