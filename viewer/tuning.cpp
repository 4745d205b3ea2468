#include "viewer/tuning.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <thread>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "core/numbers.h"
#include "core/parallel.h"
#include "viewer/session_data.h"

namespace doorbench::viewer {

namespace {
constexpr std::size_t kDefaultStrokes = 12;
}  // namespace

Tuning::Tuning(const PreparedData& data, DoorModel fitted, std::vector<int> strokes)
    : all_(data), fitted_(fitted), model_(std::move(fitted)) {
  if (data.strokes.empty()) {
    throw std::invalid_argument(data.source + ": no strokes to tune against");
  }
  if (strokes.empty()) {
    for (std::size_t i = 0; i < data.strokes.size() && i < kDefaultStrokes; ++i) {
      strokes.push_back(int(i));
    }
  }
  std::sort(strokes.begin(), strokes.end());
  if (std::string problem = check_selection(strokes); !problem.empty()) {
    throw std::invalid_argument(std::string(data.source).append(": ").append(problem));
  }
  threads_ = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  apply_selection(std::move(strokes));
}

bool Tuning::is_selected(int index) const {
  return std::binary_search(selected_.begin(), selected_.end(), index);
}

std::string Tuning::check_selection(const std::vector<int>& strokes) const {
  if (strokes.empty()) return "select at least one stroke to replay";
  for (std::size_t i = 0; i < strokes.size(); ++i) {
    const int index = strokes[i];
    if (index < 0 || std::size_t(index) >= all_.strokes.size()) {
      return std::string("stroke index ")
          .append(std::to_string(index))
          .append(" out of range (")
          .append(std::to_string(all_.strokes.size()))
          .append(" strokes)");
    }
    if (i > 0 && strokes[i - 1] == index) {
      return std::string("stroke index ").append(std::to_string(index)).append(" given twice");
    }
  }
  return "";
}

std::string Tuning::select_strokes(std::vector<int> strokes) {
  std::sort(strokes.begin(), strokes.end());
  if (std::string problem = check_selection(strokes); !problem.empty()) return problem;
  apply_selection(std::move(strokes));
  return "";
}

std::string Tuning::toggle_stroke(int index) {
  std::vector<int> strokes = selected_;
  const auto at = std::lower_bound(strokes.begin(), strokes.end(), index);
  if (at != strokes.end() && *at == index)
    strokes.erase(at);
  else
    strokes.insert(at, index);
  return select_strokes(std::move(strokes));
}

void Tuning::apply_selection(std::vector<int> strokes) {
  selected_ = std::move(strokes);
  data_ = all_;
  data_.strokes.clear();
  for (int index : selected_) data_.strokes.push_back(all_.strokes[std::size_t(index)]);
  PreparedData single = data_;
  single.strokes.clear();
  singles_.clear();
  for (const Stroke& stroke : data_.strokes) {
    singles_.push_back(single);
    singles_.back().strokes = {stroke};
  }
  // Measured ω and the fitted model's replay are fixed until the selection changes; the
  // tuned one follows each change of the model.
  std::vector<double> t, omega;
  for (const Stroke& stroke : data_.strokes) {
    if (!t.empty()) {
      t.push_back(0.5 * (t.back() + stroke.time_s.front()));
      omega.push_back(kNaN);
    }
    t.insert(t.end(), stroke.time_s.begin(), stroke.time_s.end());
    omega.insert(omega.end(), stroke.omega_rad_s.begin(), stroke.omega_rad_s.end());
  }
  const std::string rate_unit = to_display_units("rad/s", omega);
  auto measured = std::make_shared<Series>(Series::timed("measured", rate_unit, t, omega));
  style_series(*measured, plot_style::Meaning::kMeasured);
  plot.series.clear();
  plot.title = "rate: measured, fitted and tuned (strokes replayed open-loop)";
  plot.x_label = "time";
  plot.y_label = "rate";
  plot.add(measured);
  double ignored = 0.0;
  plot.add(replay(fitted_, "fitted", plot_style::Meaning::kSimulated, &ignored));
  const auto start = std::chrono::steady_clock::now();
  plot.add(replay(model_, "tuned", plot_style::Meaning::kTuned, &max_error_));
  last_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++plot.revision;
  plot.fit();
}

std::shared_ptr<Series> Tuning::replay(const DoorModel& model, const std::string& name,
                                       plot_style::Meaning meaning, double* max_error) {
  WindowOptions options = metric_window_options(FitOptions{}, model);
  options.whole_strokes = true;
  // Each stroke is one window of its own (whole_strokes): replaying them separately, in
  // parallel, gives what one simulate_windows over all of them gives (the tests check).
  std::vector<std::vector<double>> simulated(data_.strokes.size());
  parallel_for(static_cast<int>(singles_.size()), threads_, [&](int k) {
    simulated[std::size_t(k)] =
        std::move(simulate_windows(model, singles_[std::size_t(k)], options).omega_rad_s.front());
  });
  std::vector<double> t, omega;
  *max_error = 0.0;
  for (std::size_t k = 0; k < data_.strokes.size(); ++k) {
    const Stroke& stroke = data_.strokes[k];
    if (!t.empty()) {
      t.push_back(0.5 * (t.back() + stroke.time_s.front()));
      omega.push_back(kNaN);
    }
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      const double hat = simulated[k][i];
      t.push_back(stroke.time_s[i]);
      omega.push_back(hat);
      const double error = std::abs(stroke.omega_rad_s[i] - hat);
      if (std::isfinite(error)) *max_error = std::max(*max_error, error);
    }
  }
  const std::string rate_unit = to_display_units("rad/s", omega);
  auto series = std::make_shared<Series>(Series::timed(name, rate_unit, std::move(t), omega));
  style_series(*series, meaning);
  return series;
}

std::string Tuning::set_parameter(int index, double value) {
  if (index < 0 || index >= model_.parameter_count()) {
    return "parameter index " + std::to_string(index) + " out of range";
  }
  std::vector<double> values(model_.parameter_values().begin(), model_.parameter_values().end());
  values[std::size_t(index)] = value;
  try {
    model_ = model_.with_parameter_values(std::move(values));
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

std::string Tuning::set_control(perceptual::Control control, double value) {
  try {
    model_ = perceptual::set(model_, control, value);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

double Tuning::resimulate() {
  const auto start = std::chrono::steady_clock::now();
  auto tuned = replay(model_, "tuned", plot_style::Meaning::kTuned, &max_error_);
  plot.series.back() = std::move(tuned);
  ++plot.revision;
  last_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return last_ms_;
}

std::vector<std::filesystem::path> Tuning::save(const std::filesystem::path& params_path) const {
  std::vector<std::filesystem::path> written;
  auto write = [&written](const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path);
    out << text;
    out.close();
    if (!out) throw std::runtime_error(path.string() + ": cannot write");
    written.push_back(path);
  };
  write(params_path, to_parameter_json(model_));
  if (!model_.effects().empty()) {
    std::filesystem::path effects = params_path;
    effects.replace_filename(params_path.stem().string() + "-effects.json");
    write(effects, to_effects_json(model_));
  }
  return written;
}

}  // namespace doorbench::viewer
