#include "viewer/session_data.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fitting.h"
#include "analysis/preprocessing/preprocessing.h"
#include "core/numbers.h"
#include "sensors/channel_limits.h"

namespace doorbench::viewer {

namespace {

// A channel's series; `limit` (or null): its stretches at the limit as shades in `at_limit`.
std::shared_ptr<Series> channel_series(const SessionReader& reader, const ChannelInfo& info,
                                       const sensors::ChannelLimit* limit,
                                       std::vector<Shade>& at_limit) {
  const ChannelSlice slice = reader.read(info.name);
  std::vector<double> values = reader.physical(info.name, slice);
  const std::vector<sensors::SampleStretch> stretches =
      limit != nullptr ? sensors::limit_stretches(values, limit->limit)
                       : std::vector<sensors::SampleStretch>{};
  const std::string unit = to_display_units(info.unit, values);
  std::shared_ptr<Series> series;
  if (info.sample_rate_hz > 0.0) {
    const double t0 = info.first_sample_time_s + double(slice.first_index) / info.sample_rate_hz;
    series = std::make_shared<Series>(
        Series::uniform(info.name, unit, t0, 1.0 / info.sample_rate_hz, std::move(values)));
  } else {
    series =
        std::make_shared<Series>(Series::timed(info.name, unit, slice.time_s, std::move(values)));
  }
  const plot_style::ShadeStyle& style = plot_style::kAtLimitShade;
  const Rgba colour{style.r, style.g, style.b, std::uint8_t(std::lround(255.0 * style.opacity))};
  for (const sensors::SampleStretch& stretch : stretches) {
    const std::size_t after = stretch.end < series->size() ? stretch.end : stretch.end - 1;
    at_limit.push_back(
        {.x0 = series->x(stretch.begin),
         .x1 = series->x(after),
         .colour = colour,
         .label = limit->sensor + " " + info.name + " at its " + limit->range + " limit"});
  }
  return series;
}

std::shared_ptr<Series> loop_series(const PreparedData& data, StrokeDirection direction,
                                    const std::string& name, plot_style::Meaning meaning) {
  std::vector<double> angle, force;
  for (const Stroke& stroke : data.strokes) {
    if (stroke.direction != direction) continue;
    if (!angle.empty()) {
      angle.push_back(kNaN);
      force.push_back(kNaN);
    }
    angle.insert(angle.end(), stroke.theta_rad.begin(), stroke.theta_rad.end());
    force.insert(force.end(), stroke.force_N.begin(), stroke.force_N.end());
  }
  const std::string angle_unit = to_display_units("rad", angle);
  auto series = std::make_shared<Series>(
      Series::xy(name, angle_unit, "N", std::move(angle), std::move(force)));
  style_series(*series, meaning);
  return series;
}

// One of the door's quantities over the prepared strokes on the session clock, strokes in
// time order separated by a NaN sample between them (SessionData::door_angle, ...).
std::shared_ptr<Series> door_series(const PreparedData& data, const std::string& name,
                                    const std::string& stored_unit,
                                    std::vector<double> Stroke::*member) {
  std::vector<const Stroke*> strokes;
  for (const Stroke& stroke : data.strokes) {
    if (!stroke.time_s.empty()) strokes.push_back(&stroke);
  }
  std::stable_sort(strokes.begin(), strokes.end(), [](const Stroke* x, const Stroke* y) {
    return x->time_s.front() < y->time_s.front();
  });
  std::vector<double> t, values;
  for (const Stroke* stroke : strokes) {
    if (!t.empty()) {
      if (stroke->time_s.front() < t.back()) continue;  // overlaps the one before: left out
      t.push_back(0.5 * (t.back() + stroke->time_s.front()));
      values.push_back(kNaN);
    }
    t.insert(t.end(), stroke->time_s.begin(), stroke->time_s.end());
    values.insert(values.end(), (stroke->*member).begin(), (stroke->*member).end());
  }
  const std::string unit = to_display_units(stored_unit, values);
  return std::make_shared<Series>(Series::timed(name, unit, std::move(t), std::move(values)));
}

// Stroke events for a session whose file has none (see SessionData::events).
void add_found_stroke_events(SessionData& session) {
  for (const SessionEvent& e : session.events) {
    if (e.kind == "stroke_start") return;
  }
  if (!session.prepared || session.data.strokes.empty()) return;
  for (const Stroke& stroke : session.data.strokes) {
    const std::string direction =
        stroke.direction == StrokeDirection::kOpening ? "opening" : "closing";
    session.events.push_back({.time_s = motion_onset_s(stroke),
                              .kind = "stroke_start",
                              .channel = "",
                              .detail = direction});
    session.events.push_back(
        {.time_s = motion_end_s(stroke), .kind = "stroke_end", .channel = "", .detail = direction});
  }
  std::stable_sort(
      session.events.begin(), session.events.end(),
      [](const SessionEvent& x, const SessionEvent& y) { return x.time_s < y.time_s; });
  session.strokes_found_on_read = true;
}

}  // namespace

Rgba meaning_colour(plot_style::Meaning meaning, bool opaque) {
  const plot_style::LineStyle style = plot_style::line_style(meaning);
  const double alpha = opaque ? 1.0 : style.viewer_opacity;
  return {style.r, style.g, style.b, std::uint8_t(std::lround(255.0 * alpha))};
}

void style_series(Series& series, plot_style::Meaning meaning) {
  const plot_style::LineStyle style = plot_style::line_style(meaning);
  series.colour = meaning_colour(meaning);
  series.width_px = float(style.viewer_width_px);
  series.layer = style.layer;
}

std::string to_display_units(const std::string& stored_unit, std::vector<double>& values) {
  const plot_style::DisplayUnit shown = plot_style::display_unit(stored_unit);
  if (shown.scale != 1.0) {
    for (double& v : values) v *= shown.scale;
  }
  return shown.unit;
}

Rgba palette(std::size_t index) {
  static constexpr Rgba colours[] = {{230, 90, 40, 255},   {40, 140, 230, 255}, {60, 180, 75, 255},
                                     {220, 190, 30, 255},  {170, 80, 200, 255}, {30, 200, 200, 255},
                                     {240, 120, 180, 255}, {150, 150, 150, 255}};
  return colours[index % (sizeof colours / sizeof colours[0])];
}

SessionData load_session(const std::filesystem::path& path, const LoadOptions& options) {
  const SessionReader reader(path);
  SessionData session;
  session.path = path;
  session.metadata = reader.metadata();
  session.channels = reader.channels();
  session.events = reader.events();
  session.calibrations = reader.calibrations();
  const std::vector<sensors::ChannelLimit> limits =
      sensors::session_channel_limits(session.metadata);
  for (std::size_t i = 0; i < session.channels.size(); ++i) {
    const ChannelInfo& info = session.channels[i];
    session.sample_counts.push_back(reader.sample_count(info.name));
    const sensors::ChannelLimit* limit = nullptr;
    for (const sensors::ChannelLimit& l : limits) {
      if (l.channel == info.name) limit = &l;
    }
    session.at_limit.emplace_back();
    session.channel_series.push_back(channel_series(reader, info, limit, session.at_limit.back()));
    session.channel_series.back()->colour = palette(i);
  }
  if (options.prepare) {
    try {
      session.data = prepare_session(path);
      session.prepared = true;
    } catch (const std::exception& error) {
      session.prepare_message = error.what();
    }
  } else {
    session.prepare_message = "strokes not prepared";
  }
  add_found_stroke_events(session);
  if (session.prepared && !session.data.strokes.empty()) {
    session.door_angle = door_series(session.data, "angle", "rad", &Stroke::theta_rad);
    session.door_force = door_series(session.data, "force", "N", &Stroke::force_N);
    session.door_rate = door_series(session.data, "rate", "rad/s", &Stroke::omega_rad_s);
  }
  session.opening_loop = loop_series(session.data, StrokeDirection::kOpening, "opening",
                                     plot_style::Meaning::kOpening);
  session.closing_loop = loop_series(session.data, StrokeDirection::kClosing, "closing",
                                     plot_style::Meaning::kClosing);
  return session;
}

FitComparison compare_with_model(const SessionData& session, const DoorModel& model,
                                 const std::string& description) {
  if (!session.prepared || session.data.strokes.empty()) {
    throw std::invalid_argument(
        std::string(session.path.string())
            .append(": no strokes to compare the model with (")
            .append(session.prepared ? "none found" : session.prepare_message)
            .append(")"));
  }
  const WindowOptions windows = metric_window_options(FitOptions{}, model);
  const WindowSimulation sim = simulate_windows(model, session.data, windows);
  std::vector<double> t, measured, simulated, residual;
  std::vector<std::vector<double>> stroke_residuals, stroke_forces;
  double sum_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < session.data.strokes.size(); ++k) {
    const Stroke& stroke = session.data.strokes[k];
    if (!t.empty()) {
      // A NaN between strokes breaks the lines; its time sits between them.
      t.push_back(0.5 * (t.back() + stroke.time_s.front()));
      measured.push_back(kNaN);
      simulated.push_back(kNaN);
      residual.push_back(kNaN);
    }
    stroke_residuals.emplace_back();
    stroke_forces.push_back(stroke.force_N);
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      const double hat = sim.omega_rad_s[k][i];
      stroke_residuals.back().push_back(stroke.omega_rad_s[i] - hat);
      t.push_back(stroke.time_s[i]);
      measured.push_back(stroke.omega_rad_s[i]);
      simulated.push_back(hat);
      residual.push_back(stroke.omega_rad_s[i] - hat);
      if (std::isfinite(hat)) {
        sum_sq += residual.back() * residual.back();
        ++count;
      }
    }
  }
  FitComparison comparison;
  comparison.model_description = description;
  const std::string rate_unit = to_display_units("rad/s", measured);
  to_display_units("rad/s", simulated);
  to_display_units("rad/s", residual);
  comparison.measured = std::make_shared<Series>(Series::timed("measured", rate_unit, t, measured));
  comparison.simulated =
      std::make_shared<Series>(Series::timed("simulated", rate_unit, t, simulated));
  comparison.residual =
      std::make_shared<Series>(Series::timed("residual", rate_unit, std::move(t), residual));
  style_series(*comparison.measured, plot_style::Meaning::kMeasured);
  style_series(*comparison.simulated, plot_style::Meaning::kSimulated);
  style_series(*comparison.residual, plot_style::Meaning::kResidual);
  comparison.rmse_rad_s = count > 0 ? std::sqrt(sum_sq / double(count)) : kNaN;
  const double step_s = session.data.interval_median_s;
  try {
    comparison.whiteness =
        residual_whiteness(stroke_residuals, stroke_forces, step_s, whiteness_max_lag(step_s));
  } catch (const std::invalid_argument& error) {
    comparison.whiteness_message = error.what();
  }
  return comparison;
}

