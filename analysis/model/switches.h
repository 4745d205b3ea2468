#pragma once
// The smooth switches of door-models.md §1, templated on the scalar so that Ceres'
// Jets flow through them. All arguments share one scalar type T.
#include <cmath>

namespace doorbench {

// exp(−x) for x ≥ 0: exactly std::exp's value (and a Jet's exp's), but 0 without calling it
// where it is 0 anyway (x beyond 746). Sharp switches far from their step ask for exp(−2000)
// all the time, and glibc's exp takes a slow path (errno) for every result that underflows.
template <typename T>
T exp_minus(const T& x) {
  using std::exp;
  if (x > T(746.0)) return T(0.0);
  return exp(-x);
}

// The logistic function 1 / (1 + exp(−u)), in the form that neither overflows nor
// loses relative accuracy in either tail.
// The tail's exponential is exp_minus: the latch's sharp switches ask for logistic(±2000).
template <typename T>
T logistic(const T& u) {
  if (u >= T(0.0)) return T(1.0) / (T(1.0) + exp_minus(u));
  const T exp_u = exp_minus(-u);
  return exp_u / (T(1.0) + exp_u);
}

// S and S̄ at one point, each with full relative accuracy, from a single exponential.
// (½ (1 + tanh u) would cancel catastrophically for u ≪ 0 and leave tails, and torques
// that are sums of tails, with few correct digits.)
template <typename T>
struct SwitchValues {
  T on;   // S(x; x0, β) = ½ (1 + tanh(β (x − x0))): about 0 below x0, about 1 above
  T off;  // S̄(x; x0, β) = 1 − S
};

template <typename T>
SwitchValues<T> switch_values(const T& x, const T& x0, const T& beta) {
  using std::abs;
  using std::exp;
  // S = logistic(u) with u = 2β (x − x0), identical to ½ (1 + tanh(β (x − x0))).
  const T u = T(2.0) * beta * (x - x0);
  const T tail = exp_minus(abs(u));
  const T large = T(1.0) / (T(1.0) + tail);
  const T small = tail * large;
  if (u >= T(0.0)) return {large, small};
  return {small, large};
}

template <typename T>
T switch_on(const T& x, const T& x0, const T& beta) {
  return switch_values(x, x0, beta).on;
}

template <typename T>
T switch_off(const T& x, const T& x0, const T& beta) {
  return switch_values(x, x0, beta).off;
}

// W(x; a, b, β) = S(x; a) − S(x; b) from the switches at a and b. Above the middle it is
// the identical S̄(x; b) − S̄(x; a): a difference of two small tails, not of two numbers
// close to 1.
template <typename T>
T window(const T& x, const T& a, const T& b, const SwitchValues<T>& at_a,
         const SwitchValues<T>& at_b) {
  if (x + x > a + b) return at_b.off - at_a.off;
  return at_a.on - at_b.on;
}

// W(x; a, b, β): about 1 for a < x < b, about 0 outside.
template <typename T>
T window(const T& x, const T& a, const T& b, const T& beta) {
  return window(x, a, b, switch_values(x, a, beta), switch_values(x, b, beta));
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
  return positive_part + e * log1p(exp_minus(abs(z) / e));
}

// softmin_e(a, b) = −e ln(exp(−a/e) + exp(−b/e)) = min(a, b) − e ln(1 + exp(−|a − b|/e)).
template <typename T>
T softmin(const T& a, const T& b, const T& e) {
  using std::abs;
  using std::exp;
  using std::log1p;
  const T smaller = a < b ? a : b;
  return smaller - e * log1p(exp_minus(abs(a - b) / e));
}

}  // namespace doorbench
