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

}  // namespace

unsigned int to_imgui_colour(Rgba c) {
  return IM_COL32(c.r, c.g, c.b, c.a);
}

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

  // Header: title, then each series' colour, name and unit, the x quantity and unit last
  // (outside the data area, so that only curves and grid are drawn inside it). Items that
  // do not fit on a line go on the next one, so that the legend is never cut.
  std::vector<std::string> items;
  items.push_back(view.title);
  for (const auto& s : view.series) items.push_back(with_unit(s->name(), s->unit()));
  if (!view.series.empty()) {
    items.push_back("x: " + with_unit(view.x_label, view.series.front()->x_unit()));
  }
  if (!view.shades.empty()) items.push_back("shaded: " + view.shades.front().label);
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

  if (controls) {
    ImGui::SetCursorScreenPos(ImVec2(origin.x + width - 80.0f, origin.y));
    record.want_csv = ImGui::SmallButton("CSV");
    ImGui::SameLine();
    record.want_png = ImGui::SmallButton("PNG");
  }

  const Rect area{origin.x + kLeftMargin, origin.y + header_height, width - kLeftMargin - 8.0f,
                  height - header_height - kBottomMargin};
  const ImVec2 a0(float(area.x), float(area.y));
  const ImVec2 a1(float(area.x + area.width), float(area.y + area.height));

  // Input: an invisible button over the data area.
  ImGui::SetCursorScreenPos(a0);
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

  draw->AddRectFilled(a0, a1, kBackground);
  // Grid and tick labels.
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

  // Event markers and shaded stretches behind the curves, clipped to the data area like them.
  draw->PushClipRect(a0, a1, true);
  std::vector<const Shade*> shade_under_mouse;
  for (const Shade& shade : view.shades) {
    if (shade.x1 < view.x->min || shade.x0 > view.x->max) continue;
    const float left = std::round(float(view.to_px_x(shade.x0, area)));
    const float right = std::max(left + 1.0f, std::round(float(view.to_px_x(shade.x1, area))));
    draw->AddRectFilled(ImVec2(left, a0.y), ImVec2(right, a1.y), to_imgui_colour(shade.colour));
    if (hovered && mx >= left - 2.0f && mx <= right + 2.0f) shade_under_mouse.push_back(&shade);
  }
  std::vector<const Marker*> near_mouse;
  for (const Marker& m : view.markers) {
    if (m.x < view.x->min || m.x > view.x->max) continue;
    const float px = std::round(float(view.to_px_x(m.x, area)));
    draw->AddLine(ImVec2(px, a0.y), ImVec2(px, a1.y), to_imgui_colour(m.colour));
    if (hovered && std::abs(px - float(mx)) <= 3.0f) near_mouse.push_back(&m);
  }
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
  // Curves in layer order (analysis/report/plot_style.h: measured on top of a model's curve).
  int lowest = 0, highest = 0;
  for (const DrawData::Strip& strip : state.draw.strips) {
    lowest = std::min(lowest, strip.layer);
    highest = std::max(highest, strip.layer);
  }
  for (int layer = lowest; layer <= highest; ++layer) {
    for (const DrawData::Strip& strip : state.draw.strips) {
      if (strip.layer != layer) continue;
      draw->AddPolyline(reinterpret_cast<const ImVec2*>(state.draw.points.data() + strip.begin),
                        int(strip.end - strip.begin), to_imgui_colour(strip.colour), 0,
                        strip.width_px);
    }
  }
  if (state.box_active) {
    draw->AddRect(ImVec2(float(state.box_x0), float(state.box_y0)), ImVec2(float(mx), float(my)),
                  IM_COL32(255, 255, 255, 200));
  }
  // Crosshair and readout.
  if (hovered && !state.box_active) {
    draw->AddLine(ImVec2(float(mx), a0.y), ImVec2(float(mx), a1.y), IM_COL32(200, 200, 200, 120));
    draw->AddLine(ImVec2(a0.x, float(my)), ImVec2(a1.x, float(my)), IM_COL32(200, 200, 200, 120));
    const auto readouts = view.readout(mx, my, area);
    ImGui::BeginTooltip();
    for (const Marker* m : near_mouse) ImGui::Text("event at %.4f: %s", m->x, m->label.c_str());
    for (const Shade* shade : shade_under_mouse) {
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
  draw->PopClipRect();
  draw->AddRect(a0, a1, kFrameColour);

  // Leave the cursor below the whole widget.
  ImGui::SetCursorScreenPos(ImVec2(origin.x, origin.y + height));
  ImGui::Dummy(ImVec2(width, 0.0f));
  ImGui::PopID();

  record.title = view.title;
  record.labels = items;
  record.view = &view;
  record.widget = {origin.x, origin.y, width, height};
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
