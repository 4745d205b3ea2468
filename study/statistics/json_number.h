#pragma once
// A number for analysis.json: a finite value as itself, NaN or an infinity as null (JSON has
// no NaN). Used by every statistic's JSON writer.
#include <cmath>

#include <nlohmann/json.hpp>

namespace doorbench::study {

inline nlohmann::json json_number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace doorbench::study
