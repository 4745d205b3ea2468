#include "study/statistics/numeric_minimize.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace doorbench::study::statistics {
namespace {

double step_for(double x, double step) {
  return step * std::max(1.0, std::abs(x));
}

}  // namespace

Eigen::VectorXd numeric_gradient(const Objective& f, const Eigen::VectorXd& x, double step) {
  Eigen::VectorXd gradient(x.size());
  Eigen::VectorXd probe = x;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double h = step_for(x[i], step);
    probe[i] = x[i] + h;
    const double up = f(probe);
    probe[i] = x[i] - h;
    const double down = f(probe);
    probe[i] = x[i];
    gradient[i] = (up - down) / (2.0 * h);
  }
  return gradient;
}

Eigen::MatrixXd numeric_hessian(const Objective& f, const Eigen::VectorXd& x, double step) {
  const Eigen::Index n = x.size();
  Eigen::MatrixXd hessian(n, n);
  Eigen::VectorXd probe = x;
  const double centre = f(x);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double hi = step_for(x[i], step);
    probe[i] = x[i] + hi;
    const double up = f(probe);
    probe[i] = x[i] - hi;
    const double down = f(probe);
    probe[i] = x[i];
    hessian(i, i) = (up - 2.0 * centre + down) / (hi * hi);
    for (Eigen::Index j = 0; j < i; ++j) {
      const double hj = step_for(x[j], step);
      double sum = 0.0;
      for (const auto& [si, sj] : {std::pair{1.0, 1.0}, {1.0, -1.0}, {-1.0, 1.0}, {-1.0, -1.0}}) {
        probe[i] = x[i] + si * hi;
        probe[j] = x[j] + sj * hj;
        sum += si * sj * f(probe);
      }
      probe[i] = x[i];
      probe[j] = x[j];
      hessian(i, j) = hessian(j, i) = sum / (4.0 * hi * hj);
    }
  }
  return hessian;
}

namespace {

// The objective as the Newton loop sees it: the value at any point, the gradient and the
// Hessian at the accepted points.
struct NewtonModel {
  std::function<double(const Eigen::VectorXd&)> value;
  std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&, Eigen::MatrixXd&)> derivatives;
};

MinimizeResult damped_newton(const NewtonModel& model, Eigen::VectorXd x0,
                             const MinimizeOptions& options) {
  MinimizeResult result;
  result.x = std::move(x0);
  result.value = model.value(result.x);
  if (!std::isfinite(result.value)) {
    throw std::invalid_argument("minimize: the objective is not finite at the start");
  }
  double damping = 1e-3;
  const Eigen::Index n = result.x.size();
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian;
  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    model.derivatives(result.x, gradient, hessian);
    if (gradient.lpNorm<Eigen::Infinity>() < options.gradient_tolerance) {
      result.converged = true;
      return result;
    }
    // The damped system is made positive definite by raising the damping until Cholesky works
    // and the step lowers the objective.
    bool moved = false;
    for (int attempt = 0; attempt < 60 && !moved; ++attempt) {
      Eigen::MatrixXd damped = hessian;
      const double scale = std::max(1.0, hessian.diagonal().cwiseAbs().maxCoeff());
      damped.diagonal().array() += damping * scale;
      Eigen::LLT<Eigen::MatrixXd> llt(damped);
      if (llt.info() != Eigen::Success) {
        damping *= 10.0;
        continue;
      }
      const Eigen::VectorXd step = llt.solve(-gradient);
      const Eigen::VectorXd candidate = result.x + step;
      const double value = model.value(candidate);
      if (std::isfinite(value) && value <= result.value) {
        const bool small = (step.array().abs() < options.step_tolerance).all();
        result.x = candidate;
        const double gain = result.value - value;
        result.value = value;
        damping = std::max(damping / 10.0, 1e-12);
        moved = true;
        if (small || (gain == 0.0 && n > 0)) {
          result.converged = gradient.lpNorm<Eigen::Infinity>() < 1e3 * options.gradient_tolerance;
          return result;
        }
      } else {
        damping *= 10.0;
      }
    }
    if (!moved) {
      result.converged = gradient.lpNorm<Eigen::Infinity>() < 1e3 * options.gradient_tolerance;
      return result;
    }
  }
  return result;
}

}  // namespace

MinimizeResult minimize(const Objective& f, Eigen::VectorXd x0, const MinimizeOptions& options) {
  const NewtonModel model{
      f, [&f](const Eigen::VectorXd& x, Eigen::VectorXd& gradient, Eigen::MatrixXd& hessian) {
        gradient = numeric_gradient(f, x);
        hessian = numeric_hessian(f, x);
      }};
  return damped_newton(model, std::move(x0), options);
}

MinimizeResult minimize(const DerivativeObjective& f, Eigen::VectorXd x0,
                        const MinimizeOptions& options) {
  // The value at a candidate comes with its derivatives: kept for the step from it.
  Eigen::VectorXd cached_at;
  Derivatives cached;
  bool have = false;
  const auto at = [&](const Eigen::VectorXd& x) -> const Derivatives& {
    if (!have || cached_at.size() != x.size() || cached_at != x) {
      cached = f(x);
      cached_at = x;
      have = true;
    }
    return cached;
  };
  const NewtonModel model{
      [&at](const Eigen::VectorXd& x) { return at(x).value; },
      [&at](const Eigen::VectorXd& x, Eigen::VectorXd& gradient, Eigen::MatrixXd& hessian) {
        const Derivatives& d = at(x);
        gradient = d.gradient;
        hessian = d.hessian;
      }};
  return damped_newton(model, std::move(x0), options);
}

}  // namespace doorbench::study::statistics
