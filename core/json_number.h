#pragma once
// A number for a JSON file: a finite value as itself, NaN or an infinity as null (JSON has no
// NaN; a reader sees "not computed" rather than a parse error). For both of nlohmann's
// object kinds: json_number(x) is an nlohmann::json, json_number<nlohmann::ordered_json>(x)
// keeps its writer's key order. An empty optional is null too.
// Pure functions: safe from any thread.
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

namespace doorbench {

template <class Json = nlohmann::json>
Json json_number(double value) {
  return std::isfinite(value) ? Json(value) : Json(nullptr);
}

template <class Json = nlohmann::json>
Json json_number(const std::optional<double>& value) {
  return value ? json_number<Json>(*value) : Json(nullptr);
}

}  // namespace doorbench
