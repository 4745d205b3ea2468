#pragma once
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/virtual_hand.h"

namespace doorbench::app {

// The model opened and closed by the virtual hand, sampled at output_rate_hz from t = 0,
// with the hand's strokes marked.
Trajectory simulate_hand(const DoorModel& model, const VirtualHandOptions& hand_options,
                         double output_rate_hz);

}  // namespace doorbench::app
