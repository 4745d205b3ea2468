#include "viewer/viewer_app.h"

#include <imgui.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace doorbench::viewer {

namespace {

const char* raw_type_name(RawType t) {
  return t == RawType::kCounts ? "counts" : "values";
}

void text_row(const char* name, const std::string& value) {
  ImGui::TableNextRow();
  ImGui::TableNextColumn();
  ImGui::TextUnformatted(name);
  ImGui::TableNextColumn();
  ImGui::TextUnformatted(value.empty() ? "-" : value.c_str());
}

// The height of each of n plots stacked in `avail` pixels (ImGui puts item spacing after
// each), at least 140.
float stacked_height(float avail, std::size_t n) {
  const float spacing = ImGui::GetStyle().ItemSpacing.y;
  return std::max(140.0f, std::floor((avail - spacing * float(n)) / float(n)));
}

constexpr const char* kNoFitModel =
    "No model to compare with: start the viewer with --params FILE (a fitted parameter file, "
    "e.g. the one `doorbench fit` wrote) and --model, --fit DIR or --loop DIR.";
constexpr const char* kNoLoop =
    "No residual loop: start the viewer with --loop DIR (the folder `doorbench loop` wrote).";
constexpr const char* kNoTuningModel =
    "No model to tune: start the viewer with --params FILE (or --compare, --fit DIR or "
    "--loop DIR).";

constexpr ImGuiTableFlags kTableFlags =
    ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp;

}  // namespace

std::string layout_list() {
  std::string list;
  for (const std::string& name : layout_names()) list += (list.empty() ? "" : ", ") + name;
  return list;
}

std::string check_layout(const std::string& name) {
  const auto& names = layout_names();
  // "live" is not a tab: the viewer follows a journal instead of showing sessions.
  if (name == "live" || std::find(names.begin(), names.end(), name) != names.end()) return "";
  return "unknown layout '" + name + "' (expected " + layout_list() + " or live)";
}

Viewer::Viewer(std::vector<SessionData> sessions, std::vector<std::optional<FitComparison>> fits) {
  for (std::size_t i = 0; i < sessions.size(); ++i) {
    SessionView view;
    view.data = std::move(sessions[i]);
    view.channels = channel_plots(view.data);
    view.channel_states.resize(view.channels.size());
    view.loop = loop_plot(view.data);
    if (i < fits.size() && fits[i]) {
      view.fit = std::move(fits[i]);
      view.fit_plots = fit_plots(*view.fit);
      view.fit_states.resize(view.fit_plots.size());
    }
    sessions_.push_back(std::move(view));
  }
  make_overlay();
}

void Viewer::make_overlay() {
  overlay_.reset();
  overlay_states_.clear();
  if (sessions_.size() < 2) {
    overlay_message_ = "The A/B overlay needs two sessions: doorbench view A.h5 B.h5";
    return;
  }
  try {
    overlay_ = overlay_plots(sessions_[0].data, sessions_[1].data, "", overlay_raw_);
    overlay_states_.resize(overlay_->plots.size());
    if (overlay_->plots.empty()) overlay_message_ = "The two sessions share no channel name.";
  } catch (const std::invalid_argument& error) {
    overlay_message_ = error.what();
  }
}

