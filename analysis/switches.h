#pragma once
// The smooth switches of door-models.md §1, templated on the scalar so that Ceres'
// Jets flow through them. All arguments share one scalar type T.
#include <cmath>

namespace doorbench {

// S(x; x0, β) = ½ (1 + tanh(β (x − x0))): about 0 below x0, about 1 above.
template <typename T>
T switch_on(const T& x, const T& x0, const T& beta) {
  using std::tanh;
  return T(0.5) * (T(1.0) + tanh(beta * (x - x0)));
}

// S̄(x; x0, β) = 1 − S(x; x0, β).
template <typename T>
T switch_off(const T& x, const T& x0, const T& beta) {
  using std::tanh;
  return T(0.5) * (T(1.0) - tanh(beta * (x - x0)));
}

// W(x; a, b, β) = S(x; a, β) − S(x; b, β): about 1 for a < x < b, about 0 outside.
template <typename T>
T window(const T& x, const T& a, const T& b, const T& beta) {
  return switch_on(x, a, beta) - switch_on(x, b, beta);
}

// The logistic function 1 / (1 + exp(−u)), in the form that neither overflows nor
// loses relative accuracy in either tail.
template <typename T>
T logistic(const T& u) {
  using std::exp;
  if (u >= T(0.0)) return T(1.0) / (T(1.0) + exp(-u));
  const T exp_u = exp(u);
  return exp_u / (T(1.0) + exp_u);
}

// softplus_e(z) = e ln(1 + exp(z/e)), in the form max(z, 0) + e ln(1 + exp(−|z|/e))
// that is exact in real arithmetic and never overflows.
template <typename T>
T softplus(const T& z, const T& e) {
  using std::abs;
  using std::exp;
  using std::log1p;
  // ">=" so that a Jet at exactly z = 0 gets the slope ½ (|z| differentiates as +z there).
  const T positive_part = z >= T(0.0) ? z : T(0.0);
  return positive_part + e * log1p(exp(-abs(z) / e));
}

// softmin_e(a, b) = −e ln(exp(−a/e) + exp(−b/e)) = min(a, b) − e ln(1 + exp(−|a − b|/e)).
template <typename T>
T softmin(const T& a, const T& b, const T& e) {
  using std::abs;
  using std::exp;
  using std::log1p;
  const T smaller = a < b ? a : b;
  return smaller - e * log1p(exp(-abs(a - b) / e));
}

}  // namespace doorbench
