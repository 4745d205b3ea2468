// The viewer's tuning model on a session of the simulated bench (sensory reference door):
// changes re-simulate the strokes, reset restores the fitted values, bad values are
// refused with the model's reason, and the saved parameter file loads back as the same model.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/fit_metrics.h"
#include "analysis/fitting.h"
#include "analysis/parameter_file.h"
#include "analysis/preprocessing.h"
#include "simulated_session.h"
#include "temp_dir.h"
#include "viewer/tuning.h"

using Catch::Matchers::Contains;
using doorbench::ModelKind;
using doorbench::viewer::Tuning;

TEST_CASE("tuning re-simulates the strokes, resets, refuses bad values and saves", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_tuning");
  const auto session = dir.path / "bench.h5";
  doorbench::testing::record_built_in_session(session, 19.0, 5, "sensory");
  const doorbench::PreparedData data = doorbench::prepare_session(session);
  REQUIRE(data.strokes.size() >= 2);
  const doorbench::DoorModel reference = doorbench::reference_model(ModelKind::kSensory);
  Tuning tuning(data, reference);
  REQUIRE(tuning.plot.series.size() == 3);  // measured, fitted, tuned
  const double fitted_error = tuning.max_error_rad_s();
  REQUIRE(std::isfinite(fitted_error));

  // Heavier door by half: its replay is another than the fitted model's.
  using doorbench::perceptual::Control;
  const double j = doorbench::perceptual::read(reference, Control::kHeaviness);
  REQUIRE(tuning.set_control(Control::kHeaviness, 1.5 * j) == "");
  const auto before = tuning.plot.revision;
  tuning.resimulate();
  REQUIRE(tuning.plot.revision == before + 1);
  REQUIRE(tuning.max_error_rad_s() != fitted_error);
  const auto& fitted = *tuning.plot.series[1];
  const auto& tuned = *tuning.plot.series[2];
  REQUIRE(tuned.size() == fitted.size());
  double largest_difference = 0.0;
  for (std::size_t i = 0; i < tuned.size(); ++i) {
    if (std::isfinite(tuned.y(i)) && std::isfinite(fitted.y(i))) {
      largest_difference = std::max(largest_difference, std::abs(tuned.y(i) - fitted.y(i)));
    }
  }
  REQUIRE(largest_difference > 0.01);

  // Saved and loaded back: the same values.
  const auto written = tuning.save(dir.path / "tuned.json");
  REQUIRE(written.size() == 1);
  const auto loaded = doorbench::load_model(ModelKind::kSensory, written[0], "");
  REQUIRE(loaded.parameter_count() == tuning.model().parameter_count());
  for (int i = 0; i < loaded.parameter_count(); ++i) {
    INFO(loaded.parameter_name(i));
    REQUIRE(loaded.parameter_values()[std::size_t(i)] ==
            Approx(tuning.model().parameter_values()[std::size_t(i)]).epsilon(1e-12));
  }

  // A value the model refuses leaves it as it was, and says why.
  const int j_index = *reference.find_parameter("J");
  const std::string problem = tuning.set_parameter(j_index, -1.0);
  REQUIRE_THAT(problem, Contains("J"));
  REQUIRE(doorbench::perceptual::read(tuning.model(), Control::kHeaviness) == Approx(1.5 * j));

  // Reset: the fitted values exactly, and the replay is the fitted one again.
  tuning.reset();
  for (int i = 0; i < reference.parameter_count(); ++i) {
    REQUIRE(tuning.model().parameter_values()[std::size_t(i)] ==
            reference.parameter_values()[std::size_t(i)]);
  }
  tuning.resimulate();
  REQUIRE(tuning.max_error_rad_s() == fitted_error);

  REQUIRE_THROWS_WITH(Tuning(data, reference, {99}), Contains("stroke index 99 out of range"));
}

TEST_CASE("tuning replays strokes in parallel with the same result as one thread", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_tuning_threads");
  const auto session = dir.path / "bench.h5";
  doorbench::testing::record_built_in_session(session, 19.0, 5, "sensory");
  const doorbench::PreparedData data = doorbench::prepare_session(session);
  REQUIRE(data.strokes.size() >= 3);
  const doorbench::DoorModel reference = doorbench::reference_model(ModelKind::kSensory);
  Tuning one(data, reference);
  Tuning three(data, reference);
  one.set_threads(1);
  three.set_threads(3);
  using doorbench::perceptual::Control;
  const double j = doorbench::perceptual::read(reference, Control::kHeaviness);
  REQUIRE(one.set_control(Control::kHeaviness, 1.3 * j) == "");
  REQUIRE(three.set_control(Control::kHeaviness, 1.3 * j) == "");
  one.resimulate();
  three.resimulate();
  const auto& a = *one.plot.series[2];
  const auto& b = *three.plot.series[2];
  REQUIRE(a.size() == b.size());
  std::size_t finite = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    INFO("sample " << i);
    REQUIRE(a.x(i) == b.x(i));
    if (std::isnan(a.y(i))) {
      REQUIRE(std::isnan(b.y(i)));
    } else {
      REQUIRE(a.y(i) == b.y(i));  // bit for bit: each stroke's replay is independent
      ++finite;
    }
  }
  REQUIRE(finite > a.size() / 2);
  REQUIRE(one.max_error_rad_s() == three.max_error_rad_s());

  // And the same as one simulate_windows over all the strokes together (what it replaced).
  doorbench::PreparedData selected = data;
  selected.strokes.resize(std::min<std::size_t>(12, data.strokes.size()));
  doorbench::WindowOptions options =
      doorbench::metric_window_options(doorbench::FitOptions{}, one.model());
  options.whole_strokes = true;
  const auto together = doorbench::simulate_windows(one.model(), selected, options);
  std::size_t i = 0;
  for (std::size_t k = 0; k < selected.strokes.size(); ++k) {
    if (k > 0) ++i;  // the NaN between strokes
    for (double expected : together.omega_rad_s[k]) {
      INFO("stroke " << k << " sample " << i);
      if (std::isnan(expected)) {
        REQUIRE(std::isnan(b.y(i)));
      } else {
        REQUIRE(b.y(i) == expected);
      }
      ++i;
    }
  }
  REQUIRE(i == b.size());
}
