// The viewer's tuning model on a session of the simulated bench (sensory reference door):
// changes re-simulate the strokes, reset restores the fitted values, bad values are
// refused with the model's reason, and the saved parameter file loads back as the same model.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/report/plot_style.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
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
        REQUIRE(b.y(i) == expected * doorbench::kDegPerRad);  // shown in deg/s
      }
      ++i;
    }
  }
  REQUIRE(i == b.size());
}

TEST_CASE("tuning re-simulates exactly the selected strokes", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_tuning_selection");
  const auto session = dir.path / "bench.h5";
  doorbench::testing::record_built_in_session(session, 19.0, 5, "sensory");
  const doorbench::PreparedData data = doorbench::prepare_session(session);
  REQUIRE(data.strokes.size() >= 4);
  const doorbench::DoorModel reference = doorbench::reference_model(ModelKind::kSensory);
  Tuning tuning(data, reference);
  // Default: the first 12 (or all when fewer).
  const std::size_t first = std::min<std::size_t>(12, data.strokes.size());
  REQUIRE(tuning.stroke_count() == first);
  REQUIRE(tuning.session_stroke_count() == data.strokes.size());
  REQUIRE(tuning.selected_strokes().front() == 0);
  REQUIRE(tuning.selected_strokes().back() == int(first) - 1);

  // Strokes 3 and 1 (given out of order): the plot holds those two, in time order.
  const auto before = tuning.plot.revision;
  REQUIRE(tuning.select_strokes({3, 1}) == "");
  REQUIRE(tuning.selected_strokes() == std::vector<int>{1, 3});
  REQUIRE(tuning.stroke_count() == 2);
  REQUIRE(tuning.plot.revision > before);
  REQUIRE(tuning.plot.series.size() == 3);

  using doorbench::perceptual::Control;
  const double j = doorbench::perceptual::read(reference, Control::kHeaviness);
  REQUIRE(tuning.set_control(Control::kHeaviness, 1.4 * j) == "");
  tuning.resimulate();

  // What a replay of exactly strokes 1 and 3 gives, and nothing else.
  doorbench::PreparedData selected = data;
  selected.strokes = {data.strokes[1], data.strokes[3]};
  doorbench::WindowOptions options =
      doorbench::metric_window_options(doorbench::FitOptions{}, tuning.model());
  options.whole_strokes = true;
  const auto expected = doorbench::simulate_windows(tuning.model(), selected, options);
  const auto& measured = *tuning.plot.series[0];
  const auto& tuned = *tuning.plot.series[2];
  CHECK(measured.unit() == "deg/s");
  CHECK(tuned.unit() == "deg/s");
  REQUIRE(tuned.size() == selected.strokes[0].size() + 1 + selected.strokes[1].size());
  REQUIRE(measured.size() == tuned.size());
  std::size_t i = 0;
  double max_error = 0.0;
  for (std::size_t k = 0; k < selected.strokes.size(); ++k) {
    if (k > 0) {
      REQUIRE(std::isnan(tuned.y(i)));  // the break between the strokes
      ++i;
    }
    const doorbench::Stroke& stroke = selected.strokes[k];
    for (std::size_t n = 0; n < stroke.size(); ++n, ++i) {
      INFO("stroke " << k << " sample " << n);
      REQUIRE(tuned.x(i) == stroke.time_s[n]);
      // Shown in deg/s (viewer::to_display_units), the model run in rad/s.
      REQUIRE(measured.y(i) == stroke.omega_rad_s[n] * doorbench::kDegPerRad);
      const double hat = expected.omega_rad_s[k][n];
      if (std::isnan(hat)) {
        REQUIRE(std::isnan(tuned.y(i)));
      } else {
        REQUIRE(tuned.y(i) == hat * doorbench::kDegPerRad);
        max_error = std::max(max_error, std::abs(stroke.omega_rad_s[n] - hat));
      }
    }
  }
  REQUIRE(tuning.max_error_rad_s() == max_error);

  // A checkbox: stroke 2 added, then 1 removed.
  REQUIRE(tuning.toggle_stroke(2) == "");
  REQUIRE(tuning.selected_strokes() == std::vector<int>{1, 2, 3});
  REQUIRE(tuning.is_selected(2));
  REQUIRE(tuning.toggle_stroke(1) == "");
  REQUIRE(tuning.selected_strokes() == std::vector<int>{2, 3});
  REQUIRE(!tuning.is_selected(1));
  REQUIRE(tuning.plot.series[2]->size() == data.strokes[2].size() + 1 + data.strokes[3].size());

  // Refused selections leave the selection as it was.
  REQUIRE_THAT(tuning.select_strokes({}), Contains("at least one stroke"));
  REQUIRE_THAT(tuning.select_strokes({2, 2}), Contains("stroke index 2 given twice"));
  REQUIRE_THAT(tuning.select_strokes({0, 99}), Contains("stroke index 99 out of range"));
  REQUIRE(tuning.toggle_stroke(2) == "");
  REQUIRE_THAT(tuning.toggle_stroke(3), Contains("at least one stroke"));
  REQUIRE(tuning.selected_strokes() == std::vector<int>{3});
  REQUIRE(tuning.plot.series[2]->size() == data.strokes[3].size());
  REQUIRE_THROWS_WITH(Tuning(data, reference, {1, 1}), Contains("stroke index 1 given twice"));
}
