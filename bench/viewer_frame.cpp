// CPU time per frame of the viewer's overlay view (measured against simulated, residual
// below) with 10 million samples per series: decimation plus building ImGui's vertices,
// in a headless ImGui context (no window, no GPU: the GPU's share is excluded by design).
// Target: under 8 ms per frame. Results: docs/PERFORMANCE.md.
#include <benchmark/benchmark.h>
#include <imgui.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "viewer/plot_view.h"
#include "viewer/plot_widget.h"

namespace {

using namespace doorbench::viewer;

constexpr std::size_t kSamples = 10'000'000;
constexpr double kRateHz = 10000.0;  // 1000 s at 10 kHz

struct Overlay {
  std::shared_ptr<Series> measured, simulated, residual;
  PlotView top, bottom;
  PlotWidgetState top_state, bottom_state;
};

Overlay& overlay() {
  static std::unique_ptr<Overlay> o = [] {
    auto o = std::make_unique<Overlay>();
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, 0.02);
    std::vector<double> m(kSamples), s(kSamples), r(kSamples);
    for (std::size_t i = 0; i < kSamples; ++i) {
      const double t = double(i) / kRateHz;
      s[i] = std::sin(0.7 * t) * std::cos(0.013 * t);
      m[i] = s[i] + noise(rng) + 0.05 * std::sin(31.0 * t);
      r[i] = m[i] - s[i];
    }
    o->measured = std::make_shared<Series>(Series::uniform("measured", "rad/s", 0, 1 / kRateHz, m));
    o->simulated =
        std::make_shared<Series>(Series::uniform("simulated", "rad/s", 0, 1 / kRateHz, s));
    o->residual = std::make_shared<Series>(Series::uniform("residual", "rad/s", 0, 1 / kRateHz, r));
    o->measured->colour = {40, 140, 230, 255};
    o->simulated->colour = {230, 90, 40, 255};
    o->residual->colour = {60, 180, 75, 255};
    o->top.title = "rate";
    o->top.add(o->measured);
    o->top.add(o->simulated);
    o->bottom.title = "residual";
    o->bottom.add(o->residual);
    o->bottom.link_x_to(o->top);
    o->top.fit();
    o->bottom.fit_y();
    return o;
  }();
  return *o;
}

// The draw data alone (decimation and polylines in pixels), both plots, 1840 px wide.
void BM_OverlayDrawData(benchmark::State& state) {
  Overlay& o = overlay();
  const double fraction = double(state.range(0)) / 1000.0;  // visible share of the record
  o.top.fit_x();
  *o.top.x = {o.top.x->min, o.top.x->min + o.top.x->span() * fraction};
  const Rect top{.x = 64, .y = 20, .width = 1840, .height = 600};
  const Rect bottom{.x = 64, .y = 660, .width = 1840, .height = 300};
  DrawData a, b;
  for (auto _ : state) {
    o.top.build_draw_data(top, a);
    o.bottom.build_draw_data(bottom, b);
    benchmark::DoNotOptimize(a.points.data());
    benchmark::DoNotOptimize(b.points.data());
  }
  state.counters["visible_samples"] = double(a.visible_samples + b.visible_samples);
  state.counters["points"] = double(a.points.size() + b.points.size());
}
BENCHMARK(BM_OverlayDrawData)->Arg(1000)->Arg(100)->Arg(1)->Unit(benchmark::kMillisecond);

// A whole ImGui frame of the overlay view: NewFrame, both plot widgets (grid, ticks,
// legend, decimated curves as anti-aliased polylines), Render() building the vertex and
// index buffers. 1920 × 1080 display.
void BM_OverlayImGuiFrame(benchmark::State& state) {
  Overlay& o = overlay();
  o.top.fit_x();
  const double fraction = double(state.range(0)) / 1000.0;
  *o.top.x = {o.top.x->min, o.top.x->min + o.top.x->span() * fraction};
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  io.DisplaySize = ImVec2(1920, 1080);
  io.DeltaTime = 1.0f / 60.0f;
  io.BackendFlags |= ImGuiBackendFlags_RendererHasVtxOffset;  // as the OpenGL 3 backend
  unsigned char* texels = nullptr;
  int tw = 0, th = 0;
  io.Fonts->GetTexDataAsRGBA32(&texels, &tw, &th);
  std::size_t vertices = 0;
  const Range start = *o.top.x;
  bool nudge = false;
  for (auto _ : state) {
    // A plot that did not move reuses last frame's draw data; move it by a hair every frame
    // so that each frame decimates and builds afresh (the cost while zooming or panning).
    nudge = !nudge;
    *o.top.x = {start.min + (nudge ? 1e-9 : 0.0), start.max};
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(io.DisplaySize);
    ImGui::Begin("overlay", nullptr, ImGuiWindowFlags_NoDecoration);
    plot_widget("top", o.top, o.top_state, 0.0f, 700.0f);
    plot_widget("bottom", o.bottom, o.bottom_state, 0.0f, 0.0f);
    ImGui::End();
    ImGui::Render();
    vertices = std::size_t(ImGui::GetDrawData()->TotalVtxCount);
    benchmark::DoNotOptimize(vertices);
  }
  state.counters["vertices"] = double(vertices);
  ImGui::DestroyContext();
}
BENCHMARK(BM_OverlayImGuiFrame)->Arg(1000)->Arg(100)->Arg(1)->Unit(benchmark::kMillisecond);

// A force–angle loop is drawn point by point (x–y series cannot be decimated by column):
// 1 million points, consecutive points in one pixel merged.
void BM_LoopDrawData(benchmark::State& state) {
  const std::size_t n = std::size_t(state.range(0));
  std::vector<double> angle(n), force(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = double(i) / double(n) * 60.0;
    angle[i] = 0.8 * (1.0 - std::cos(t));
    force[i] = 10.0 * std::sin(t) + 0.3 * std::sin(97.0 * t);
  }
  PlotView loop;
  loop.add(std::make_shared<Series>(Series::xy("loop", "rad", "N", angle, force)));
  loop.fit();
  const Rect r{.x = 64, .y = 20, .width = 1840, .height = 1000};
  DrawData data;
  for (auto _ : state) {
    loop.build_draw_data(r, data);
    benchmark::DoNotOptimize(data.points.data());
  }
  state.counters["points"] = double(data.points.size());
}
BENCHMARK(BM_LoopDrawData)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

// One-off cost when a session is opened: the min/max pyramid of 10 million samples.
void BM_BuildPyramid(benchmark::State& state) {
  std::vector<double> y(kSamples);
  for (std::size_t i = 0; i < kSamples; ++i) y[i] = std::sin(double(i) * 1e-4);
  for (auto _ : state) {
    MinMaxPyramid pyramid(y);
    benchmark::DoNotOptimize(&pyramid);
  }
}
BENCHMARK(BM_BuildPyramid)->Unit(benchmark::kMillisecond);

}  // namespace
