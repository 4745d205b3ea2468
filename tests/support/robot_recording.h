#pragma once
// The 50 Hz, 4-stroke robot recording with an untared load cell (fixtures/'
// robot_operator_conditions(), seed 42, the handle at 0.8 m), prepared; the recording family's
// draws at one rate; and the start `doorbench fit` takes on them without --params: the
// reference door with the recording's radius, its values taken from the data.
#include <cstdint>

#include "analysis/fit/fit_init.h"
#include "fixtures/recording_family.h"
#include "fixtures/reference_doors.h"

namespace doorbench::testing {

// The door the robot recording is made with: the sensory reference door, the handle at 0.8 m.
inline DoorModel robot_door() {
  return with_handle_radius(sensory_reference(), 0.8);
}

inline PreparedData robot_recording() {
  return family_recording(robot_door(), robot_operator_conditions(), 42);
}

// Draw `seed` of the recording family (12 strokes) at one sample rate, as doorbench_fit_study
// draws it: the seed is the draw's conditions' and its recording's.
inline PreparedData family_draw(std::uint32_t seed, double rate_hz) {
  FamilyOptions family;
  family.sample_rates_hz = {rate_hz};
  return family_recording(sensory_reference(), draw_conditions(seed, family), seed);
}

// The start `doorbench fit` takes without --params on any recording of the sensory family.
inline DoorModel fit_start_read_off(const PreparedData& data) {
  return start_from_data(data, with_handle_radius(sensory_reference(), data.handle_radius_m)).model;
}

inline DoorModel robot_fit_start(const PreparedData& data) {
  return fit_start_read_off(data);
}

}  // namespace doorbench::testing