std::string channel_group(const ChannelInfo& channel) {
  const std::string& kind = channel.sensor_kind;
  if (kind == "haptic_force" || kind == "haptic_angle" || kind == "haptic_rate") return "door";
  if (kind == "haptic_position" || kind == "haptic_velocity" || kind == "haptic_force_sensor" ||
      kind == "haptic_command") {
    return "device";
  }
  if (kind == "haptic_model") return "model";
  if (kind == "haptic_safety" || kind == "haptic_constraint" || kind == "haptic_parameters") {
    return "safety";
  }
  return "";
}

std::vector<PlotView> channel_plots(const SessionData& session) {
  std::vector<PlotView> plots;
  for (std::size_t i = 0; i < session.channels.size(); ++i) {
    PlotView plot;
    plot.title = session.channels[i].name;
    plot.x_label = "time";
    plot.y_label = session.channels[i].name;
    plot.add(session.channel_series[i]);
    plot.markers = event_markers(session, session.channels[i].name);
    if (i < session.at_limit.size()) plot.shades = session.at_limit[i];
    if (!plots.empty()) plot.link_x_to(plots.front());
    plots.push_back(std::move(plot));
  }
  if (!plots.empty()) {
    plots.front().fit_x();
    for (PlotView& plot : plots) plot.fit_y();
  }
  return plots;
}

