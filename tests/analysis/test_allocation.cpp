// Evaluating a door model never allocates (door_model.h's promise): the count of
// tests/support/allocation_counter.h across many evaluations.
#include <ceres/jet.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "tests/support/allocation_counter.h"

using doorbench::testing::allocations;

namespace {

using doorbench::DoorModel;
using doorbench::ModelKind;

DoorModel with_effects(ModelKind kind, const char* json) {
  DoorModel model = doorbench::reference_model(kind);
  for (auto& setting : doorbench::parse_effects_file(json, "effects.json")) {
    model = model.with_effect(std::move(setting));
  }
  return model;
}

// Every effect of the catalogue switched on.
constexpr const char* kAllEffects = R"({
  "viscous_damping": {"b": 0.3}, "gravity_imbalance": {"g1": 1.5},
  "stribeck": {"d_s": 3.4, "w_s": 0.04}, "direction_friction": {"d_dir": 0.5},
  "soft_close": {"b_sc": 4, "theta_sc": 0.05, "beta_sc": 40},
  "end_stop": {"k_e": 800, "theta_e": 1.4, "beta_e": 300},
  "force_offset": {"F_off": 1.2}, "inertia_error": {"delta_J": 0.1}})";

// Sums what it is given so that the evaluations cannot be optimised away.
volatile double g_sink = 0.0;

// Makes a pointer escape so that the compiler cannot elide a new/delete pair.
void escape(void* pointer) {
  asm volatile("" : : "g"(pointer) : "memory");
}

// The allocations made by 1000 evaluations of `model` by each entry point, across
// the stroke (θ from −0.02 to 1.6) and both directions.
struct Counts {
  long long torque = 0, torque_with_terms = 0, derivatives = 0, jet = 0, inertia = 0;
};

Counts count_evaluations(const DoorModel& model) {
  Counts counts;
  auto theta_at = [](int i) { return -0.02 + 1.62 * i / 999.0; };
  auto omega_at = [](int i) { return (i % 2 == 0 ? 1.0 : -1.0) * (0.001 + 0.002 * (i % 500)); };
  double sum = 0.0;

  long long before = allocations();
  for (int i = 0; i < 1000; ++i) sum += model.torque_Nm(theta_at(i), omega_at(i));
  counts.torque = allocations() - before;

  std::array<double, DoorModel::kMaxTerms> terms{};
  before = allocations();
  for (int i = 0; i < 1000; ++i) sum += model.torque_Nm(theta_at(i), omega_at(i), terms);
  counts.torque_with_terms = allocations() - before;

  before = allocations();
  for (int i = 0; i < 1000; ++i) {
    const doorbench::TorqueDerivatives d = model.torque_derivatives(theta_at(i), omega_at(i));
    sum += d.torque_Nm + d.dtorque_dtheta_Nm_per_rad + d.dtorque_domega_Nm_s_per_rad;
  }
  counts.derivatives = allocations() - before;

  // The generic evaluation with parameter Jets, as a fit would use it.
  using Jet = ceres::Jet<double, 4>;
  std::array<Jet, DoorModel::kMaxParameters> parameters;
  std::array<Jet, DoorModel::kMaxTerms> jet_terms;
  before = allocations();
  for (int i = 0; i < 1000; ++i) {
    for (int p = 0; p < model.parameter_count(); ++p) {
      parameters[p] = Jet(model.parameter_values()[p]);
    }
    for (int k = 0; k < 4; ++k) parameters[k].v[k] = 1.0;
    const Jet t =
        model.evaluate(parameters.data(), Jet(theta_at(i)), Jet(omega_at(i)), jet_terms.data());
    sum += t.a + t.v[0];
  }
  counts.jet = allocations() - before;

  before = allocations();
  for (int i = 0; i < 1000; ++i) sum += model.inertia_kg_m2();
  counts.inertia = allocations() - before;

  g_sink = g_sink + sum;
  return counts;
}

void check_no_allocations(const DoorModel& model) {
  const Counts counts = count_evaluations(model);
  CHECK(counts.torque == 0);
  CHECK(counts.torque_with_terms == 0);
  CHECK(counts.derivatives == 0);
  CHECK(counts.jet == 0);
  CHECK(counts.inertia == 0);
}

}  // namespace

TEST_CASE("Allocation: the counter sees allocations", "[allocation]") {
  // Building a model fills vectors of values and names: the counter must notice.
  const long long before = allocations();
  const DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  CHECK(allocations() > before);
  // And each form of new is counted.
  const long long start = allocations();
  auto* plain = new std::vector<double>(8, 1.0);  // the object and its buffer: 2
  auto* array = new double[16];
  auto* nothrow = new (std::nothrow) double(2.0);
  struct alignas(64) Wide {
    double x[8];
  };
  auto* aligned = new Wide{};
  for (void* pointer : {static_cast<void*>(plain), static_cast<void*>(array),
                        static_cast<void*>(nothrow), static_cast<void*>(aligned)}) {
    escape(pointer);
  }
  CHECK(allocations() - start == 5);
  delete aligned;
  delete nothrow;
  delete[] array;
  delete plain;
  CHECK(model.term_count() == 5);
}

TEST_CASE("Allocation: evaluating the sensory model allocates nothing", "[allocation]") {
  check_no_allocations(doorbench::reference_model(ModelKind::kSensory));
  check_no_allocations(with_effects(ModelKind::kSensory, kAllEffects));
}

TEST_CASE("Allocation: evaluating the physical model allocates nothing", "[allocation]") {
  check_no_allocations(doorbench::reference_model(ModelKind::kPhysical));
  check_no_allocations(with_effects(ModelKind::kPhysical, kAllEffects));
}
