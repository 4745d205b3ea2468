// doorbench demo: the main job on the simulated bench. For now: the reference door opened
// and closed by the virtual hand with both models, a summary each, the runs on disk.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "acquisition/recording_csv.h"
#include "analysis/parameter_file.h"
#include "analysis/run_summary.h"
#include "analysis/svg_plot.h"
#include "analysis/trajectory_io.h"
#include "app/commands.h"
#include "app/hand_run.h"

namespace doorbench::app {
namespace {

struct DemoOptions {
  std::string out_dir = "doorbench-demo";
};

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

// The samples of one stroke (1 opening, 2 closing) below an angle, as degrees and newtons.
struct Curve {
  std::vector<double> angle_deg, force_N;
};

Curve latch_curve(const Trajectory& run, int stroke, double below_deg) {
  Curve curve;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double angle_deg = run.theta_rad[i] * kDegPerRad;
    if (run.stroke[i] == stroke && angle_deg < below_deg) {
      curve.angle_deg.push_back(angle_deg);
      curve.force_N.push_back(run.force_N[i]);
    }
  }
  return curve;
}

struct ModelRun {
  ModelKind kind;
  Trajectory run;
  std::vector<double> angle_deg;
};

void write_plots(const std::filesystem::path& dir, const std::vector<ModelRun>& runs) {
  std::vector<PlotSeries> angle, force, loops;
  std::vector<Curve> curves;
  curves.reserve(2 * runs.size());
  for (const ModelRun& model_run : runs) {
    const std::string name(to_string(model_run.kind));
    angle.push_back({name + " model", model_run.run.time_s, model_run.angle_deg, ""});
    force.push_back({name + " model", model_run.run.time_s, model_run.run.force_N, ""});
    curves.push_back(latch_curve(model_run.run, 1, 8.0));
    curves.push_back(latch_curve(model_run.run, 2, 8.0));
  }
  const char* colors[] = {"#1f77b4", "#6baed6", "#d62728", "#fc9272"};
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const std::string name(to_string(runs[i / 2].kind));
    loops.push_back({name + (i % 2 == 0 ? ", opening" : ", closing"), curves[i].angle_deg,
                     curves[i].force_N, colors[i % 4]});
  }
  write_svg_plot((dir / "angle.svg").string(),
                 {"Door angle, virtual hand open-close", "time (s)", "angle (deg)"}, angle);
  write_svg_plot((dir / "hand-force.svg").string(),
                 {"Hand force at the handle (positive = opening)", "time (s)", "force (N)"}, force);
  write_svg_plot(
      (dir / "force-angle-latch.svg").string(),
      {"Force-angle near closed: unlatching and latching", "angle (deg)", "hand force (N)"}, loops);
}

void run_demo(const DemoOptions& options) {
  const std::filesystem::path dir = options.out_dir;
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw std::runtime_error(dir.string() + ": cannot create folder: " + error.message());
  std::cout << "doorbench demo: the reference door on the simulated bench, opened to 80 deg and "
               "closed again by the virtual hand (10 s at 1 kHz)\n";
  std::vector<ModelRun> runs;
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel model = reference_model(kind);
    const Trajectory& run =
        runs.emplace_back(ModelRun{kind, simulate_hand(model, VirtualHandOptions{}, 1000.0), {}})
            .run;
    const std::filesystem::path run_path = dir / (std::string(to_string(kind)) + "-open-close.csv");
    write_recording_csv_file(
        run_path, to_recording(run, "doorbench demo, reference door, " +
                                        std::string(to_string(kind)) + " model, virtual hand"));
    const std::filesystem::path params_path = dir / (std::string(to_string(kind)) + "-params.json");
    std::ofstream(params_path) << to_parameter_json(model);
    std::cout << "\n"
              << to_string(kind) << " model (" << run_path.string() << "):\n"
              << format_summary(summarize_run(model, run));
  }
  for (ModelRun& model_run : runs) {
    for (double theta : model_run.run.theta_rad) model_run.angle_deg.push_back(theta * kDegPerRad);
  }
  write_plots(dir, runs);
  std::cout << "\nruns, parameter files and plots (angle.svg, hand-force.svg, "
               "force-angle-latch.svg) are in "
            << dir.string() << "/\n";
}

}  // namespace

void add_demo_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* demo = app.add_subcommand(
      "demo", "Run the main job on the simulated bench (no hardware needed) and summarize it");
  demo->add_option("--out", options->out_dir, "Folder for the runs")->capture_default_str();
  demo->callback([options, &action] { action = [options] { run_demo(*options); }; });
}

}  // namespace doorbench::app
