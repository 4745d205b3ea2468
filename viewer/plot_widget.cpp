#include "viewer/plot_widget.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace doorbench::viewer {

namespace {

constexpr float kLeftMargin = 64.0f;    // y tick labels
constexpr float kBottomMargin = 20.0f;  // x tick labels
constexpr float kHeaderHeight = 20.0f;  // title and legend, above the data area

const ImU32 kFrameColour = IM_COL32(120, 120, 120, 255);
const ImU32 kGridColour = IM_COL32(60, 60, 60, 255);
const ImU32 kTextColour = IM_COL32(210, 210, 210, 255);
const ImU32 kBackground = IM_COL32(20, 20, 24, 255);

std::string with_unit(const std::string& label, const std::string& unit) {
  if (unit.empty()) return label;
  return std::string(label).append(" [").append(unit).append("]");
}

// The header's texts: the title, each series' "name [unit]", "x: label [unit]", and the
// first shade's label.
std::vector<std::string> header_items(const PlotView& view) {
  std::vector<std::string> items;
  items.push_back(view.title);
  for (const auto& s : view.series) items.push_back(with_unit(s->name(), s->unit()));
  if (!view.series.empty()) {
    items.push_back("x: " + with_unit(view.x_label, view.series.front()->x_unit()));
  }
  if (!view.shades.empty()) items.push_back("shaded: " + view.shades.front().label);
  return items;
}

// Header: title, then each series' colour, name and unit, the x quantity and unit last
// (outside the data area, so that only curves and grid are drawn inside it). Items that
// do not fit on a line go on the next one, so that the legend is never cut. Returns the
// header's height.
float draw_header(const PlotView& view, const std::vector<std::string>& items, ImVec2 origin,
                  float width, bool controls, ImDrawList* draw) {
  const float line_end = origin.x + width - (controls ? 90.0f : 8.0f);
  std::vector<ImVec2> at(items.size());
  float hx = origin.x + 4.0f, hy = origin.y + 2.0f;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const bool swatch = i > 0 && i <= view.series.size();
    const float w = ImGui::CalcTextSize(items[i].c_str()).x + (swatch ? 14.0f : 0.0f);
    if (i > 0 && hx + w > line_end) {
      hx = origin.x + 4.0f;
      hy += kHeaderHeight - 2.0f;
    }
    at[i] = ImVec2(hx, hy);
    hx += w + 16.0f;
  }
  const float header_height = hy - origin.y + kHeaderHeight - 2.0f;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const bool swatch = i > 0 && i <= view.series.size();
    ImVec2 p = at[i];
    if (swatch) {
      Rgba swatch_colour = view.series[i - 1]->colour;
      swatch_colour.a = 255;  // the colour itself, even for a translucent curve
      draw->AddRectFilled(ImVec2(p.x, p.y + 4.0f), ImVec2(p.x + 10.0f, p.y + 14.0f),
                          to_imgui_colour(swatch_colour));
      p.x += 14.0f;
    }
    const bool x_item = i > view.series.size() && i > 0;
    draw->AddText(p, x_item ? IM_COL32(160, 160, 160, 255) : kTextColour, items[i].c_str());
  }
  return header_height;
}

// The mouse over the data area this frame.
struct Pointer {
  bool hovered = false;
  double mx = 0.0, my = 0.0;
};

// Input: an invisible button over the data area; the wheel zooms, a left drag pans, a
// right drag zooms to its box, a double click fits.
Pointer handle_input(PlotView& view, PlotWidgetState& state, const Rect& area) {
  ImGui::SetCursorScreenPos(ImVec2(float(area.x), float(area.y)));
  ImGui::InvisibleButton("area", ImVec2(float(area.width), float(area.height)),
                         ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  const bool hovered = ImGui::IsItemHovered();
  const ImGuiIO& io = ImGui::GetIO();
  const double mx = io.MousePos.x, my = io.MousePos.y;
  if (hovered && io.MouseWheel != 0.0f) {
    view.zoom_about(std::pow(0.85, double(io.MouseWheel)), mx, my, area,
                    view.is_xy() || io.KeyShift);
  }
  if (ImGui::IsItemActive() && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
    view.pan_px(io.MouseDelta.x, io.MouseDelta.y, area);
  }
  if (hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Right)) {
    state.box_active = true;
    state.box_x0 = mx;
    state.box_y0 = my;
  }
  if (state.box_active && ImGui::IsMouseReleased(ImGuiMouseButton_Right)) {
    view.box_zoom(state.box_x0, state.box_y0, mx, my, area);
    state.box_active = false;
  }
  if (hovered && ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) view.fit();
  return Pointer{.hovered = hovered, .mx = mx, .my = my};
}

