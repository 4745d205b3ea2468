#pragma once
// The global stage's scale of a parameter's bounds (docs/fitting.md, "The global stage", step
// 2): the scale its sample spreads points on and its hops step on, for anyone who shows where
// a value lies within its bounds. Pure functions, safe on any thread.
#include "analysis/model/parameters.h"

namespace doorbench {

// True where the stage spreads a parameter with these bounds logarithmically: bounds spanning
// more than two decades from a lower bound >= 0 (the stiffnesses), then over
// [max(lower, upper / 1000), upper].
bool search_scale_is_logarithmic(const Bounds& bounds);

// Where `value` lies within `bounds` on that scale: 0 at the lower end, 1 at the upper,
// clamped to [0, 1] (a value below the logarithmic scale's lower end is 0).
double search_scale_place(const Bounds& bounds, double value);

}  // namespace doorbench
