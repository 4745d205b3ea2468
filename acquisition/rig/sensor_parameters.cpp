#include "acquisition/rig/sensor_parameters.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <numbers>

#include "core/number_format.h"
#include "core/units.h"

namespace doorbench {
namespace {

// What a field's value must satisfy (besides being finite, which every field must be).
enum class Rule { kAny, kPositive, kNonNegative, kFlag, kBits, kAboveMinusOne };

template <class Parameters>
struct FieldEntry {
  ParameterField field;
  double Parameters::*member;
  Rule rule;
};

// The ParameterField column of a field table, for fields().
template <class Parameters, std::size_t N>
constexpr std::array<ParameterField, N> field_column(
    const std::array<FieldEntry<Parameters>, N>& entries) {
  std::array<ParameterField, N> column{};
  for (std::size_t i = 0; i < N; ++i) column[i] = entries[i].field;
  return column;
}

template <class Parameters, std::size_t N>
bool set_field(const std::array<FieldEntry<Parameters>, N>& entries, Parameters& parameters,
               std::string_view name, double value) {
  for (const auto& entry : entries) {
    if (entry.field.name == name) {
      parameters.*entry.member = value;
      return true;
    }
  }
  return false;
}

// "" when `value` obeys `rule`, else the rule's text after "must be".
std::string_view rule_violation(Rule rule, double value) {
  if (!std::isfinite(value)) return "finite";
  switch (rule) {
    case Rule::kAny:
      return "";
    case Rule::kPositive:
      return value > 0 ? "" : "> 0";
    case Rule::kNonNegative:
      return value >= 0 ? "" : ">= 0";
    case Rule::kFlag:
      return value == 0 || value == 1 ? "" : "0 or 1";
    case Rule::kBits:
      return value >= 8 && value <= 24 && value == std::floor(value) ? "" : "an integer in [8, 24]";
    case Rule::kAboveMinusOne:
      return value > -1 ? "" : "> -1";
  }
  return "";
}

std::string violation_message(std::string_view sensor, std::string_view field, double value,
                              std::string_view rule_text) {
  std::string message(sensor);
  message += ' ';
  message += field;
  message += " = ";
  message += format_number(value);
  message += " must be ";
  message += rule_text;
  return message;
}

// The first field (in table order) that breaks its rule, as a message; "" when none does.
template <class Parameters, std::size_t N>
std::string check_fields(std::string_view sensor,
                         const std::array<FieldEntry<Parameters>, N>& entries,
                         const Parameters& parameters) {
  for (const auto& entry : entries) {
    const double value = parameters.*entry.member;
    const std::string_view broken = rule_violation(entry.rule, value);
    if (!broken.empty()) return violation_message(sensor, entry.field.name, value, broken);
  }
  return "";
}

using LoadCellEntry = FieldEntry<LoadCellParameters>;
constexpr std::array<LoadCellEntry, 10> kLoadCellFields{{
    {{"full_scale_N", "N", "rated capacity"}, &LoadCellParameters::full_scale_N, Rule::kPositive},
    {{"sensitivity_mV_per_V", "mV/V", "bridge output at full scale per volt of excitation"},
     &LoadCellParameters::sensitivity_mV_per_V,
     Rule::kPositive},
    {{"excitation_V", "V", "bridge excitation"},
     &LoadCellParameters::excitation_V,
     Rule::kPositive},
    {{"amplifier_gain", "V/V", "bridge amplifier gain"},
     &LoadCellParameters::amplifier_gain,
     Rule::kPositive},
    {{"noise_rms_N", "N", "white noise per sample, referred to the force"},
     &LoadCellParameters::noise_rms_N,
     Rule::kNonNegative},
    {{"nonlinearity_fraction_fs", "1",
      "largest deviation from the straight line (at half full scale) / full scale"},
     &LoadCellParameters::nonlinearity_fraction_fs,
     Rule::kNonNegative},
    {{"hysteresis_fraction_fs", "1", "loading vs unloading difference / full scale"},
     &LoadCellParameters::hysteresis_fraction_fs,
     Rule::kNonNegative},
    {{"overload_fraction_fs", "1", "the output clips at +- this x full scale"},
     &LoadCellParameters::overload_fraction_fs,
     Rule::kPositive},
    {{"zero_offset_N", "N", "unloaded reading"}, &LoadCellParameters::zero_offset_N, Rule::kAny},
    {{"compression_only", "1", "1: reads max(F, 0); 0: reads both ways"},
     &LoadCellParameters::compression_only,
     Rule::kFlag},
}};
constexpr auto kLoadCellFieldColumn = field_column(kLoadCellFields);

using InclinometerEntry = FieldEntry<InclinometerParameters>;
constexpr std::array<InclinometerEntry, 5> kInclinometerFields{{
    {{"range_deg", "deg", "the output saturates beyond +- this"},
     &InclinometerParameters::range_deg,
     Rule::kPositive},
    {{"bandwidth_hz", "Hz", "first-order low-pass -3 dB frequency"},
     &InclinometerParameters::bandwidth_hz,
     Rule::kPositive},
    {{"noise_rms_deg", "deg", "white noise per sample"},
     &InclinometerParameters::noise_rms_deg,
     Rule::kNonNegative},
    {{"offset_deg", "deg", "reading when level"}, &InclinometerParameters::offset_deg, Rule::kAny},
    {{"output_V_per_deg", "V/deg", "output scale"},
     &InclinometerParameters::output_V_per_deg,
     Rule::kPositive},
}};
constexpr auto kInclinometerFieldColumn = field_column(kInclinometerFields);

using GyroscopeEntry = FieldEntry<GyroscopeParameters>;
constexpr std::array<GyroscopeEntry, 6> kGyroscopeFields{{
    {{"range_dps", "deg/s", "the output saturates beyond +- this"},
     &GyroscopeParameters::range_dps,
     Rule::kPositive},
    {{"noise_rms_dps", "deg/s", "white noise per sample"},
     &GyroscopeParameters::noise_rms_dps,
     Rule::kNonNegative},
    {{"bias_dps", "deg/s", "initial bias"}, &GyroscopeParameters::bias_dps, Rule::kAny},
    {{"bias_random_walk_dps_per_sqrt_s", "deg/s/sqrt(s)",
      "bias random walk: the bias's standard deviation grows as this x sqrt(time)"},
     &GyroscopeParameters::bias_random_walk_dps_per_sqrt_s,
     Rule::kNonNegative},
    {{"scale_factor_error", "1", "reads (1 + this) x rate"},
     &GyroscopeParameters::scale_factor_error,
     Rule::kAboveMinusOne},
    {{"output_V_per_dps", "V/(deg/s)", "output scale"},
     &GyroscopeParameters::output_V_per_dps,
     Rule::kPositive},
}};
constexpr auto kGyroscopeFieldColumn = field_column(kGyroscopeFields);

using DaqEntry = FieldEntry<DaqParameters>;
constexpr std::array<DaqEntry, 5> kDaqFields{{
    {{"range_min_V", "V", "input range, lower end (count 0)"},
     &DaqParameters::range_min_V,
     Rule::kAny},
    {{"range_max_V", "V", "input range, upper end (the largest count)"},
     &DaqParameters::range_max_V,
     Rule::kAny},
    {{"resolution_bits", "bit", "converter resolution, an integer in [8, 24]"},
     &DaqParameters::resolution_bits,
     Rule::kBits},
    {{"sample_rate_hz", "Hz", "scans per second (all channels)"},
     &DaqParameters::sample_rate_hz,
     Rule::kPositive},
    {{"convert_interval_s", "s", "time between channels within a scan"},
     &DaqParameters::convert_interval_s,
     Rule::kNonNegative},
}};
constexpr auto kDaqFieldColumn = field_column(kDaqFields);

}  // namespace

std::span<const ParameterField> LoadCellParameters::fields() {
  return kLoadCellFieldColumn;
}

bool LoadCellParameters::set(std::string_view name, double value) {
  return set_field(kLoadCellFields, *this, name, value);
}

std::string LoadCellParameters::validate() const {
  return check_fields("load_cell", kLoadCellFields, *this);
}

double LoadCellParameters::volts_per_newton() const {
  return sensitivity_mV_per_V * 1e-3 * excitation_V * amplifier_gain / full_scale_N;
}

std::span<const ParameterField> InclinometerParameters::fields() {
  return kInclinometerFieldColumn;
}

bool InclinometerParameters::set(std::string_view name, double value) {
  return set_field(kInclinometerFields, *this, name, value);
}

std::string InclinometerParameters::validate() const {
  return check_fields("inclinometer", kInclinometerFields, *this);
}

double InclinometerParameters::volts_per_rad() const {
  return output_V_per_deg * kDegPerRad;
}

std::span<const ParameterField> GyroscopeParameters::fields() {
  return kGyroscopeFieldColumn;
}

bool GyroscopeParameters::set(std::string_view name, double value) {
  return set_field(kGyroscopeFields, *this, name, value);
}

std::string GyroscopeParameters::validate() const {
  return check_fields("gyroscope", kGyroscopeFields, *this);
}

double GyroscopeParameters::volts_per_rad_s() const {
  return output_V_per_dps * kDegPerRad;
}

std::span<const ParameterField> DaqParameters::fields() {
  return kDaqFieldColumn;
}

bool DaqParameters::set(std::string_view name, double value) {
  return set_field(kDaqFields, *this, name, value);
}

std::string DaqParameters::validate() const {
  std::string message = check_fields("daq", kDaqFields, *this);
  if (message.empty() && !(range_min_V < range_max_V)) {
    message = violation_message("daq", "range_min_V", range_min_V,
                                "< range_max_V = " + format_number(range_max_V));
  }
  return message;
}

std::string sample_rate_violation(std::string_view sensor, double sample_rate_hz) {
  const std::string_view broken = rule_violation(Rule::kPositive, sample_rate_hz);
  if (broken.empty()) return "";
  return violation_message(sensor, "sample_rate_hz", sample_rate_hz, broken);
}

}  // namespace doorbench
