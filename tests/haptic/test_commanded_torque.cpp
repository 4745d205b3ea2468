// Specifying a door from haptic playback recordings (analysis/fit/commanded_torque.h): a physical
// door with known changes is played on the simulated HapticMaster (1 ms control delay,
// admittance, force-sensor noise, the virtual user), recorded, and the inverse design must
// name the changes it was played with, whatever the device added to the motion.
#include <catch2/catch.hpp>
#include <cmath>

#include "acquisition/session/session_file.h"
#include "analysis/design/inverse_design.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "fixtures/temp_dir.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"

using namespace doorbench;
using namespace doorbench::haptic;

namespace {

DoorModel changed(const DoorModel& model,
                  const std::vector<std::pair<std::string, double>>& factors) {
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  for (const auto& [name, factor] : factors) values[*model.find_parameter(name)] *= factor;
  return model.with_parameter_values(values);
}

// Plays `model` for `duration_s` of simulated time with the virtual user opening and closing
// the door, recorded to `path`.
void play(const DoorModel& model, const std::filesystem::path& path, double duration_s) {
  DeviceRequest request;
  request.uri = "sim";
  request.simulated_time = true;
  request.hand.duration_s = 10.0;
  PlaybackOptions options;
  options.duration_s = duration_s;
  options.loop.safety.max_force = 100.0;  // the device's own limits: nothing clipped
  options.loop.safety.max_force_rate = 20000.0;
  OpenedDevice opened = open_device(request, options.arc, model.geometry().handle_radius_m);
  SessionMetadata metadata;
  metadata.rig_name = "simulated HapticMaster";
  Playback playback(*opened.device, model, options, path, metadata,
                    PlaybackSetup{opened.device->name(), "TO-BE variant", ""});
  const PlaybackSummary summary =
      playback.run_simulated([&](double t) { opened.simulated->advance_to(t); });
  REQUIRE(summary.records_dropped == 0);
}

}  // namespace

TEST_CASE("a playback session's commanded torque is the played model's", "[inverse][haptic]") {
  testing::TempDir dir("commanded_read");
  const DoorModel played = changed(reference_model(ModelKind::kPhysical), {{"k_l", 0.8}});
  const auto path = dir.path / "played.h5";
  play(played, path, 5.0);
  const std::optional<CommandedTorque> torque = read_commanded_torque(path, 1);
  REQUIRE(torque.has_value());
  REQUIRE(torque->torque_Nm.size() > 4000);
  double largest_difference = 0.0;
  double largest_torque = 0.0;
  for (std::size_t i = 0; i < torque->torque_Nm.size(); ++i) {
    const double model_torque = played.torque_Nm(torque->theta_rad[i], torque->omega_rad_s[i]);
    largest_difference =
        std::max(largest_difference, std::abs(model_torque - torque->torque_Nm[i]));
    largest_torque = std::max(largest_torque, std::abs(torque->torque_Nm[i]));
  }
  CHECK(largest_torque > 5.0);  // the latch was played
  CHECK(largest_difference < 1e-9);
  // Every second tick by default.
  const std::optional<CommandedTorque> decimated = read_commanded_torque(path);
  REQUIRE(decimated.has_value());
  CHECK(decimated->torque_Nm.size() == (torque->torque_Nm.size() + 1) / 2);
}

TEST_CASE("a session without a model torque is not a playback", "[inverse]") {
  testing::TempDir dir("commanded_none");
  const auto path = dir.path / "bench.h5";
  {
    SessionWriter writer(path, SessionMetadata{});
    ChannelInfo info;
    info.name = "angle";
    info.raw_type = RawType::kValues;
    info.unit = "rad";
    info.raw_unit = "rad";
    info.sample_rate_hz = 1000.0;
    writer.add_channel(info);
  }
  CHECK_FALSE(read_commanded_torque(path).has_value());
  CHECK_THROWS_WITH(read_commanded_torque(path, 0), Catch::Contains("decimation must be >= 1"));
}

