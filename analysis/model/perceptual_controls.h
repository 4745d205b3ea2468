#pragma once
// The perceptual controls of door-models.md §2: sensations an operator tunes, each a
// documented map onto the sensory model's parameters. Reading a control never fails;
// setting one returns a new, validated model (std::invalid_argument when the wish
// cannot be met, with a message saying why).
//
//  control            unit     reads                         setting changes
//  heaviness          kg*m^2   J                             J
//  latch_effort       N        (k θ1 + k_inf (θ1 − θ0))/r_h  k_inf (θ0, θ1 kept)
//  closing_effort     N        k_lock (θ3 − θ2)/r_h          k_lock
//  snap               N*m*s    c (θ2 − θ1): the angular      c (the width kept); the width
//                              momentum the snap zone adds   itself via set_snap_width
//  smoothness         N        d1 / r_h: dry friction felt   d1 and d2 (d2/d1 kept)
//                              at the handle when open
//  friction_balance   1        d2 / d1: how much lighter     d2 (d1 kept)
//                              the door runs near closed
//  friction_change    rad      θ4                            θ4
#include <array>
#include <optional>
#include <string_view>

#include "analysis/model/door_model.h"

namespace doorbench::perceptual {

enum class Control {
  kHeaviness,
  kLatchEffort,
  kClosingEffort,
  kSnap,
  kSmoothness,
  kFrictionBalance,
  kFrictionChange,
};

struct ControlInfo {
  Control control;
  std::string_view name;
  std::string_view unit;
  std::string_view meaning;
};

std::span<const ControlInfo> controls();
std::optional<Control> find(std::string_view name);

// Both take a sensory model (std::invalid_argument otherwise).
double read(const DoorModel& model, Control control);
DoorModel set(const DoorModel& model, Control control, double value);

// The snap zone's width θ2 − θ1 (rad); setting it moves θ2 and keeps c.
double snap_width_rad(const DoorModel& model);
DoorModel set_snap_width(const DoorModel& model, double width_rad);

}  // namespace doorbench::perceptual
