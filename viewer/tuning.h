#pragma once
// Tuning (no GL, no ImGui): a door model's parameters and, for the sensory model, the
// perceptual controls (analysis/model/perceptual_controls.h, spec §2) changed one at a time; each
// change re-simulates the selected strokes open-loop under their recorded force (the
// study's replay, analysis/fit/fit_metrics.h) so that the tuned ω can be seen against the
// measured one; reset to the fitted values; save as a new parameter file.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/perceptual_controls.h"
#include "analysis/report/plot_style.h"
#include "analysis/preprocessing/strokes.h"
#include "viewer/plot_view.h"

namespace doorbench::viewer {

class Tuning {
 public:
  // `strokes`: indices into data.strokes to re-simulate (empty: at most the first 12).
  // Throws std::invalid_argument when there is no stroke or an index is out of range or
  // given twice.
  Tuning(const PreparedData& data, DoorModel fitted, std::vector<int> strokes = {});

  const DoorModel& fitted() const { return fitted_; }
  const DoorModel& model() const { return model_; }
  // The strokes replayed (the selection's size) and the session's strokes to choose from.
  std::size_t stroke_count() const { return data_.strokes.size(); }
  std::size_t session_stroke_count() const { return all_.strokes.size(); }
  // The selection: indices into the session's strokes, ascending.
  const std::vector<int>& selected_strokes() const { return selected_; }
  bool is_selected(int index) const;
  // Replays exactly these strokes from now on (in ascending order whatever the order
  // given): the plot's measured, fitted and tuned curves are rebuilt for them with the
  // current model. "" when done; otherwise why (empty, out of range, given twice) and the
  // selection stays as it was.
  std::string select_strokes(std::vector<int> strokes);
  // The selection with one stroke added or removed (what a checkbox does).
  std::string toggle_stroke(int index);

  // "" when the change was made; otherwise the model's one-line reason, and nothing changes.
  std::string set_parameter(int index, double value);
  std::string set_control(perceptual::Control control, double value);
  void reset() { model_ = fitted_; }

  // Replays the selected strokes with the current model and updates the plot; returns the
  // wall time it took in ms. A stroke whose replay fails shows as a gap.
  double resimulate();
  double last_resimulate_ms() const { return last_ms_; }
  // Strokes are replayed in parallel on up to this many threads (default: the cores);
  // each stroke's replay is independent, so the result does not depend on it.
  void set_threads(int threads) { threads_ = threads < 1 ? 1 : threads; }
  int threads() const { return threads_; }
  // Largest |ω_meas − ω_sim| over the replayed strokes (the study's objective), rad/s.
  double max_error_rad_s() const { return max_error_; }

  // Measured ω, the fitted model's and the tuned model's replay; strokes one after another.
  PlotView plot;

  // Writes the tuned model as a parameter file at `params_path` and, when it has effects,
  // its effects file next to it (stem + "-effects.json"); returns the paths written.
  std::vector<std::filesystem::path> save(const std::filesystem::path& params_path) const;

 private:
  std::shared_ptr<Series> replay(const DoorModel& model, const std::string& name,
                                 plot_style::Meaning meaning, double* max_error);
  // "" or why `strokes` (sorted) is not a selection of all_'s strokes.
  std::string check_selection(const std::vector<int>& strokes) const;
  // Takes a checked, sorted selection: data_, singles_ and the plot's three curves.
  void apply_selection(std::vector<int> strokes);
  PreparedData all_;  // every stroke of the session
  std::vector<int> selected_;
  PreparedData data_;  // the selected strokes only
  // The same strokes one per PreparedData, so that each replays on its own thread.
  std::vector<PreparedData> singles_;
  int threads_ = 1;
  DoorModel fitted_;
  DoorModel model_;
  double last_ms_ = 0.0;
  double max_error_ = 0.0;
};

}  // namespace doorbench::viewer