// Grid and tick labels.
void draw_grid(const PlotView& view, const Rect& area, ImVec2 a0, ImVec2 a1, ImDrawList* draw) {
  const auto x_ticks = nice_ticks(view.x->min, view.x->max, std::max(2, int(area.width / 110)),
                                  view.integer_x ? 1.0 : 0.0);
  const auto y_ticks = nice_ticks(view.y.min, view.y.max, std::max(2, int(area.height / 50)));
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : view.x->span();
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : view.y.span();
  for (double t : x_ticks) {
    const float px = std::round(float(view.to_px_x(t, area)));
    draw->AddLine(ImVec2(px, a0.y), ImVec2(px, a1.y), kGridColour);
    const std::string label = tick_label(t, x_step);
    const float w = ImGui::CalcTextSize(label.c_str()).x;
    draw->AddText(ImVec2(px - w / 2, a1.y + 3.0f), kTextColour, label.c_str());
  }
  for (double t : y_ticks) {
    const float py = std::round(float(view.to_px_y(t, area)));
    draw->AddLine(ImVec2(a0.x, py), ImVec2(a1.x, py), kGridColour);
    const std::string label = tick_label(t, y_step);
    const float w = ImGui::CalcTextSize(label.c_str()).x;
    draw->AddText(ImVec2(a0.x - w - 4.0f, py - 7.0f), kTextColour, label.c_str());
  }
}

// The shaded stretches and event markers under the mouse, for the readout.
struct UnderMouse {
  std::vector<const Shade*> shades;
  std::vector<const Marker*> markers;
};

// Event markers and shaded stretches (behind the curves); returns those under the mouse.
UnderMouse draw_shades_and_markers(const PlotView& view, const Rect& area, const Pointer& pointer,
                                   ImVec2 a0, ImVec2 a1, ImDrawList* draw) {
  UnderMouse under;
  for (const Shade& shade : view.shades) {
    if (shade.x1 < view.x->min || shade.x0 > view.x->max) continue;
    const float left = std::round(float(view.to_px_x(shade.x0, area)));
    const float right = std::max(left + 1.0f, std::round(float(view.to_px_x(shade.x1, area))));
    draw->AddRectFilled(ImVec2(left, a0.y), ImVec2(right, a1.y), to_imgui_colour(shade.colour));
    if (pointer.hovered && pointer.mx >= left - 2.0f && pointer.mx <= right + 2.0f) {
      under.shades.push_back(&shade);
    }
  }
  for (const Marker& m : view.markers) {
    if (m.x < view.x->min || m.x > view.x->max) continue;
    const float px = std::round(float(view.to_px_x(m.x, area)));
    draw->AddLine(ImVec2(px, a0.y), ImVec2(px, a1.y), to_imgui_colour(m.colour));
    if (pointer.hovered && std::abs(px - float(pointer.mx)) <= 3.0f) under.markers.push_back(&m);
  }
  return under;
}

// Rebuilds the draw data when the ranges, the area, the series or their revision changed.
void update_draw_data(PlotView& view, PlotWidgetState& state, const Rect& area) {
  const bool same =
      state.drawn && state.drawn_x.min == view.x->min && state.drawn_x.max == view.x->max &&
      state.drawn_y.min == view.y.min && state.drawn_y.max == view.y.max &&
      state.drawn_area.x == area.x && state.drawn_area.y == area.y &&
      state.drawn_area.width == area.width && state.drawn_area.height == area.height &&
      state.drawn_series == view.series.size() && state.drawn_revision == view.revision;
  if (!same) {
    view.build_draw_data(area, state.draw);
    state.drawn_x = *view.x;
    state.drawn_y = view.y;
    state.drawn_area = area;
    state.drawn_series = view.series.size();
    state.drawn_revision = view.revision;
    state.drawn = true;
  }
}

// Curves in layer order (analysis/report/plot_style.h: measured on top of a model's curve).
void draw_curves(const DrawData& data, ImDrawList* draw) {
  int lowest = 0, highest = 0;
  for (const DrawData::Strip& strip : data.strips) {
    lowest = std::min(lowest, strip.layer);
    highest = std::max(highest, strip.layer);
  }
  for (int layer = lowest; layer <= highest; ++layer) {
    for (const DrawData::Strip& strip : data.strips) {
      if (strip.layer != layer) continue;
      draw->AddPolyline(reinterpret_cast<const ImVec2*>(data.points.data() + strip.begin),
                        int(strip.end - strip.begin), to_imgui_colour(strip.colour), 0,
                        strip.width_px);
    }
  }
}