TEST_CASE("the commanded-torque fit checks its inputs by name", "[inverse]") {
  const DoorModel model = reference_model(ModelKind::kPhysical);
  CommandedTorque data;
  data.source = "one.h5";
  data.theta_rad = {0.1, 0.2};
  data.omega_rad_s = {0.0, 0.1};
  data.torque_Nm = {model.torque_Nm(0.1, 0.0), model.torque_Nm(0.2, 0.1)};
  const FitOptions options;
  CHECK_THROWS_WITH(fit_commanded_torque(model, {data}, {"J_d"}, {}, options, 0.01),
                    Catch::Contains("'J_d' is the inertia"));
  CHECK_THROWS_WITH(fit_commanded_torque(model, {data}, {"spring_rate"}, {}, options, 0.01),
                    Catch::Contains("no parameter 'spring_rate'"));
  CHECK_THROWS_WITH(fit_commanded_torque(model, {data}, {"T_h"}, {}, options, 0.0),
                    Catch::Contains("torque_scale_Nm must be > 0"));
  CHECK_THROWS_WITH(fit_commanded_torque(model, {CommandedTorque{}}, {"T_h"}, {}, options, 0.01),
                    Catch::Contains("no samples"));
  data.torque_Nm.pop_back();
  CHECK_THROWS_WITH(fit_commanded_torque(model, {data}, {"T_h"}, {}, options, 0.01),
                    Catch::Contains("one.h5: angle, rate and torque differ in length"));
}

TEST_CASE("a played TO-BE door is specified from its playback: the changes, and nothing else",
          "[inverse][haptic]") {
  testing::TempDir dir("commanded_spec");
  const DoorModel asis = reference_model(ModelKind::kPhysical);
  // 25 % easier to unlatch, stronger preload, more hinge friction, 20 % heavier.
  const DoorModel played =
      changed(asis, {{"k_l", 0.75}, {"F_l0", 0.75}, {"F0", 1.1}, {"T_h", 1.3}, {"J_d", 1.2}});
  const auto path = dir.path / "tobe.h5";
  play(played, path, 20.0);
  const PreparedData data = prepare_session(path);
  const std::optional<CommandedTorque> torque = read_commanded_torque(path);
  REQUIRE(torque.has_value());

  InverseDesignOptions options;
  options.fixed = {"m_d", "l_c", "k_stop", "c_stop", "e", "w_f"};  // J_d free: heavier
  const InverseDesignResult result = inverse_design(asis, {data}, options, {*torque});
  INFO(result.full_report());
  REQUIRE(result.commanded_torque);
  REQUIRE(result.feasible);
  // The preload's change can be shared by the spring's free length and anchor (the torque is
  // the same): the smallest change spreads it, the fewest-changes alternative puts it back
  // on F0 alone, which is the played door, and is ranked first (fewer parts changed).
  REQUIRE(result.solutions.size() == 2);
  const DesignSolution* fewest = &result.solutions.front();
  CHECK_FALSE(fewest->held_at_as_is.empty());
  CHECK(fewest->parts_changed_cost < result.solutions[1].parts_changed_cost);
  CHECK(result.solutions[1].held_at_as_is.empty());
  CHECK(result.solutions[1].size_of_change < fewest->size_of_change);
  for (const DesignParameter& p : fewest->parameters) {
    const double truth = played.parameter_values()[*played.find_parameter(p.name)];
    INFO(p.name << ": AS-IS " << p.as_is << ", played " << truth << ", specified " << p.to_be
                << " ± " << p.uncertainty);
    if (p.name == "J_d") {
      // From the motion, which carries the device's own dynamics: within 5 %.
      CHECK(std::abs(p.to_be - truth) <= 0.05 * truth);
    } else if (truth != p.as_is) {
      // A changed parameter: the played value, within 0.5 % (the torque is exact; what is
      // left is the priors' pull toward AS-IS).
      CHECK(std::abs(p.to_be - truth) <= 0.005 * std::abs(truth));
    } else {
      // An unchanged one stays within 0.1 % of its bound width.
      CHECK(std::abs(p.change) <= 0.001 * (p.bounds.upper - p.bounds.lower));
    }
  }
  // Both feel the same: the felt torque differs by under 0.01 N*m RMS.
  for (const DesignSolution& solution : result.solutions) {
    CHECK(solution.data_cost <= 0.5 * solution.data_residuals * 1.0);
  }
  // Motion alone, the same recording: the device's rendering moves the design.
  InverseDesignOptions motion = options;
  motion.use_commanded_torque = false;
  motion.starts = 1;
  motion.fewest_changes_refits = 0;
  const InverseDesignResult from_motion = inverse_design(asis, {data}, motion, {*torque});
  CHECK_FALSE(from_motion.commanded_torque);
}
