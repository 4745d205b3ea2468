#pragma once
// The named field of a JSON object, for the readers of fit and loop results
// (analysis/fit/fit_result_file.h, analysis/loop/loop_result_file.h).
// Errors: std::runtime_error "WHERE: no field 'NAME'" when the object lacks it.
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace doorbench {

// The JSON document in `path`; throws std::runtime_error "PATH: cannot open" or
// "PATH: not JSON (parser's message)".
inline nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error(path.string() + ": not JSON (" + error.what() + ")");
  }
}

inline const nlohmann::json& json_field(const nlohmann::json& object, const char* name,
                                        const std::string& where) {
  if (!object.is_object() || !object.contains(name)) {
    throw std::runtime_error(std::string(where).append(": no field '").append(name).append("'"));
  }
  return object.at(name);
}

}  // namespace doorbench
