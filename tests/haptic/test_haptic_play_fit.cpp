// The device as a measuring instrument: a door variant played on the simulated HapticMaster
// (1 ms control delay, force-sensor noise, the virtual user opening and closing it), recorded
// by the render loop, then prepared and fitted like a bench session. The played parameters
// must come back.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "analysis/preprocessing/preprocessing.h"
#include "fixtures/temp_dir.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"

using namespace doorbench;
using namespace doorbench::haptic;

TEST_CASE("playback followed by a fit recovers the played door", "[haptic][fit]") {
  testing::TempDir dir("play_fit");
  // A tuned variant, away from the reference door the fit starts from.
  const DoorModel reference = reference_model(ModelKind::kSensory);
  DoorModel played = perceptual::set(reference, perceptual::Control::kHeaviness, 1.25);
  played = perceptual::set(played, perceptual::Control::kLatchEffort,
                           1.3 * perceptual::read(reference, perceptual::Control::kLatchEffort));
  played = perceptual::set(played, perceptual::Control::kSmoothness,
                           1.4 * perceptual::read(reference, perceptual::Control::kSmoothness));

  DeviceRequest request;
  request.uri = "sim";
  request.simulated_time = true;
  request.hand.duration_s = 10.0;
  PlaybackOptions options;
  options.duration_s = 30.0;  // three open-close cycles
  // The simulated HapticMaster's own force and rate limits: the virtual user pushes the door into
  // its closed stop, and a force the safety layer clips is a force the fit does not see.
  options.loop.safety.max_force = 100.0;
  options.loop.safety.max_force_rate = 20000.0;
  OpenedDevice opened = open_device(request, options.arc, played.geometry().handle_radius_m);
  const std::filesystem::path path = dir.path / "played.h5";
  SessionMetadata metadata;
  metadata.rig_name = "simulated HapticMaster";
  PlaybackSummary summary;
  {
    Playback playback(*opened.device, played, options, path, metadata,
                      PlaybackSetup{opened.device->name(), "tuned variant", ""});
    summary = playback.run_simulated([&](double t) { opened.simulated->advance_to(t); });
  }
  INFO(summary.brief_report());
  REQUIRE(summary.records_dropped == 0);

  const PreparedData data = prepare_session(path);
  REQUIRE(data.strokes.size() >= 6);
  FitOptions fit_options;
  fit_options.cross_validation_folds = 0;
  const FitResult fit = fit_model(reference, data, fit_options);
  INFO(fit.summary.full_report());
  for (const char* name : {"J", "k_inf", "k_lock", "theta1", "theta3", "d1", "d2"}) {
    const int index = *played.find_parameter(name);
    const FittedParameter& fitted = fit.summary.parameters.at(index);
    const double truth = played.parameter_values()[index];
    INFO(name << ": played " << truth << ", recovered " << fitted.value << " ± "
              << fitted.uncertainty);
    // Within 5 % of the played value (the 1 ms control delay and the sensor noise are what the
    // fit does not model), and the reference's value is not: the data moved it.
    CHECK(std::abs(fitted.value - truth) <= 0.05 * std::abs(truth));
  }
  // The changed ones moved far from the reference door's values, so the check above is not
  // met by the start alone.
  for (const char* name : {"J", "k_inf", "d1", "d2"}) {
    const int index = *played.find_parameter(name);
    const double truth = played.parameter_values()[index];
    const double start = reference.parameter_values()[index];
    CHECK(std::abs(start - truth) > 0.15 * std::abs(truth));
  }
}

TEST_CASE("the arc constraint holds the end-effector near the arc under the virtual user's pushes",
          "[haptic][arc]") {
  // The whole render loop (constraint, safety layer with its force and rate limits) on the
  // simulated HapticMaster; the virtual user's hand has no sideways grip of its own and is
  // pushed off the arc by ±20 N pulses of 0.1 s, twice a second on average, radially and
  // axially. Stated bound (docs/haptic.md): 3 mm from the cylinder and from the plane.
  testing::TempDir dir("arc_pushes");
  const DoorModel model = reference_model(ModelKind::kSensory);
  DeviceRequest request;
  request.uri = "sim";
  request.simulated_time = true;
  request.hand.duration_s = 10.0;
  request.pushes.rate_hz = 2.0;
  request.pushes.amplitude_N = 20.0;
  request.pushes.duration_s = 0.1;
  PlaybackOptions options;
  options.duration_s = 20.0;
  options.loop.safety.max_force = 100.0;
  options.loop.safety.max_force_rate = 20000.0;
  OpenedDevice opened = open_device(request, options.arc, model.geometry().handle_radius_m);
  SessionMetadata metadata;
  metadata.rig_name = "simulated HapticMaster, pushed";
  PlaybackSummary summary;
  {
    Playback playback(*opened.device, model, options, dir.path / "pushed.h5", metadata,
                      PlaybackSetup{opened.device->name(), "reference door", ""});
    summary = playback.run_simulated([&](double t) { opened.simulated->advance_to(t); });
  }
  INFO(summary.brief_report());
  CHECK(opened.simulated->truth().pushes >= 20);
  // While the force is fully on (not during the start-up and stop ramps, when the safety layer
  // scales the constraint down with everything else).
  const SessionReader session(dir.path / "pushed.h5");
  const std::vector<double> scale = session.read("safety_scale").raw;
  const std::vector<double> radial = session.read("radial_error").raw;
  const std::vector<double> axial = session.read("axial_error").raw;
  double largest_radial_m = 0.0, largest_axial_m = 0.0;
  for (std::size_t i = 0; i < scale.size(); ++i) {
    if (scale[i] < 1.0) continue;
    largest_radial_m = std::max(largest_radial_m, std::abs(radial[i]));
    largest_axial_m = std::max(largest_axial_m, std::abs(axial[i]));
  }
  INFO("largest radial " << largest_radial_m * 1e3 << " mm, axial " << largest_axial_m * 1e3
                         << " mm");
  CHECK(largest_radial_m < 0.003);
  CHECK(largest_axial_m < 0.003);
  // The pushes moved it off the arc measurably: the bound is the constraint's doing.
  CHECK(std::max(largest_radial_m, largest_axial_m) > 0.0005);
}
