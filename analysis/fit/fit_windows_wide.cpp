// The window cost with Jets of 24 derivative parts (a loop's refits: 17-19 free parameters
// and window states), in a translation unit of its own (analysis/fit/internal/window_residual.h).
#include "analysis/fit/internal/window_residual.h"

namespace doorbench::fit_detail {

ceres::CostFunction* make_wide_window_cost(const WindowResidualSetup& setup,
                                           const FitWindow& window) {
  return make_cost<24>(setup, window);
}

}  // namespace doorbench::fit_detail
