#pragma once
// What every model parameter carries: a name, a unit, a meaning, a value and fit bounds.
#include <string>
#include <string_view>

namespace doorbench {

struct ParameterInfo {
  std::string_view name;
  std::string_view unit;
  std::string_view meaning;
};

struct Bounds {
  double lower = 0.0;
  double upper = 0.0;
};

// The door's geometry, from the top level of a door file. Not fitted.
struct DoorGeometry {
  double handle_radius_m = 0.0;  // hinge axis to where the hand pushes
  double theta_max_rad = 0.0;    // fully open
};

// Empty when the geometry is usable, else a one-line message naming the field.
std::string validate_geometry(const DoorGeometry& geometry);

}  // namespace doorbench
