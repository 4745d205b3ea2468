#pragma once
// Start values and bounds taken from a recording, for a door that is not the reference door
// (docs/fitting.md, "Start values from the data"). Sensory model only; the base model (the
// reference door, with the recording's geometry) supplies what the data do not give.
//
// With y = r_h F (the hand's torque) and α = dω/dt (central differences over
// ±max(5 ms, 1.5 sample intervals)), over the samples of free motion (moving: |ω| above
// max(3 σ_ω, 0.02 rad/s); above the latch region: θ > max(0.12 rad, 2 θ3 of the base)):
//
//   y = J α + d_open tanh(s ω) [θ > θ4] + d_near tanh(s ω) [θ <= θ4] + g1 sin θ + b
//
// by least squares gives the inertia J (force against acceleration), the dry friction when
// open d1 = d_open and its reduction near closed d2 = d_open − d_near (force at speed), the
// balance torque g1 (a door on a tilted or sprung hinge; the sensory model has no such term:
// it is reported, and the residual loop's gravity_imbalance adds it) and a constant b (a load
// cell that was not tared reads F + b / r_h; the loop's force_offset adds it). s and θ4 are
// the base's. Then the latch (θ0…θ3, k_inf, k_lock) is read off the force–angle curves near
// closed with that J (analysis/fit/fit_start.h). Bounds are widened around every value taken from
// the data: J within [J/4, 4 J], friction up to 5 × d1, latch angles within [x/2, 2 x] (below
// θ_max), latch stiffnesses up to 4 ×.
//
// Thread safety: a free function without shared state.
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

struct DataStart {
  DoorModel model;  // the start: values and bounds; every constraint holds
  // Per base parameter, where its start came from: "free motion", "latch read-off" or
  // "reference door".
  std::vector<std::string> origin;
  int free_motion_samples = 0;     // samples in the regression (0: not used)
  double balance_torque_Nm = 0.0;  // g1
  double force_offset_N = 0.0;     // b / r_h
  std::vector<std::string> notes;  // what was not taken from the data, and why
};

// Throws std::invalid_argument when `base` is not a sensory model or `data` has no strokes.
DataStart start_from_data(const PreparedData& data, const DoorModel& base);

}  // namespace doorbench
