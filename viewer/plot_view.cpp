#include "viewer/plot_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace doorbench::viewer {

namespace {

// Keeps pixel coordinates of far-off samples within float range and ImGui's clipping.
float clamp_px(double v, double lo, double hi) {
  const double margin = 1.0e4;
  return float(std::clamp(v, lo - margin, hi + margin));
}

struct StripBuilder {
  DrawData& out;
  Rgba colour;
  float width_px;
  int layer;
  std::size_t begin = 0;
  bool open = false;

  void point(float x, float y) {
    if (!open) {
      begin = out.points.size();
      open = true;
    }
    out.points.push_back({x, y});
  }
  void close() {
    if (open && out.points.size() - begin >= 2) {
      out.strips.push_back({.begin = begin,
                            .end = out.points.size(),
                            .colour = colour,
                            .width_px = width_px,
                            .layer = layer});
    } else if (open) {
      out.points.resize(begin);  // a lone point draws nothing
    }
    open = false;
  }
};

void fit_range(Range& range, double lo, double hi, double margin) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    range = {0.0, 1.0};
    return;
  }
  if (hi - lo <= 0.0) {
    range = {lo - 0.5, hi + 0.5};
    return;
  }
  const double pad = (hi - lo) * margin;
  range = {lo - pad, hi + pad};
}

}  // namespace

void PlotView::add(std::shared_ptr<const Series> s) {
  if (!s) throw std::invalid_argument("plot '" + title + "': null series");
  if (!series.empty() && s->is_xy() != is_xy()) {
    throw std::invalid_argument(std::string("plot '")
                                    .append(title)
                                    .append("': series '")
                                    .append(s->name())
                                    .append("' mixes x-y and time series in one plot"));
  }
  series.push_back(std::move(s));
}

void PlotView::fit_x() {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const auto& s : series) {
    double x0, x1, y0, y1;
    s->bounds(x0, x1, y0, y1);
    lo = std::min(lo, x0);
    hi = std::max(hi, x1);
  }
  fit_range(*x, lo, hi, is_xy() ? 0.05 : 0.0);
}

void PlotView::fit_y(double margin) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const auto& s : series) {
    std::size_t begin = 0, end = s->size();
    if (!s->is_xy()) s->index_range(x->min, x->max, begin, end);
    double y0, y1;
    s->y_range(begin, end, y0, y1);
    lo = std::min(lo, y0);
    hi = std::max(hi, y1);
  }
  fit_range(y, lo, hi, margin);
}

double PlotView::to_px_x(double xv, const Rect& r) const {
  return r.x + (xv - x->min) / x->span() * r.width;
}
double PlotView::to_px_y(double yv, const Rect& r) const {
  return r.y + r.height - (yv - y.min) / y.span() * r.height;
}
double PlotView::from_px_x(double px, const Rect& r) const {
  return x->min + (px - r.x) / r.width * x->span();
}
double PlotView::from_px_y(double py, const Rect& r) const {
  return y.min + (r.y + r.height - py) / r.height * y.span();
}

void PlotView::zoom_about(double factor, double px, double py, const Rect& r, bool y_too) {
  if (!(factor > 0.0) || !std::isfinite(factor)) return;
  const double xc = from_px_x(px, r);
  *x = {xc - (xc - x->min) * factor, xc + (x->max - xc) * factor};
  if (y_too) {
    const double yc = from_px_y(py, r);
    y = {yc - (yc - y.min) * factor, yc + (y.max - yc) * factor};
  }
}

void PlotView::pan_px(double dx_px, double dy_px, const Rect& r) {
  const double dx = dx_px / r.width * x->span();
  const double dy = dy_px / r.height * y.span();
  *x = {x->min - dx, x->max - dx};
  y = {y.min + dy, y.max + dy};
}

bool PlotView::box_zoom(double px0, double py0, double px1, double py1, const Rect& r) {
  if (std::abs(px1 - px0) < 3.0 || std::abs(py1 - py0) < 3.0) return false;
  const double xa = from_px_x(std::min(px0, px1), r), xb = from_px_x(std::max(px0, px1), r);
  const double ya = from_px_y(std::max(py0, py1), r), yb = from_px_y(std::min(py0, py1), r);
  *x = {xa, xb};
  y = {ya, yb};
  return true;
}

std::vector<Readout> PlotView::readout(double px, double py, const Rect& r) const {
  std::vector<Readout> result;
  const double xq = from_px_x(px, r), yq = from_px_y(py, r);
  for (const auto& s : series) {
    if (s->size() == 0) continue;
    const std::size_t i = s->nearest(xq, yq, r.width / x->span(), r.height / y.span());
    if (i >= s->size()) continue;
    result.push_back({.series = s->name(),
                      .unit = s->unit(),
                      .x_unit = s->x_unit(),
                      .index = i,
                      .x = s->x(i),
                      .y = s->y(i)});
  }
  return result;
}