// Crosshair and readout: the events and shades under the mouse and each series' nearest
// sample, in a tooltip, with a circle on each sample.
void draw_readout(const PlotView& view, const Rect& area, const Pointer& pointer,
                  const UnderMouse& under, ImVec2 a0, ImVec2 a1, ImDrawList* draw) {
  const double mx = pointer.mx, my = pointer.my;
  draw->AddLine(ImVec2(float(mx), a0.y), ImVec2(float(mx), a1.y), IM_COL32(200, 200, 200, 120));
  draw->AddLine(ImVec2(a0.x, float(my)), ImVec2(a1.x, float(my)), IM_COL32(200, 200, 200, 120));
  const auto readouts = view.readout(mx, my, area);
  ImGui::BeginTooltip();
  for (const Marker* m : under.markers) {
    ImGui::Text("event at %.4f: %s", m->x, m->label.c_str());
  }
  for (const Shade* shade : under.shades) {
    ImGui::Text("%.4f to %.4f: %s", shade->x0, shade->x1, shade->label.c_str());
  }
  for (const Readout& r : readouts) {
    ImGui::Text("%s: x = %.6g %s, y = %.6g %s (sample %zu)", r.series.c_str(), r.x,
                r.x_unit.c_str(), r.y, r.unit.c_str(), r.index);
  }
  ImGui::EndTooltip();
  for (const Readout& r : readouts) {
    draw->AddCircle(ImVec2(float(view.to_px_x(r.x, area)), float(view.to_px_y(r.y, area))), 4.0f,
                    IM_COL32(255, 255, 255, 220));
  }
}

}  // namespace

unsigned int to_imgui_colour(Rgba c) {
  return IM_COL32(c.r, c.g, c.b, c.a);
}

// The stages: the header (and its buttons), the input over the data area, the grid, the
// shades and markers, the curves, the zoom box, the crosshair and readout, the frame; then
// what was drawn where.
PlotRecord plot_widget(const char* id, PlotView& view, PlotWidgetState& state, float width,
                       float height, bool controls) {
  PlotRecord record;
  static_assert(sizeof(Point) == sizeof(ImVec2), "Point is drawn as ImVec2");
  ImGui::PushID(id);
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  if (width <= 0.0f) width = avail.x;
  if (height <= 0.0f) height = avail.y;
  width = std::max(width, kLeftMargin + 40.0f);
  height = std::max(height, kHeaderHeight + kBottomMargin + 40.0f);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();

  const std::vector<std::string> items = header_items(view);
  const float header_height = draw_header(view, items, origin, width, controls, draw);
  if (controls) {
    ImGui::SetCursorScreenPos(ImVec2(origin.x + width - 80.0f, origin.y));
    record.want_csv = ImGui::SmallButton("CSV");
    ImGui::SameLine();
    record.want_png = ImGui::SmallButton("PNG");
  }

  const Rect area{.x = origin.x + kLeftMargin,
                  .y = origin.y + header_height,
                  .width = width - kLeftMargin - 8.0f,
                  .height = height - header_height - kBottomMargin};
  const ImVec2 a0(float(area.x), float(area.y));
  const ImVec2 a1(float(area.x + area.width), float(area.y + area.height));
  const Pointer pointer = handle_input(view, state, area);

  draw->AddRectFilled(a0, a1, kBackground);
  draw_grid(view, area, a0, a1, draw);
  // Event markers and shaded stretches behind the curves, clipped to the data area like them.
  draw->PushClipRect(a0, a1, true);
  const UnderMouse under = draw_shades_and_markers(view, area, pointer, a0, a1, draw);
  update_draw_data(view, state, area);
  draw_curves(state.draw, draw);
  if (state.box_active) {
    draw->AddRect(ImVec2(float(state.box_x0), float(state.box_y0)),
                  ImVec2(float(pointer.mx), float(pointer.my)), IM_COL32(255, 255, 255, 200));
  }
  if (pointer.hovered && !state.box_active) draw_readout(view, area, pointer, under, a0, a1, draw);
  draw->PopClipRect();
  draw->AddRect(a0, a1, kFrameColour);

  // Leave the cursor below the whole widget.
  ImGui::SetCursorScreenPos(ImVec2(origin.x, origin.y + height));
  ImGui::Dummy(ImVec2(width, 0.0f));
  ImGui::PopID();

  record.title = view.title;
  record.labels = items;
  record.view = &view;
  record.widget = {.x = origin.x, .y = origin.y, .width = width, .height = height};
  record.area = area;
  record.x = *view.x;
  record.y = view.y;
  for (const auto& s : view.series) {
    record.series.push_back(s->name());
    record.colours.push_back(s->colour);
  }
  return record;
}

}  // namespace doorbench::viewer
