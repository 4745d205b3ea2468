#pragma once
// The residual examination with the fit options of the model under examination
// (analysis/loop/ only): examine_residual() with `fit` in place of options.fit, for the
// loop, whose current model was fitted with options of its own. Options not validated.
#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"

namespace doorbench::loop_detail {

ResidualExamination examine(const DoorModel& model, const PreparedData& data,
                            const LoopOptions& options, const FitOptions& fit);

}  // namespace doorbench::loop_detail