void PlotView::build_draw_data(const Rect& r, DrawData& out) const {
  out.clear();
  const std::size_t width = std::max<std::size_t>(1, std::size_t(std::lround(r.width)));
  const double top = r.y, bottom = r.y + r.height, left = r.x, right = r.x + r.width;
  for (const auto& s : series) {
    StripBuilder strip{.out = out, .colour = s->colour, .width_px = s->width_px, .layer = s->layer};
    if (s->is_xy()) {
      float last_x = NAN, last_y = NAN;
      for (std::size_t i = 0; i < s->size(); ++i) {
        const double xv = s->x(i), yv = s->y(i);
        if (!std::isfinite(xv) || !std::isfinite(yv)) {
          strip.close();
          last_x = last_y = NAN;
          continue;
        }
        const float px = clamp_px(to_px_x(xv, r), left, right);
        const float py = clamp_px(to_px_y(yv, r), top, bottom);
        // Consecutive points in the same pixel add nothing visible.
        if (std::lround(px) == std::lround(last_x) && std::lround(py) == std::lround(last_y)) {
          continue;
        }
        strip.point(px, py);
        last_x = px;
        last_y = py;
      }
      strip.close();
      out.visible_samples += s->size();
      continue;
    }
    std::size_t begin = 0, end = 0;
    s->index_range(x->min, x->max, begin, end);
    out.visible_samples += end - begin;
    if (end - begin <= 2 * width) {
      // Few samples: draw each, with one neighbour either side so lines reach the edges.
      const std::size_t b = begin > 0 ? begin - 1 : 0;
      const std::size_t e = std::min(s->size(), end + 1);
      for (std::size_t i = b; i < e; ++i) {
        const double yv = s->y(i);
        if (!std::isfinite(yv)) {
          strip.close();
          continue;
        }
        strip.point(clamp_px(to_px_x(s->x(i), r), left, right),
                    clamp_px(to_px_y(yv, r), top, bottom));
      }
      strip.close();
      continue;
    }
    decimate_into(*s, x->min, x->max, width, out.columns);
    for (std::size_t c = 0; c < width; ++c) {
      const Column& col = out.columns[c];
      if (col.count == 0) continue;  // a gap in explicit times: bridge it
      if (!std::isfinite(col.min)) {
        strip.close();  // all NaN
        continue;
      }
      const float px = float(left + double(c) + 0.5);
      const double first = std::isfinite(col.first) ? col.first : col.min;
      const double last = std::isfinite(col.last) ? col.last : col.max;
      strip.point(px, clamp_px(to_px_y(first, r), top, bottom));
      strip.point(px, clamp_px(to_px_y(col.min, r), top, bottom));
      strip.point(px, clamp_px(to_px_y(col.max, r), top, bottom));
      strip.point(px, clamp_px(to_px_y(last, r), top, bottom));
    }
    strip.close();
  }
}

std::string visible_csv(const PlotView& view) {
  std::string csv = "series,x,y,x_unit,y_unit\n";
  char row[160];
  for (const auto& s : view.series) {
    std::size_t begin = 0, end = s->size();
    if (!s->is_xy()) s->index_range(view.x->min, view.x->max, begin, end);
    // Names and units are written as they are: [A-Za-z0-9_ /.] in doorbench; quote if not.
    auto field = [](const std::string& text) {
      if (text.find_first_of(",\"\n") == std::string::npos) return text;
      std::string quoted(1, '"');
      for (char c : text) {
        if (c == '"') quoted.push_back('"');
        quoted.push_back(c);
      }
      quoted.push_back('"');
      return quoted;
    };
    std::string suffix(1, ',');
    suffix.append(field(s->x_unit())).append(1, ',').append(field(s->unit())).append(1, '\n');
    const std::string name = field(s->name());
    for (std::size_t i = begin; i < end; ++i) {
      const double xv = s->x(i), yv = s->y(i);
      if (s->is_xy() &&
          !(xv >= view.x->min && xv <= view.x->max && yv >= view.y.min && yv <= view.y.max)) {
        continue;
      }
      std::snprintf(row, sizeof row, ",%.17g,%.17g", xv, yv);
      csv.append(name).append(row).append(suffix);
    }
  }
  return csv;
}

std::vector<double> nice_ticks(double min, double max, int target, double min_step) {
  std::vector<double> ticks;
  const double span = max - min;
  if (!std::isfinite(span) || !(span > 0.0) || target < 1) return ticks;
  const double raw = span / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / magnitude;
  double step = (norm < 1.5 ? 1.0 : norm < 3.5 ? 2.0 : norm < 7.5 ? 5.0 : 10.0) * magnitude;
  if (min_step > 0.0) step = std::max(step, min_step);
  const double first = std::ceil(min / step - 1e-9);
  for (double k = first;; k += 1.0) {
    const double v = k * step;
    if (v > max + step * 1e-9) break;
    ticks.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
    if (ticks.size() > 1000) break;
  }
  // One tick says nothing about the scale: ask for more until two fit (not below min_step).
  if (ticks.size() < 2 && target < 64 && !(min_step > 0.0 && step <= min_step)) {
    return nice_ticks(min, max, target * 2, min_step);
  }
  return ticks;
}

std::string tick_label(double value, double step) {
  char text[64];
  // Very small or large steps: a few significant digits with an exponent, not 0.000005.
  if (step > 0.0 && std::isfinite(step) && (step < 1e-3 || step >= 1e6)) {
    std::snprintf(text, sizeof text, "%.3g", std::abs(value) < step * 1e-9 ? 0.0 : value);
    return text;
  }
  int decimals = 0;
  if (step > 0.0 && std::isfinite(step)) {
    decimals = std::max(0, int(-std::floor(std::log10(step) + 1e-9)));
  }
  std::snprintf(text, sizeof text, "%.*f", std::min(decimals, 12), value);
  return text;
}

}  // namespace doorbench::viewer
