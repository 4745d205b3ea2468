#pragma once
// What a person feels when opening and closing a door, as a handful of numbers read off the
// hand force against the angle: the peak force to unlatch and to latch, the friction (half the
// gap between the opening and closing force curves) near closed and further open, and the
// balance (the force needed to hold the door still at mid-angle; it tells whether the door
// falls open or shut). docs/design-spec.md defines each.
//
// The same function reads them off a model (opened and closed by the virtual hand in a
// simulation) and off recordings (measured strokes, e.g. TO-BE haptic playback sessions), so
// that the two compare like for like. The check (compare_feel) goes further: it computes the
// hand force the model needs along the recordings' own motion (inverse dynamics,
// F = (J dω/dt − τ_m(θ, ω)) / r_h) and compares force–angle curves and felt quantities.
//
// Thread safety: free functions without shared state; a DoorModel may be shared.
#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/simulation/simulator.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/simulation/virtual_hand.h"

namespace doorbench {

struct FeltOptions {
  // The model's run: the virtual hand's standard open-close (80° in 10 s), sampled at
  // output_rate_hz with the simulator's options.
  VirtualHandOptions hand;
  double output_rate_hz = 1000.0;
  SimulationOptions simulation;
  // Near closed: 0 < θ < latch_zone_rad (the latch's region, as in run_summary.h).
  double latch_zone_rad = 0.1;
  // The force–angle curves' bins.
  double bin_width_rad = 0.0349066;  // 2°
  // Samples slower than this are left out of the curves and the latch peak (a door held
  // still has no friction direction; the hold after closing is no latching).
  double moving_rate_rad_s = 0.02;
  // Friction "near closed" is over latch_zone_rad..near_closed_end_rad, "open" beyond it up
  // to θ_max − open_end_margin_rad (the open stop's region left out).
  double near_closed_end_rad = 0.5;
  double open_end_margin_rad = 0.1;
  // The balance: over bins within balance_half_width_rad of balance_angle_rad.
  double balance_angle_rad = 0.785398;        // 45°
  double balance_half_width_rad = 0.0872665;  // 5°
  // The model's force along recorded motion needs dω/dt: differentiated after a zero-phase
  // low-pass at this cut-off (preprocessing.h smoothing_derivative).
  // 200 Hz (or 0.4 × the sample rate when lower): a latch snap lasts milliseconds, and a
  // lower cut-off spreads its acceleration onto the peak force (measured: 20 Hz puts 8 N on
  // the reference door's 36 N unlatching peak, 200 Hz 1 N).
  double acceleration_cutoff_hz = 200.0;
  // The peaks are taken of the force's running median over this many samples (odd).
  int peak_median_samples = 5;

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

// NaN where the data hold nothing to read it from (e.g. no closing stroke).
struct FeltQuantities {
  double peak_unlatch_force_N;      // largest opening hand force near closed (median of strokes)
  double unlatch_angle_rad;         // where that peak is
  double peak_latch_force_N;        // largest closing push near closed while moving
  double friction_near_closed_N;    // half the opening–closing gap, latch zone..near_closed_end
  double friction_open_N;           // the same further open
  double free_movement_friction_N;  // the same over the whole free range
  double balance_force_N;           // holding force at balance angle: > 0 falls shut, < 0 open
  double balance_angle_rad;

  std::string brief_report() const;
};

// The quantities compared, in a fixed order (for loops, JSON and tables).
struct FeltQuantityInfo {
  std::string_view name;   // as in JSON: "peak_unlatch_force_N"
  std::string_view label;  // for people: "peak force to unlatch"
  std::string_view unit;
  double FeltQuantities::*member;
};
extern const std::array<FeltQuantityInfo, 6> kFeltQuantities;

// "peak force to unlatch (N)": the label people read, with its unit.
std::string felt_label(const FeltQuantityInfo& info);

// One line stating where each quantity is read (angles, directions, speeds), from `options`:
// the definition every table of felt quantities shares.
std::string felt_definition(const FeltOptions& options);

// The standard run's conditions: "virtual hand, 0 to 80 deg and back in 10 s".
std::string standard_run_conditions(const FeltOptions& options);

// Mean hand force per angle bin and direction; NaN in a bin without samples.
struct ForceAngleCurve {
  double bin_width_rad = 0.0;
  std::vector<double> angle_rad;  // bin centres, from bin_width / 2 up to θ_max
  std::vector<double> opening_force_N, closing_force_N;
  std::vector<int> opening_count, closing_count;
};

// The curve of moving samples (|ω| > moving_rate_rad_s) with 0 <= θ < θ_max.
ForceAngleCurve force_angle_curve(std::span<const PreparedData> data, double theta_max_rad,
                                  const FeltOptions& options = {});

// Felt quantities of measured (or simulated) strokes. Throws std::invalid_argument for bad
// options or θ_max, and when the data hold no stroke.
FeltQuantities felt_from_strokes(std::span<const PreparedData> data, double theta_max_rad,
                                 const FeltOptions& options = {});

// The model opened and closed once by the virtual hand: an opening and a closing stroke.
PreparedData virtual_hand_strokes(const DoorModel& model, const FeltOptions& options = {});

// Felt quantities of a model: felt_from_strokes(virtual_hand_strokes(model)).
FeltQuantities felt_quantities(const DoorModel& model, const FeltOptions& options = {});

// The recordings with each sample's force replaced by the hand force the model needs to move
// the same way: F = (J dω/dt − τ_m(θ, ω)) / r_h (r_h and J the model's).
std::vector<PreparedData> model_force_along(const DoorModel& model,
                                            std::span<const PreparedData> recordings,
                                            const FeltOptions& options = {});

struct FeltQuantityError {
  std::string name;
  double model = 0.0, recorded = 0.0;
  double error = 0.0;          // model − recorded, in the quantity's unit
  double error_percent = 0.0;  // of |recorded|; NaN when recorded is 0 or NaN
};

// Does the model feel like the recordings? The model's force along the recordings' motion
// against the measured force: both curves from the same samples, the felt quantities of both.
struct FeelCheck {
  ForceAngleCurve model_curve, recorded_curve;
  FeltQuantities model{}, recorded{};
  std::vector<FeltQuantityError> errors;  // kFeltQuantities' order
  // RMS over bins holding samples, model − recorded (N): each direction, and both together.
  double opening_rms_error_N = 0.0, closing_rms_error_N = 0.0, curve_rms_error_N = 0.0;
  int bins_compared = 0;
  std::string brief_report() const;
};

// Throws std::invalid_argument when there are no recordings or none holds a stroke.
FeelCheck compare_feel(const DoorModel& model, std::span<const PreparedData> recordings,
                       const FeltOptions& options = {});

}  // namespace doorbench
