#pragma once
// A small unconstrained minimiser for the study's likelihoods (ratings, thresholds): damped
// Newton steps (Levenberg–Marquardt damping of the Hessian), on the gradient and Hessian the
// objective supplies (thresholds: analytic) or on central differences (ratings). Meant for a
// handful to a few dozen parameters and smooth objectives; the objective may return +inf or
// NaN where it is undefined, which rejects the step.
// Internal to study/statistics (not part of any verb's interface).
// Thread safety: free functions without shared state; `f` is called from the caller's thread.
#include <Eigen/Dense>
#include <functional>

namespace doorbench::study::statistics {

using Objective = std::function<double(const Eigen::VectorXd&)>;

// The objective's value, gradient and Hessian at a point (the last two may be left empty
// where the value is not finite).
struct Derivatives {
  double value = 0.0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian;
};
using DerivativeObjective = std::function<Derivatives(const Eigen::VectorXd&)>;

struct MinimizeOptions {
  int max_iterations = 200;
  double gradient_tolerance = 1e-8;  // stop when max |gradient| falls below (absolute)
  double step_tolerance = 1e-11;     // or when a step moves every coordinate less than this
};

struct MinimizeResult {
  Eigen::VectorXd x;
  double value = 0.0;
  int iterations = 0;
  bool converged = false;
};

// Central-difference gradient and Hessian at x with steps h_i = step * max(1, |x_i|).
Eigen::VectorXd numeric_gradient(const Objective& f, const Eigen::VectorXd& x, double step = 1e-6);
Eigen::MatrixXd numeric_hessian(const Objective& f, const Eigen::VectorXd& x, double step = 1e-4);

// Minimises f from x0, its derivatives by central differences. Throws std::invalid_argument
// when f(x0) is not finite.
MinimizeResult minimize(const Objective& f, Eigen::VectorXd x0,
                        const MinimizeOptions& options = {});

// The same on the derivatives f supplies (two evaluations per accepted step at most: the
// candidate's value comes with its derivatives for the next step).
MinimizeResult minimize(const DerivativeObjective& f, Eigen::VectorXd x0,
                        const MinimizeOptions& options = {});

}  // namespace doorbench::study::statistics
