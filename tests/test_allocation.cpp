// Evaluating a door model never allocates (door_model.h's promise). This file replaces
// the global operator new/delete for the whole test binary with versions that forward
// to malloc/free and only count, then checks the count across many evaluations.
#include <ceres/jet.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#include "analysis/door_model.h"
#include "analysis/parameter_file.h"
#include "tests/allocation_counter.h"

namespace {

std::atomic<long long> g_allocations{0};

void* counted_malloc(std::size_t size) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}

void* counted_aligned_malloc(std::size_t size, std::align_val_t alignment) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  std::size_t align = static_cast<std::size_t>(alignment);
  if (align < sizeof(void*)) align = sizeof(void*);
  // aligned_alloc wants a size that is a multiple of the alignment.
  const std::size_t rounded = size == 0 ? align : (size + align - 1) / align * align;
  return std::aligned_alloc(align, rounded);
}

void* or_throw(void* pointer) {
  if (pointer == nullptr) throw std::bad_alloc();
  return pointer;
}

// Kept out of line: inlined into a delete-expression, a direct free() makes g++ -O2 warn
// (-Wmismatched-new-delete) although the pair is right.
[[gnu::noinline]] void release(void* pointer) noexcept {
  std::free(pointer);
}

}  // namespace

namespace doorbench::testing {
long long allocations() {
  return g_allocations.load(std::memory_order_relaxed);
}
}  // namespace doorbench::testing

using doorbench::testing::allocations;

// The replaceable allocation functions ([new.delete]): plain, array, nothrow, aligned.
void* operator new(std::size_t size) {
  return or_throw(counted_malloc(size));
}
void* operator new[](std::size_t size) {
  return or_throw(counted_malloc(size));
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return counted_malloc(size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return counted_malloc(size);
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  return or_throw(counted_aligned_malloc(size, alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return or_throw(counted_aligned_malloc(size, alignment));
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return counted_aligned_malloc(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return counted_aligned_malloc(size, alignment);
}

// The matching deallocation functions, all forwarding to free (aligned_alloc's memory
// is released with free too).
void operator delete(void* pointer) noexcept {
  release(pointer);
}
void operator delete[](void* pointer) noexcept {
  release(pointer);
}
void operator delete(void* pointer, std::size_t) noexcept {
  release(pointer);
}
void operator delete[](void* pointer, std::size_t) noexcept {
  release(pointer);
}
void operator delete(void* pointer, const std::nothrow_t&) noexcept {
  release(pointer);
}
void operator delete[](void* pointer, const std::nothrow_t&) noexcept {
  release(pointer);
}
void operator delete(void* pointer, std::align_val_t) noexcept {
  release(pointer);
}
void operator delete[](void* pointer, std::align_val_t) noexcept {
  release(pointer);
}
void operator delete(void* pointer, std::size_t, std::align_val_t) noexcept {
  release(pointer);
}
void operator delete[](void* pointer, std::size_t, std::align_val_t) noexcept {
  release(pointer);
}
void operator delete(void* pointer, std::align_val_t, const std::nothrow_t&) noexcept {
  release(pointer);
}
void operator delete[](void* pointer, std::align_val_t, const std::nothrow_t&) noexcept {
  release(pointer);
}

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
