// The NI scaling of TDMS channels (acquisition/session/internal/tdms_scaling.h): linear and
// polynomial scales, chained by scale id, over a channel's raw values or a DAQmx channel's
// scalers' raw values (docs/tdms.md).
#include "acquisition/session/internal/tdms_scaling.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

namespace doorbench::tdms_detail {
namespace {

// What a channel's scales read: its raw value, or a DAQmx channel's scalers' raw values (by
// scale id) at one sample.
struct ScaleInputs {
  double raw = 0.0;
  const std::map<std::uint32_t, std::vector<double>>* daqmx = nullptr;
  std::size_t sample = 0;
};

// The channel's scaling (NI_Scaling_Status "unscaled"): scale NI_Number_Of_Scales − 1,
// whose input source is another scale's index or the raw data (−1, absent). In a DAQmx
// channel, a scale without a Scale_Type is the scaler of that scale id.
double scale_value(const std::map<std::string, TdmsProperty>& p, int scale, const ScaleInputs& in,
                   int depth, const std::string& where) {
  if (scale < 0) {
    if (in.daqmx) {
      throw TdmsError(where +
                      ": a scale reads the raw data, which a DAQmx channel has only "
                      "through its scalers");
    }
    return in.raw;
  }
  if (depth > 16) throw TdmsError(where + ": the scales' input sources form a loop");
  const std::string prefix = "NI_Scale[" + std::to_string(scale) + "]_";
  const auto type = p.find(prefix + "Scale_Type");
  if (type == p.end()) {
    if (in.daqmx) {
      if (const auto it = in.daqmx->find(static_cast<std::uint32_t>(scale));
          it != in.daqmx->end()) {
        return it->second[in.sample];
      }
    }
    throw TdmsError(where + ": " + prefix + "Scale_Type is missing");
  }
  auto number = [&](const std::string& name) {
    const auto it = p.find(prefix + name);
    if (it == p.end() || !it->second.number) {
      throw TdmsError(where + ": " + prefix + name + " is missing or not a number");
    }
    return *it->second.number;
  };
  auto input = [&](const std::string& kind) {
    const auto it = p.find(prefix + kind + "_Input_Source");
    if (it == p.end() || !it->second.number) return -1;
    const double source = *it->second.number;
    return source >= 4294967295.0 || source < 0 ? -1 : static_cast<int>(source);
  };
  if (type->second.text == "Linear") {
    const double x = scale_value(p, input("Linear"), in, depth + 1, where);
    return number("Linear_Slope") * x + number("Linear_Y_Intercept");
  }
  if (type->second.text == "Polynomial") {
    const double x = scale_value(p, input("Polynomial"), in, depth + 1, where);
    const int size = static_cast<int>(number("Polynomial_Coefficients_Size"));
    double sum = 0.0;
    for (int k = size - 1; k >= 0; --k) {
      sum = sum * x + number("Polynomial_Coefficients[" + std::to_string(k) + "]");
    }
    return sum;
  }
  throw TdmsError(where + ": " + prefix + "Scale_Type '" + type->second.text +
                  "' is not supported (Linear and Polynomial are)");
}

// How many scales a channel has: NI_Number_Of_Scales, else (DAQmx files may leave it out)
// one more than the highest k of an NI_Scale[k]_Scale_Type; 0 when neither.
int number_of_scales(const TdmsChannel& channel) {
  const auto count = channel.properties.find("NI_Number_Of_Scales");
  if (count != channel.properties.end() && count->second.number) {
    return std::max(0, static_cast<int>(*count->second.number));
  }
  if (channel.daqmx_raw.empty()) return 0;
  int scales = 0;
  for (const auto& [name, value] : channel.properties) {
    int k = -1;
    char rest[16] = {};
    if (std::sscanf(name.c_str(), "NI_Scale[%d]_Scale_Typ%15s", &k, rest) == 2 &&
        std::string(rest) == "e") {
      scales = std::max(scales, k + 1);
    }
  }
  return scales;
}

}  // namespace

void apply_scaling(TdmsChannel& channel, const std::string& source) {
  const bool daqmx = !channel.daqmx_raw.empty();
  const auto status = channel.properties.find("NI_Scaling_Status");
  const bool unscaled = status != channel.properties.end() && status->second.text == "unscaled";
  const int scales = number_of_scales(channel);
  const std::string where = source + ": channel " + channel.group + "/" + channel.name;
  if (daqmx && (scales < 1 || (!unscaled && status != channel.properties.end()))) {
    // No scales: the one scaler's raw values, as stored.
    if (channel.daqmx_raw.size() != 1) {
      throw TdmsError(where + ": DAQmx raw data with " + std::to_string(channel.daqmx_raw.size()) +
                      " scalers and no NI_Scale properties to combine them");
    }
    channel.values = channel.daqmx_raw.begin()->second;
    channel.scaling = "DAQmx scaler " + std::to_string(channel.daqmx_raw.begin()->first) + " (raw)";
    return;
  }
  if (!unscaled && !daqmx) return;
  if (scales < 1) return;
  const int last = scales - 1;
  ScaleInputs in;
  if (daqmx) {
    in.daqmx = &channel.daqmx_raw;
    channel.values.assign(channel.daqmx_raw.begin()->second.size(), 0.0);
  }
  for (std::size_t i = 0; i < channel.values.size(); ++i) {
    in.raw = channel.values[i];
    in.sample = i;
    channel.values[i] = scale_value(channel.properties, last, in, 0, where);
  }
  const auto type = channel.properties.find("NI_Scale[" + std::to_string(last) + "]_Scale_Type");
  channel.scaling = "NI_Scale[" + std::to_string(last) + "] (" +
                    (type != channel.properties.end() ? type->second.text : "DAQmx scaler") + ")";
}

}  // namespace doorbench::tdms_detail