PlotView loop_plot(const SessionData& session) {
  PlotView plot;
  plot.title = "force against angle";
  plot.x_label = "angle";
  plot.y_label = "force";
  plot.add(session.opening_loop);
  plot.add(session.closing_loop);
  plot.fit();
  return plot;
}

PlotView whiteness_plot(const ResidualWhiteness& w) {
  PlotView plot;
  plot.title = "residual whiteness (99 % band): " + w.summary();
  plot.x_label = "lag";
  const int max_lag = int(w.autocorrelation.size()) - 1;
  const double dx = w.lag_step_s > 0 ? w.lag_step_s : 1.0;
  auto autocorrelation =
      std::make_shared<Series>(Series::uniform("autocorrelation", "", 0.0, dx, w.autocorrelation));
  style_series(*autocorrelation, plot_style::Meaning::kResidual);
  auto cross = std::make_shared<Series>(
      Series::uniform("cross-correlation with force", "", -max_lag * dx, dx, w.cross_correlation));
  cross->colour = palette(3);
  plot.add(autocorrelation);
  plot.add(cross);
  for (double sign : {1.0, -1.0}) {
    auto band = std::make_shared<Series>(
        Series::uniform(sign > 0 ? "+99 %" : "-99 %", "", -max_lag * dx, 2.0 * max_lag * dx,
                        std::vector<double>{sign * w.band, sign * w.band}));
    style_series(*band, plot_style::Meaning::kOther);
    band->width_px = 1.0f;
    plot.add(band);
  }
  plot.fit();
  return plot;
}