std::string Viewer::missing_data(const std::string& layout) const {
  if (const std::string problem = check_layout(layout); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  if (layout == "steps") return steps_ ? "" : kNoLoop;
  if (layout == "live") return live_ ? "" : "not following a recording (--live)";
  if (sessions_.empty()) return "no session";
  const SessionView& s = sessions_[std::size_t(std::clamp(current_, 0, int(sessions_.size()) - 1))];
  const std::string no_strokes = "no strokes in " + s.data.path.string() + ": " +
                                 (s.data.prepared ? "none found" : s.data.prepare_message);
  if (layout == "loop" && (!s.data.prepared || s.data.data.strokes.empty())) return no_strokes;
  if (layout == "fit" && !s.fit) {
    return tuning_model_ ? "no comparison with the model: " + no_strokes : kNoFitModel;
  }
  if (layout == "overlay" && (!overlay_ || overlay_->plots.empty())) return overlay_message_;
  if (layout == "tuning") {
    if (!tuning_model_) return kNoTuningModel;
    if (!s.data.prepared || s.data.data.strokes.empty()) return no_strokes;
  }
  return "";
}

void Viewer::frame(float width, float height, const std::string& layout) {
  if (!layout.empty()) {
    const std::string problem = check_layout(layout);
    if (!problem.empty()) throw std::invalid_argument(problem);
  }
  plots_.clear();
  controls_ = layout.empty();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(width, height));
  ImGui::Begin("doorbench view", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoBringToFrontOnFocus | ImGuiWindowFlags_NoSavedSettings);
  if (live_ || layout == "live") {
    if (live_) {
      live();
    } else {
      ImGui::TextUnformatted("Not following a recording: doorbench view --live SESSION.h5");
    }
    ImGui::End();
    handle_exports();
    return;
  }
  if (sessions_.empty()) {
    if (steps_ || layout == "steps") {
      steps();
    } else {
      ImGui::TextUnformatted("No session: doorbench view SESSION.h5 ...");
    }
    ImGui::End();
    handle_exports();
    return;
  }
  current_ = std::clamp(current_, 0, int(sessions_.size()) - 1);
  SessionView& s = sessions_[std::size_t(current_)];
  if (layout.empty()) {
    if (sessions_.size() > 1) {
      ImGui::SetNextItemWidth(500.0f);
      const std::string label = s.data.path.filename().string();
      if (ImGui::BeginCombo("session", label.c_str())) {
        for (std::size_t i = 0; i < sessions_.size(); ++i) {
          const std::string name = sessions_[i].data.path.string();
          if (ImGui::Selectable(name.c_str(), int(i) == current_)) current_ = int(i);
        }
        ImGui::EndCombo();
      }
    } else {
      ImGui::Text("%s", s.data.path.string().c_str());
    }
    if (!status_.empty()) {
      ImGui::SameLine();
      ImGui::TextDisabled("   %s", status_.c_str());
    }
    if (ImGui::BeginTabBar("layouts")) {
      for (const std::string& name : layout_names()) {
        const bool select = !initial_layout_shown_ && name == initial_layout_;
        if (ImGui::BeginTabItem(name.c_str(), nullptr,
                                select ? ImGuiTabItemFlags_SetSelected : ImGuiTabItemFlags_None)) {
          layout_body(s, name);
          ImGui::EndTabItem();
        }
      }
      ImGui::EndTabBar();
    }
    initial_layout_shown_ = true;
  } else {
    layout_body(s, layout);
  }
  ImGui::End();
  handle_exports();
}

std::filesystem::path Viewer::export_path(const std::string& title, const std::string& extension) {
  std::string stem;
  for (char c : title) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    if (keep)
      stem += c;
    else if (!stem.empty() && stem.back() != '-')
      stem += '-';
  }
  if (stem.empty()) stem = "plot";
  return export_dir / (stem + "-" + std::to_string(++exports_) + extension);
}

void Viewer::handle_exports() {
  for (const PlotRecord& record : plots_) {
    if (record.want_csv && record.view != nullptr) {
      const std::filesystem::path path = export_path(record.title, ".csv");
      std::ofstream out(path);
      out << visible_csv(*record.view);
      status_ = out ? "wrote " + path.string() : "cannot write " + path.string();
    }
    if (record.want_png)
      png_request_ = PngRequest{record.widget, export_path(record.title, ".png")};
  }
}

std::optional<Viewer::PngRequest> Viewer::take_png_request() {
  std::optional<PngRequest> request = std::move(png_request_);
  png_request_.reset();
  return request;
}

void Viewer::layout_body(SessionView& s, const std::string& layout) {
  if (layout == "browser") browser(s);
  if (layout == "channels") channels(s);
  if (layout == "loop") loop(s);
  if (layout == "fit") fit(s);
  if (layout == "overlay") overlay();
  if (layout == "steps") steps();
  if (layout == "tuning") tuning(s);
}

