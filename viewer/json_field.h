#pragma once
// The named field of a JSON object, for the viewer's readers of fit and loop results.
// Errors: std::runtime_error "WHERE: no field 'NAME'" when the object lacks it.
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace doorbench::viewer {

inline const nlohmann::json& json_field(const nlohmann::json& object, const char* name,
                                        const std::string& where) {
  if (!object.is_object() || !object.contains(name)) {
    throw std::runtime_error(std::string(where).append(": no field '").append(name).append("'"));
  }
  return object.at(name);
}

}  // namespace doorbench::viewer