std::vector<PlotView> fit_plots(const FitComparison& comparison) {
  std::vector<PlotView> plots(2);
  plots[0].title = "rate: measured and " + comparison.model_description;
  plots[0].x_label = "time";
  plots[0].y_label = "rate";
  plots[0].add(comparison.measured);
  plots[0].add(comparison.simulated);
  plots[1].title = "residual (measured - simulated)";
  plots[1].x_label = "time";
  plots[1].y_label = "residual";
  plots[1].add(comparison.residual);
  plots[1].link_x_to(plots[0]);
  plots[0].fit();
  plots[1].fit_y();
  if (comparison.whiteness) plots.push_back(whiteness_plot(*comparison.whiteness));
  return plots;
}

}  // namespace doorbench::viewer

namespace doorbench::viewer {

bool event_marker(const SessionEvent& e, Marker& marker) {
  Rgba colour;
  if (e.kind == "stroke_start" || e.kind == "stroke_end") {
    colour = meaning_colour(e.detail == "closing" ? plot_style::Meaning::kClosing
                                                  : plot_style::Meaning::kOpening);
    colour.a = 110;
    if (e.kind == "stroke_end") colour = {170, 170, 170, 90};
  } else if (e.kind == "fault" || e.kind == "gap") {
    colour = {255, 0, 255, 200};
  } else if (e.kind == "trigger") {
    colour = {255, 255, 255, 160};
  } else if (e.kind == "mark") {
    colour = {200, 200, 120, 160};
  } else if (e.kind == "stop") {
    colour = {255, 60, 60, 200};
  } else {
    return false;
  }
  std::string label = e.kind;
  if (!e.detail.empty()) label.append(" ").append(e.detail);
  marker = {e.time_s, colour, std::move(label)};
  return true;
}

std::vector<Marker> event_markers(const SessionData& session, const std::string& channel) {
  return event_markers_of(session.events, channel);
}

double first_stroke_start_s(const SessionData& session, const std::string& direction) {
  double first = std::numeric_limits<double>::infinity();
  for (const SessionEvent& e : session.events) {
    if (e.kind == "stroke_start" && (direction.empty() || e.detail == direction)) {
      first = std::min(first, e.time_s);
    }
  }
  if (!std::isfinite(first)) {
    throw std::invalid_argument(std::string(session.path.string())
                                    .append(": no stroke_start event")
                                    .append(direction.empty() ? "" : " of direction " + direction)
                                    .append(" to align on"));
  }
  return first;
}

double motion_onset_s(const Stroke& stroke) {
  const double threshold = PreprocessingOptions{}.motion_rate_rad_s;
  for (std::size_t i = 0; i < stroke.size(); ++i) {
    if (std::abs(stroke.omega_rad_s[i]) > threshold) return stroke.time_s[i];
  }
  return stroke.time_s.empty() ? kNaN : stroke.time_s.front();
}

double motion_end_s(const Stroke& stroke) {
  const double threshold = PreprocessingOptions{}.motion_rate_rad_s;
  for (std::size_t i = stroke.size(); i-- > 0;) {
    if (std::abs(stroke.omega_rad_s[i]) > threshold) return stroke.time_s[i];
  }
  return stroke.time_s.empty() ? kNaN : stroke.time_s.back();
}

double first_motion_onset_s(const SessionData& session, const std::string& direction) {
  double first = std::numeric_limits<double>::infinity();
  for (const Stroke& stroke : session.data.strokes) {
    const bool opening = stroke.direction == StrokeDirection::kOpening;
    if (!direction.empty() && direction != (opening ? "opening" : "closing")) continue;
    if (!stroke.time_s.empty()) first = std::min(first, motion_onset_s(stroke));
  }
  if (!std::isfinite(first)) {
    throw std::invalid_argument(
        std::string(session.path.string())
            .append(": no stroke")
            .append(direction.empty() ? "" : " of direction " + direction)
            .append(" found from its motion to align on")
            .append(session.prepared ? "" : " (" + session.prepare_message + ")"));
  }
  return first;
}

namespace {

// The stretches where `session`'s channel `index` sat at its sensor's limit, on the
// overlay's clock (shifted by -start_s), labelled with the session ("A session.h5: ...")
// and `consequence`; all gyroscopes' when `index` is npos (the door's quantities: preprocessing
// integrates the rate, so the angle and the rate are not known where it is clipped).
void add_limit_shades(const SessionData& session, const std::string& who, double start_s,
                      std::size_t index, const std::string& consequence, PlotView& plot) {
  for (std::size_t i = 0; i < session.at_limit.size() && i < session.channels.size(); ++i) {
    const bool wanted =
        index == std::string::npos ? session.channels[i].sensor_kind == "gyroscope" : i == index;
    if (!wanted) continue;
    for (Shade shade : session.at_limit[i]) {
      shade.x0 -= start_s;
      shade.x1 -= start_s;
      shade.label = who + " " + session.path.filename().string() + ": " + shade.label + consequence;
      plot.shades.push_back(std::move(shade));
    }
  }
}

// One overlay plot: A's and B's series shifted to their stroke starts, A as measured on top,
// B opaque and wider beneath, so that both show where they coincide.
PlotView overlay_plot(const Overlay& overlay, const SessionData& a, const Series& series_a,
                      const SessionData& b, const Series& series_b, std::string title,
                      std::string y_label) {
  PlotView plot;
  plot.title = std::move(title);
  plot.x_label = "time since stroke start";
  plot.y_label = std::move(y_label);
  auto sa = std::make_shared<Series>(
      series_a.shifted(-overlay.a_start_s, "A " + a.path.filename().string()));
  auto sb = std::make_shared<Series>(
      series_b.shifted(-overlay.b_start_s, "B " + b.path.filename().string()));
  style_series(*sa, plot_style::Meaning::kMeasured);
  sb->colour = meaning_colour(plot_style::Meaning::kSimulated, true);
  sb->width_px = 4.0f;
  sb->layer = 1;
  plot.add(sa);
  plot.add(sb);
  return plot;
}

}  // namespace

Overlay overlay_plots(const SessionData& a, const SessionData& b, const std::string& direction,
                      bool raw_channels) {
  Overlay overlay;
  const bool by_events = !a.strokes_found_on_read && !b.strokes_found_on_read;
  overlay.alignment = by_events ? "stroke_start events" : "motion onset";
  overlay.a_start_s =
      by_events ? first_stroke_start_s(a, direction) : first_motion_onset_s(a, direction);
  overlay.b_start_s =
      by_events ? first_stroke_start_s(b, direction) : first_motion_onset_s(b, direction);
  const std::string aligned = ": A and B, aligned on stroke start (" + overlay.alignment + ")";
  const bool physical = a.door_angle && b.door_angle;
  if (physical) {
    overlay.shown =
        "the door's angle (fused from inclinometer and gyroscope), hand force (+ opening, as "
        "export signs it) and rate, from the prepared strokes";
    overlay.plots.push_back(overlay_plot(overlay, a, *a.door_angle, b, *b.door_angle,
                                         "angle (fused)" + aligned, "door angle"));
    overlay.plots.push_back(overlay_plot(overlay, a, *a.door_force, b, *b.door_force,
                                         "force (handle, + opening)" + aligned, "hand force"));
    overlay.plots.push_back(overlay_plot(overlay, a, *a.door_rate, b, *b.door_rate,
                                         "rate (bias removed)" + aligned, "door rate"));
    // Where a gyroscope sat at its limit the door's angle and rate are not known: the prepared
    // strokes leave those samples out (the curves break) and the stretch is shaded.
    for (PlotView& plot : overlay.plots) {
      const std::string consequence = ", the door's angle and rate not known there";
      add_limit_shades(a, "A", overlay.a_start_s, std::string::npos, consequence, plot);
      add_limit_shades(b, "B", overlay.b_start_s, std::string::npos, consequence, plot);
    }
    if (raw_channels) overlay.shown += " and the raw channels";
  } else {
    const SessionData& unprepared = a.door_angle ? b : a;
    overlay.shown = std::string("raw channels: ")
                        .append(unprepared.path.filename().string())
                        .append(" is not prepared into strokes (")
                        .append(unprepared.prepared ? "none found" : unprepared.prepare_message)
                        .append(")");
  }
  if (!physical || raw_channels) {
    for (std::size_t i = 0; i < a.channels.size(); ++i) {
      for (std::size_t j = 0; j < b.channels.size(); ++j) {
        if (a.channels[i].name != b.channels[j].name) continue;
        overlay.plots.push_back(
            overlay_plot(overlay, a, *a.channel_series[i], b, *b.channel_series[j],
                         "channel " + a.channels[i].name + aligned, a.channels[i].name));
        add_limit_shades(a, "A", overlay.a_start_s, i, "", overlay.plots.back());
        add_limit_shades(b, "B", overlay.b_start_s, j, "", overlay.plots.back());
      }
    }
  }
  for (std::size_t i = 1; i < overlay.plots.size(); ++i) {
    overlay.plots[i].link_x_to(overlay.plots.front());
  }
  if (!overlay.plots.empty()) {
    overlay.plots.front().fit_x();
    for (PlotView& plot : overlay.plots) plot.fit_y();
  }
  return overlay;
}

}  // namespace doorbench::viewer