void Viewer::browser(SessionView& s) {
  const SessionData& d = s.data;
  ImGui::BeginChild("browser");
  if (ImGui::CollapsingHeader("Metadata", ImGuiTreeNodeFlags_DefaultOpen) &&
      ImGui::BeginTable("metadata", 2, kTableFlags)) {
    text_row("file", d.path.string());
    text_row("rig", d.metadata.rig_name);
    text_row("operator", d.metadata.operator_name);
    text_row("product", d.metadata.product_id);
    text_row("start (UTC)", d.metadata.start_time_utc);
    text_row("software", d.metadata.software_version);
    text_row("notes", d.metadata.notes);
    ImGui::EndTable();
  }
  if (ImGui::CollapsingHeader("Channels", ImGuiTreeNodeFlags_DefaultOpen) &&
      ImGui::BeginTable("channels", 8, kTableFlags)) {
    for (const char* h :
         {"name", "sensor", "serial", "raw", "unit", "rate [Hz]", "samples", "calibration"}) {
      ImGui::TableSetupColumn(h);
    }
    ImGui::TableHeadersRow();
    for (std::size_t i = 0; i < d.channels.size(); ++i) {
      const ChannelInfo& c = d.channels[i];
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(c.name.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(c.sensor_kind.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(c.sensor_serial.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%s (%s)", raw_type_name(c.raw_type), c.raw_unit.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(c.unit.c_str());
      ImGui::TableNextColumn();
      if (c.sample_rate_hz > 0) {
        ImGui::Text("%g", c.sample_rate_hz);
      } else {
        ImGui::TextUnformatted("explicit times");
      }
      ImGui::TableNextColumn();
      ImGui::Text("%zu", d.sample_counts[i]);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(c.calibration_id.empty() ? "-" : c.calibration_id.c_str());
    }
    ImGui::EndTable();
  }
  if (ImGui::CollapsingHeader("Events", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Text("%zu events", d.events.size());
    if (!d.events.empty() &&
        ImGui::BeginTable("events", 4, kTableFlags | ImGuiTableFlags_ScrollY, ImVec2(0, 220))) {
      for (const char* h : {"time [s]", "kind", "channel", "detail"}) ImGui::TableSetupColumn(h);
      ImGui::TableSetupScrollFreeze(0, 1);
      ImGui::TableHeadersRow();
      ImGuiListClipper clipper;
      clipper.Begin(int(d.events.size()));
      while (clipper.Step()) {
        for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
          const SessionEvent& e = d.events[std::size_t(i)];
          ImGui::TableNextRow();
          ImGui::TableNextColumn();
          ImGui::Text("%.4f", e.time_s);
          ImGui::TableNextColumn();
          ImGui::TextUnformatted(e.kind.c_str());
          ImGui::TableNextColumn();
          ImGui::TextUnformatted(e.channel.c_str());
          ImGui::TableNextColumn();
          ImGui::TextUnformatted(e.detail.c_str());
        }
      }
      ImGui::EndTable();
    }
  }
  if (ImGui::CollapsingHeader("Calibration records", ImGuiTreeNodeFlags_DefaultOpen) &&
      ImGui::BeginTable("calibrations", 6, kTableFlags)) {
    for (const char* h : {"id", "sensor", "unit", "coefficients", "method", "date"}) {
      ImGui::TableSetupColumn(h);
    }
    ImGui::TableHeadersRow();
    for (const auto& r : d.calibrations) {
      std::string coefficients;
      char number[32];
      for (double c : r.coefficients) {
        std::snprintf(number, sizeof number, "%s%.6g", coefficients.empty() ? "" : ", ", c);
        coefficients += number;
      }
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.id.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%s %s", r.sensor_kind.c_str(), r.sensor_serial.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%s -> %s", r.input_unit.c_str(), r.unit.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(coefficients.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.method.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.date_utc.c_str());
    }
    ImGui::EndTable();
  }
  if (ImGui::CollapsingHeader("Strokes", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (!d.prepared) {
      ImGui::TextWrapped("Not prepared: %s", d.prepare_message.c_str());
    } else {
      int opening = 0;
      for (const Stroke& st : d.data.strokes) opening += st.direction == StrokeDirection::kOpening;
      ImGui::Text("%zu strokes (%d opening, %zu closing), %zu segments left out; angle: %s",
                  d.data.strokes.size(), opening, d.data.strokes.size() - std::size_t(opening),
                  d.data.excluded.size(), d.data.angle_source.c_str());
    }
  }
  ImGui::EndChild();
}

void Viewer::channels(SessionView& s) {
  if (s.channels.empty()) {
    ImGui::TextUnformatted("The session has no channels.");
    return;
  }
  const float avail = ImGui::GetContentRegionAvail().y;
  std::vector<std::string> groups;
  for (const ChannelInfo& c : s.data.channels) groups.push_back(channel_group(c));
  const bool grouped =
      std::any_of(groups.begin(), groups.end(), [](const std::string& g) { return !g.empty(); });
  ImGui::BeginChild("channels");
  if (!grouped) {
    const float each = stacked_height(avail, s.channels.size());
    for (std::size_t i = 0; i < s.channels.size(); ++i) {
      const std::string id = "channel" + std::to_string(i);
      plots_.push_back(
          plot_widget(id.c_str(), s.channels[i], s.channel_states[i], 0.0f, each, controls_));
    }
  } else {
    // A haptic session's many channels: a header per group (the door's open), two plots
    // side by side, scrolling.
    const float half =
        std::floor((ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x) * 0.5f);
    for (const std::string& group : channel_group_order()) {
      const auto count = std::count(groups.begin(), groups.end(), group);
      if (count == 0) continue;
      const std::string header = (group.empty() ? std::string("other") : group) + " (" +
                                 std::to_string(count) + " channels)###" + group;
      if (!ImGui::CollapsingHeader(header.c_str(),
                                   group == "door" ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
        continue;
      }
      int column = 0;
      for (std::size_t i = 0; i < s.channels.size(); ++i) {
        if (groups[i] != group) continue;
        if (column++ % 2 == 1) ImGui::SameLine();
        const std::string id = "channel" + std::to_string(i);
        ImGui::BeginGroup();  // so that SameLine puts the next plot beside this one
        plots_.push_back(
            plot_widget(id.c_str(), s.channels[i], s.channel_states[i], half, 170.0f, controls_));
        ImGui::EndGroup();
      }
    }
  }
  ImGui::EndChild();
}

void Viewer::live() {
  const LivePoll poll = live_->poll();
  // The plots are rebuilt at most 20 times a second (a fast rig's 10 s window costs about
  // 10 ms to rebuild: docs/PERFORMANCE.md), and at once when the state changes.
  const auto now = std::chrono::steady_clock::now();
  if (poll.state_changed || live_plots_.empty() ||
      now - live_rebuilt_ >= std::chrono::milliseconds(50)) {
    if (live_->update_plots(live_plots_)) {
      live_states_.resize(live_plots_.size());
      live_rebuilt_ = now;
    }
  }
  ImGui::Text("live: %s", live_->journal_path().string().c_str());
  ImGui::SameLine();
  // The state in colour: recording green, ended or gone amber, waiting grey.
  const LiveState state = live_->state();
  const ImVec4 colour = state == LiveState::kRecording ? ImVec4(0.3f, 0.9f, 0.3f, 1.0f)
                        : state == LiveState::kWaiting ? ImVec4(0.6f, 0.6f, 0.6f, 1.0f)
                                                       : ImVec4(1.0f, 0.7f, 0.2f, 1.0f);
  ImGui::TextColored(colour, "   %s", live_->status().c_str());
  if (live_plots_.empty()) {
    ImGui::TextUnformatted("Waiting for the recording's journal.");
    return;
  }
  const float avail = ImGui::GetContentRegionAvail().y;
  const float each = stacked_height(avail, live_plots_.size());
  ImGui::BeginChild("live");
  for (std::size_t i = 0; i < live_plots_.size(); ++i) {
    const std::string id = "live" + std::to_string(i);
    plots_.push_back(
        plot_widget(id.c_str(), live_plots_[i], live_states_[i], 0.0f, each, controls_));
  }
  ImGui::EndChild();
}

void Viewer::loop(SessionView& s) {
  if (!s.data.prepared) ImGui::TextWrapped("No strokes: %s", s.data.prepare_message.c_str());
  plots_.push_back(plot_widget("loop", s.loop, s.loop_state, 0.0f, 0.0f, controls_));
}

void Viewer::fit(SessionView& s) {
  if (!s.fit) {
    ImGui::TextWrapped("%s", kNoFitModel);
    return;
  }
  const plot_style::DisplayUnit rate = plot_style::display_unit("rad/s");  // as the plots
  ImGui::Text("%s: rate RMSE %.4g %s over windows (as the fit sees them)",
              s.fit->model_description.c_str(), s.fit->rmse_rad_s * rate.scale, rate.unit.c_str());
  const float avail = ImGui::GetContentRegionAvail().y;
  const bool whiteness = s.fit_plots.size() > 2;
  plots_.push_back(plot_widget("fit", s.fit_plots[0], s.fit_states[0], 0.0f,
                               std::floor(avail * (whiteness ? 0.5f : 0.65f)), controls_));
  plots_.push_back(plot_widget("residual", s.fit_plots[1], s.fit_states[1], 0.0f,
                               whiteness ? std::floor(avail * 0.24f) : 0.0f, controls_));
  if (whiteness) {
    plots_.push_back(
        plot_widget("whiteness", s.fit_plots[2], s.fit_states[2], 0.0f, 0.0f, controls_));
  } else if (!s.fit->whiteness_message.empty()) {
    ImGui::TextWrapped("No whiteness: %s", s.fit->whiteness_message.c_str());
  }
}

void Viewer::overlay() {
  if (!overlay_ || overlay_->plots.empty()) {
    ImGui::TextWrapped("%s", overlay_message_.c_str());
    return;
  }
  ImGui::Text("A: %s (stroke at %.4f s)   B: %s (stroke at %.4f s)   aligned on %s",
              sessions_[0].data.path.string().c_str(), overlay_->a_start_s,
              sessions_[1].data.path.string().c_str(), overlay_->b_start_s,
              overlay_->alignment.c_str());
  ImGui::TextWrapped("showing %s", overlay_->shown.c_str());
  if (controls_ && ImGui::Checkbox("raw channels too", &overlay_raw_)) {
    make_overlay();  // the next frame draws the new plots
    return;
  }
  const float avail = ImGui::GetContentRegionAvail().y;
  const float each = stacked_height(avail, overlay_->plots.size());
  ImGui::BeginChild("overlay");
  for (std::size_t i = 0; i < overlay_->plots.size(); ++i) {
    const std::string id = "overlay" + std::to_string(i);
    plots_.push_back(
        plot_widget(id.c_str(), overlay_->plots[i], overlay_states_[i], 0.0f, each, controls_));
  }
  ImGui::EndChild();
}

void Viewer::set_loop_steps(LoopSteps steps) {
  steps_plot_ = loop_steps_plot(steps);
  steps_ = std::move(steps);
}

void Viewer::steps() {
  if (!steps_) {
    ImGui::TextWrapped("%s", kNoLoop);
    return;
  }
  ImGui::Text("%s (loop on %s)", steps_->path.string().c_str(), steps_->source.c_str());
  if (ImGui::BeginTable("steps", 7, kTableFlags)) {
    for (const char* h : {"step", "effect", "parameters", "fitted RMSE [rad/s]",
                          "held out RMSE [rad/s]", "held-out improvement", "BIC change"}) {
      ImGui::TableSetupColumn(h);
    }
    ImGui::TableHeadersRow();
    for (const LoopStep& s : steps_->steps) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("%d", s.number);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(s.effect.c_str());
      ImGui::TableNextColumn();
      ImGui::TextWrapped("%s", s.parameters.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%.4g -> %.4g", s.fitted_before_rad_s, s.fitted_after_rad_s);
      ImGui::TableNextColumn();
      ImGui::Text("%.4g -> %.4g", s.held_out_before_rad_s, s.held_out_after_rad_s);
      ImGui::TableNextColumn();
      ImGui::Text("%.4g", s.held_out_improvement);
      ImGui::TableNextColumn();
      ImGui::Text("%.4g", s.bic_change);
    }
    ImGui::EndTable();
  }
  plots_.push_back(plot_widget("steps", steps_plot_, steps_state_, 0.0f, 0.0f, controls_));
}

namespace {

// "Reset to fitted" and "Save as" with its file name; whether the model was reset. A save
// or its error goes to `status`.
bool tuning_reset_and_save(Tuning& t, char* save_path, std::size_t save_path_size,
                           std::string& status) {
  bool changed = false;
  if (ImGui::Button("Reset to fitted")) {
    t.reset();
    changed = true;
  }
  ImGui::SetNextItemWidth(260.0f);
  ImGui::InputText("##save", save_path, save_path_size);
  ImGui::SameLine();
  if (ImGui::Button("Save as")) {
    try {
      const auto written = t.save(save_path);
      status = "wrote " + written.front().string();
    } catch (const std::exception& error) {
      status = error.what();
    }
  }
  return changed;
}

// Which strokes each change replays: a checkbox per stroke of the session, and buttons for
// the first 12, all, the openings and the closings. The selection re-simulates at once
// (measured, fitted and tuned curves for those strokes); a refusal goes to `status`.
void stroke_selection(Tuning& t, const std::vector<Stroke>& strokes, std::string& status) {
  const std::string strokes_header = std::string("Strokes (")
                                         .append(std::to_string(t.stroke_count()))
                                         .append(" of ")
                                         .append(std::to_string(t.session_stroke_count()))
                                         .append(" replayed)###strokes");
  if (!ImGui::CollapsingHeader(strokes_header.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
  auto select = [&status, &t](std::vector<int> chosen) {
    if (std::string problem = t.select_strokes(std::move(chosen)); !problem.empty())
      status = problem;
  };
  auto of_direction = [&strokes](StrokeDirection direction) {
    std::vector<int> chosen;
    for (std::size_t i = 0; i < strokes.size(); ++i) {
      if (strokes[i].direction == direction) chosen.push_back(int(i));
    }
    return chosen;
  };
  if (ImGui::Button("First 12")) {
    std::vector<int> first;
    for (int i = 0; i < int(t.session_stroke_count()) && i < 12; ++i) first.push_back(i);
    select(std::move(first));
  }
  ImGui::SameLine();
  if (ImGui::Button("All")) {
    std::vector<int> all(t.session_stroke_count());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = int(i);
    select(std::move(all));
  }
  ImGui::SameLine();
  if (ImGui::Button("Openings")) select(of_direction(StrokeDirection::kOpening));
  ImGui::SameLine();
  if (ImGui::Button("Closings")) select(of_direction(StrokeDirection::kClosing));
  ImGui::BeginChild("stroke list", ImVec2(0.0f, 160.0f), true);
  for (std::size_t i = 0; i < strokes.size(); ++i) {
    const Stroke& stroke = strokes[i];
    char label[96];
    std::snprintf(label, sizeof label, "%zu: stroke %d, %s, %.2f-%.2f s", i, stroke.id,
                  stroke.direction == StrokeDirection::kOpening ? "opening" : "closing",
                  stroke.time_s.empty() ? 0.0 : stroke.time_s.front(),
                  stroke.time_s.empty() ? 0.0 : stroke.time_s.back());
    bool on = t.is_selected(int(i));
    if (ImGui::Checkbox(label, &on)) {
      if (std::string problem = t.toggle_stroke(int(i)); !problem.empty()) status = problem;
    }
  }
  ImGui::EndChild();
}

// The sensory model's perceptual controls (spec 2) as drag fields; whether one changed
// the model (a refused value goes to `status`).
bool perceptual_control_fields(Tuning& t, std::string& status) {
  bool changed = false;
  ImGui::Separator();
  ImGui::TextUnformatted("Perceptual controls (spec 2)");
  for (const perceptual::ControlInfo& info : perceptual::controls()) {
    double value = perceptual::read(t.model(), info.control);
    const std::string label = std::string(info.name).append(" [").append(info.unit).append("]");
    const float speed = float(std::max(std::abs(value) * 0.003, 1e-6));
    if (ImGui::DragScalar(label.c_str(), ImGuiDataType_Double, &value, speed, nullptr, nullptr,
                          "%.5g")) {
      const std::string problem = t.set_control(info.control, value);
      if (problem.empty())
        changed = true;
      else
        status = problem;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", std::string(info.meaning).c_str());
  }
  return changed;
}

// The model's parameters: a slider within finite bounds, else a drag field; whether one
// changed the model (a refused value goes to `status`).
bool parameter_sliders(Tuning& t, std::string& status) {
  bool changed = false;
  ImGui::Separator();
  ImGui::TextUnformatted("Parameters");
  for (int i = 0; i < t.model().parameter_count(); ++i) {
    double value = t.model().parameter_values()[std::size_t(i)];
    const Bounds bounds = t.model().parameter_bounds()[std::size_t(i)];
    std::string label = t.model().parameter_name(i);
    const std::string_view unit = t.model().parameter_unit(i);
    if (!unit.empty()) label.append(" [").append(unit).append("]");
    bool moved = false;
    if (std::isfinite(bounds.lower) && std::isfinite(bounds.upper) && bounds.upper > bounds.lower) {
      moved = ImGui::SliderScalar(label.c_str(), ImGuiDataType_Double, &value, &bounds.lower,
                                  &bounds.upper, "%.5g");
    } else {
      const float speed = float(std::max(std::abs(value) * 0.003, 1e-6));
      moved = ImGui::DragScalar(label.c_str(), ImGuiDataType_Double, &value, speed, nullptr,
                                nullptr, "%.5g");
    }
    if (moved) {
      const std::string problem = t.set_parameter(i, value);
      if (problem.empty())
        changed = true;
      else
        status = problem;
    }
  }
  return changed;
}

}  // namespace

// The stages: the tuning made on first showing, then in the left child the reset and save
// row, the strokes replayed, the perceptual controls (sensory model) and the parameters;
// a change re-simulates; the tuned plot on the right.
void Viewer::tuning(SessionView& s) {
  if (!tuning_model_) {
    ImGui::TextWrapped("%s", kNoTuningModel);
    return;
  }
  if (!s.tuning && s.tuning_message.empty()) {
    try {
      if (!s.data.prepared) throw std::invalid_argument(s.data.prepare_message);
      s.tuning.emplace(s.data.data, *tuning_model_);
    } catch (const std::exception& error) {
      s.tuning_message = std::string("Cannot tune on this session: ").append(error.what());
    }
  }
  if (!s.tuning) {
    ImGui::TextWrapped("%s", s.tuning_message.c_str());
    return;
  }
  Tuning& t = *s.tuning;
  ImGui::BeginChild("sliders", ImVec2(500.0f, 0.0f), true);
  bool changed = tuning_reset_and_save(t, save_path_, sizeof save_path_, status_);
  ImGui::Separator();
  stroke_selection(t, s.data.data.strokes, status_);
  if (t.model().kind() == ModelKind::kSensory) {
    changed = perceptual_control_fields(t, status_) || changed;
  }
  changed = parameter_sliders(t, status_) || changed;
  ImGui::EndChild();
  if (changed) t.resimulate();
  ImGui::SameLine();
  ImGui::BeginChild("tuned");
  const plot_style::DisplayUnit rate = plot_style::display_unit("rad/s");  // as the plot
  ImGui::Text("%zu strokes replayed in %.1f ms; largest |w_meas - w_sim| %.4g %s", t.stroke_count(),
              t.last_resimulate_ms(), t.max_error_rad_s() * rate.scale, rate.unit.c_str());
  plots_.push_back(plot_widget("tuning", t.plot, s.tuning_state, 0.0f, 0.0f, controls_));
  ImGui::EndChild();
}

}  // namespace doorbench::viewer
