// Input sanity: a physically impossible sample is never used and never
// silent, and a fit never starts from non-finite residuals. On a 3-cycle recording of the
// simulated bench (the sensory reference door), exported as a recording.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "acquisition/session/session_csv.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"

namespace {

using namespace doorbench;

const Recording& bench_recording() {
  static const Recording recording = [] {
    const testing::TempDir dir("impossible");
    const auto path = dir / "bench.h5";
    testing::record_built_in_session(path, 18.6, 11, "sensory");
    return session_to_recording(SessionReader(path));
  }();
  return recording;
}

std::size_t row_at(const Recording& recording, double time_s) {
  std::size_t i = 0;
  while (i + 1 < recording.size() && recording.time_s[i] < time_s - 1e-9) ++i;
  return i;
}

FitOptions quick() {
  FitOptions options;
  options.cross_validation_folds = 0;
  return options;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("Impossible samples: one 1e308 N outside the strokes is named and changes no fit",
          "[preprocessing][impossible]") {
  const Recording& clean = bench_recording();
  Recording spiked = clean;
  const std::size_t at = row_at(spiked, 6.3);  // at rest between stroke 2 and stroke 3
  spiked.force_N[at] = 1e308;
  const PreparedData a = prepare(clean);
  const PreparedData b = prepare(spiked);
  REQUIRE(b.warnings.size() == 1);
  CHECK(b.warnings[0] ==
        "force_N: 1 physically impossible sample (|value| > 10000 N) from 6.300 s, the largest "
        "1e+308 N: not used");
  CHECK(a.warnings.empty());
  REQUIRE(b.strokes.size() == a.strokes.size());
  bool listed = false;
  for (const ExcludedSegment& e : b.excluded) {
    if (e.reason == "outside the strokes: physically impossible values") listed = true;
  }
  CHECK(listed);

  const DoorModel start = reference_model(ModelKind::kSensory);
  const FitResult fa = fit_model(start, a, quick());
  const FitResult fb = fit_model(start, b, quick());
  for (std::size_t i = 0; i < fa.summary.parameters.size(); ++i) {
    const FittedParameter& p = fb.summary.parameters[i];
    const FittedParameter& q = fa.summary.parameters[i];
    INFO(p.name << ": " << p.value << " and, without the sample, " << q.value << " +- "
                << q.uncertainty);
    if (q.free) CHECK(std::abs(p.value - q.value) <= 0.1 * q.uncertainty);
  }
}

TEST_CASE("Impossible samples: a spike inside a stroke is left out and the fit runs",
          "[preprocessing][impossible]") {
  Recording spiked = bench_recording();
  const std::size_t at = row_at(spiked, 7.5);  // in stroke 3, an opening
  spiked.force_N[at] = -1e300;
  (*spiked.rate_rad_s)[at + 5] = 1e30;
  const PreparedData data = prepare(spiked);
  REQUIRE(data.warnings.size() == 2);
  CHECK(data.warnings[0] ==
        "force_N: 1 physically impossible sample (|value| > 10000 N) from 7.500 s, the largest "
        "-1e+300 N: not used");
  CHECK(data.warnings[1] ==
        "rate_rad_s: 1 physically impossible sample (|value| > 17.4533 rad/s) from 7.505 s, the "
        "largest 1e+30 rad/s: not used");
  bool listed = false;
  for (const ExcludedSegment& e : data.excluded) {
    INFO(e.reason);
    if (contains(e.reason, "stroke 3 (opening)") &&
        contains(e.reason, "physically impossible values in 2 samples from 7.500 s")) {
      listed = true;
    }
  }
  CHECK(listed);
  for (const Stroke& stroke : data.strokes) {
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      if (!(std::abs(stroke.force_N[i]) < 1e4)) FAIL("stroke " << stroke.id << " sample " << i);
    }
  }
  const FitResult result = fit_model(reference_model(ModelKind::kSensory), data, quick());
  CHECK(std::isfinite(result.summary.final_cost));
}

TEST_CASE("Impossible samples: a fit never starts from non-finite residuals",
          "[fitting][impossible]") {
  // Prepared data handed to the fit directly: a finite but absurd force in stroke 3.
  PreparedData data = prepare(bench_recording());
  REQUIRE(data.strokes.size() == 6);
  Stroke& third = data.strokes[2];
  third.force_N[third.size() / 2] = 1e200;
  try {
    fit_model(reference_model(ModelKind::kSensory), data, quick());
    FAIL("the fit ran");
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    INFO(message);
    CHECK(message.rfind("fit: the start model's simulation is not finite in stroke 3 (opening), "
                        "the window from ",
                        0) == 0);
    CHECK(contains(message,
                   " (largest |force| there 1e+200 N); check that window's data and "
                   "the start parameters"));
  }
}
