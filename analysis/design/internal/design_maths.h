#pragma once
// The maths of the inverse design (analysis/design/ only; docs/inverse-design.md): a design
// described against AS-IS, the designs of a fit of the motion or of the commanded torques,
// the reduced Gauss–Newton system and the directions it determines least, the sparse
// search's predicted decreases, the bound check and the fewest-changes alternative, the
// ranking of equivalent designs. design_maths.cpp; used by the run's stages
// (inverse_design.cpp, sparse_search.cpp). Pure functions but for the fits they run through
// a DesignFitter; safe on any thread.
#include <Eigen/Dense>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/design/inverse_design.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/fit/fit_problem.h"

namespace doorbench::design_detail {

struct Setup {
  std::vector<int> free_index;                  // model order
  std::vector<double> as_is;                    // every parameter
  std::vector<double> scale;                    // s_i, every parameter
  std::vector<double> weight;                   // w_i, every parameter
  double significant_uncertainties = 1.0;       // a change counts when larger than these
  double significant_fraction_of_bounds = 0.0;  // (InverseDesignOptions)
};

// A design from a fit of the TO-BE motion.
DesignSolution make_solution(const FitResult& fit, const DoorModel& asis, const Setup& setup,
                             double lambda, int start_index);

// A design from the commanded torques of playback recordings: every free parameter but the
// inertia from the torque map (fit_commanded_torque), then the inertia, when free, from the
// motion with the others held. The data cost and φ are the torque fit's.
DesignSolution fit_commanded_design(const DoorModel& start,
                                    const std::vector<CommandedTorque>& commanded,
                                    const PreparedData& data, const FitOptions& fit,
                                    const DoorModel& asis, const Setup& setup, double lambda,
                                    int start_index, const std::vector<std::string>& held);

// φ: the reduced data cost, 1 when the model misses the data by their noise only.
double misfit_factor(const DesignSolution& solution);

// The reduced Gauss–Newton system (window states eliminated) of the data at `model` over
// every free parameter of `setup`, in scaled units (s_i); the priors of `fit` included when
// `with_priors`. Empty when a window cannot be evaluated.
std::optional<ReducedSystem> reduced_system(const DoorModel& model, const PreparedData& data,
                                            const FitOptions& fit, double rate_noise_rad_s,
                                            double angle_noise_rad, const Setup& setup,
                                            bool with_priors);

// The directions the data determines least, in scaled units (s_i), most poorly first: the
// eigenvectors of the information matrix H (window states eliminated, the priors
// included) with the smallest eigenvalues, at `model`. H itself rather than the fit's
// covariance: a pseudo-inverse would hide exactly the directions the data cannot see.
std::vector<Eigen::VectorXd> weak_directions(const DoorModel& model, const PreparedData& data,
                                             const FitOptions& fit, double rate_noise_rad_s,
                                             double angle_noise_rad, const Setup& setup, int count);

// Per free position of `setup`: the Gauss–Newton predicted decrease of the data's Σ r² at
// `model` when that parameter is freed beside `chosen` (free positions), from one Jacobian;
// −∞ for the chosen ones. Empty when the system cannot be evaluated.
std::vector<double> predicted_decreases(const ReducedSystem& system,
                                        const std::vector<int>& chosen);

// The largest difference between two solutions' free parameters, in scaled units.
double scaled_distance(const DesignSolution& a, const DesignSolution& b, const Setup& setup);

// Fits a design from a start model (its bounds are the fit's); the int is the start's index,
// the names are free parameters held at their start values.
using DesignFitter =
    std::function<DesignSolution(const DoorModel&, int, const std::vector<std::string>&)>;

// Whether a design's data cost is one the data cannot tell from the best: within `tolerance`
// of it, or above it by less than a hundredth of a noise level's variance per residual (so
// that exact data, whose best cost is ~0, have a usable test).
bool equivalent_cost(double cost, double best_cost, int residuals, double tolerance);

// Refits with the bounds on which `best` holds parameters moved outward by
// options.bound_widening widths and decides feasibility (see InverseDesignOptions). `held`:
// the free parameters `best` kept at AS-IS, kept so in the refit.
void check_bounds(const DoorModel& asis, const DesignFitter& fit_design,
                  const InverseDesignOptions& options, const DesignSolution& best,
                  const std::vector<std::string>& held, InverseDesignResult& result);

// The ranking of equivalent designs: fewest parts changed (weighted by their costs of
// change) first, then the smallest weighted size of the change.
void rank_solutions(std::vector<DesignSolution>& solutions);

// The fewest-changes alternative (InverseDesignOptions::fewest_changes_refits), added to
// result.solutions; the solutions are then ranked again.
void add_fewest_changes(const DoorModel& asis, const DesignFitter& fit_design,
                        const InverseDesignOptions& options, const Setup& setup, double best_cost,
                        int residuals, bool commanded_torque, InverseDesignResult& result);

}  // namespace doorbench::design_detail
