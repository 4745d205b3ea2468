#pragma once
// The 50 Hz, 4-stroke robot recording with an untared load cell (fixtures/'
// robot_operator_conditions(), seed 42, the handle at 0.8 m), prepared, and the start
// `doorbench fit` takes on it without --params: the reference door with the recording's radius,
// its values taken from the data.
#include "analysis/fit/fit_init.h"
#include "fixtures/recording_family.h"
#include "fixtures/reference_doors.h"

namespace doorbench::testing {

inline PreparedData robot_recording() {
  const DoorModel door = with_handle_radius(sensory_reference(), 0.8);
  return family_recording(door, robot_operator_conditions(), 42);
}

// The start `doorbench fit` takes without --params on any recording of the sensory family.
inline DoorModel fit_start_read_off(const PreparedData& data) {
  return start_from_data(data, with_handle_radius(sensory_reference(), data.handle_radius_m)).model;
}

inline DoorModel robot_fit_start(const PreparedData& data) {
  return fit_start_read_off(data);
}

}  // namespace doorbench::testing
