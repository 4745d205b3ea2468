// doorbench ab: a blinded A/B comparison (docs/ab-testing.md). Variant A against variant B
// on the device, or the real door on the bench against a virtual one; the plan, answers and
// statistics are study/ab_trials.h, the playing of one presentation study/presenter.h.
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "app/play_run.h"
#include "app/session_recording.h"
#include "app/station_screen.h"
#include "core/number_format.h"
#include "study/ab_trials.h"
#include "study/presenter.h"

namespace doorbench::app {
namespace {

struct AbCommandOptions {
  std::string params_a;
  std::string params_b;
  std::string real_rig;
  std::string model = "sensory";
  std::string device = "sim";
  int trials = 10;
  std::string question = "preference";
  std::optional<std::uint64_t> seed;
  double presentation_s = 10.0;
  std::string out_dir;
  std::string answers_path;
  std::vector<std::string> labels{"1", "2"};
  bool real_time = false;
  StationCommandOptions station;
};

void run_ab_command(const AbCommandOptions& options) {
  if (options.params_a.empty() == options.real_rig.empty()) {
    throw UsageError("ab needs exactly one of --a PARAMS.json and --real-rig RIG.toml");
  }
  study::AbRunInputs inputs;
  inputs.options.trials = options.trials;
  if (const std::string problem = inputs.options.ask(options.question); !problem.empty()) {
    throw UsageError(problem);
  }
  inputs.options.seed = options.seed ? *options.seed : std::random_device{}();
  inputs.options.presentation_s = options.presentation_s;
  inputs.options.a_is_real = !options.real_rig.empty();
  inputs.options.labels = {options.labels.at(0), options.labels.at(1)};
  if (const std::string problem = inputs.options.validate(); !problem.empty()) {
    throw UsageError(problem);
  }
  inputs.params_a = options.real_rig.empty() ? options.params_a : options.real_rig;
  inputs.params_b = options.params_b;
  inputs.out_dir = options.out_dir;
  const std::optional<ModelKind> kind = parse_model_kind(options.model);
  if (!kind) throw UsageError("--model must be sensory or physical, not " + options.model);
  study::PresenterOptions presenting;
  presenting.device = options.device;
  presenting.real_time = options.real_time;
  presenting.presentation_s = options.presentation_s;
  presenting.operator_name = "doorbench ab";
  if (const std::string problem = presenting.validate(); !problem.empty()) {
    throw UsageError(problem);
  }
  // Loaded before the first trial, so that a bad file stops the run at once.
  inputs.model_b = doorbench::load_model(*kind, options.params_b, "");
  std::shared_ptr<const RigDefinition> rig;
  if (options.real_rig.empty()) {
    inputs.model_a = doorbench::load_model(*kind, options.params_a, "");
  } else {
    rig = std::make_shared<const RigDefinition>(load_rig(options.real_rig));
  }
  study::DevicePresenter presenter(presenting, presentation_player(), real_door_recorder(rig),
                                   std::cerr);

  study::AnswerSource answers;
  std::shared_ptr<std::ifstream> file;
  if (!options.answers_path.empty()) {
    file = std::make_shared<std::ifstream>(options.answers_path);
    if (!*file) throw std::runtime_error(options.answers_path + ": cannot open the answers file");
    answers.name = options.answers_path;
  } else {
    answers.name = "stdin";
    answers.interactive = ::isatty(STDIN_FILENO) == 1;
  }
  answers.next_line = [file]() -> std::optional<std::string> {
    std::string line;
    std::istream& in = file ? static_cast<std::istream&>(*file) : std::cin;
    if (!std::getline(in, line)) return std::nullopt;
    return line;
  };
  std::unique_ptr<StationScreen> station;
  if (options.station.station) {
    try {
      study::screen_questions(inputs.options.asked(), inputs.options.labels);
    } catch (const std::invalid_argument& problem) {
      throw UsageError("--station: " + std::string(problem.what()));
    }
    // Opened now: a bad scene or display stops the run before the device moves.
    station = std::make_unique<StationScreen>(options.station.request());
    presenter.show_on(station.get());
    answers.screen = station.get();
    // Without --answers the participant answers on the station; with it, each line is
    // pressed there.
    if (options.answers_path.empty()) {
      answers.next_line = nullptr;
      answers.name = "the station";
    }
  }
  std::cerr << "doorbench ab: " << inputs.options.trials << " trials, "
            << study::to_string(inputs.options.question) << ", presentations of "
            << inputs.options.presentation_s << " s on " << options.device << "\n";
  const study::AbSummary summary =
      study::run_ab(inputs, presenter.as_presenter(), answers, std::cerr);
  if (station) std::cout << station->close() << "\n";
  std::cout << summary.brief_report() << "results in " << options.out_dir
            << " (answers.csv, ab-summary.json, ab-summary.txt, one session per presentation)\n";
}

}  // namespace

void add_ab_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<AbCommandOptions>();
  CLI::App* ab = app.add_subcommand(
      "ab",
      "Blinded A/B comparison: variant A vs B on the device, or the real door vs a virtual one; "
      "N trials in a balanced random order, answers per trial, counts and an exact binomial "
      "test.");
  auto* a = ab->add_option("--a", options->params_a, "Variant A's parameter file (JSON)");
  auto* real = ab->add_option("--real-rig", options->real_rig,
                              "A is the real door on this rig (TOML) instead of a parameter file");
  a->excludes(real);
  ab->add_option("--b", options->params_b, "Variant B's parameter file (JSON)")->required();
  ab->add_option("--model", options->model, "Model of the parameter files: sensory or physical")
      ->capture_default_str();
  ab->add_option("--device", options->device, "sim, or hapticmaster://HOST")->capture_default_str();
  ab->add_option("--trials", options->trials, "Number of trials N")
      ->check(number_range(1, 10000))
      ->capture_default_str();
  ab->add_option("--question", options->question,
                 "preference (which felt better), identify-real (which was the real door) or "
                 "rating[:K] (each presentation rated 1..K, default K 7)")
      ->capture_default_str();
  ab->add_option("--seed", options->seed,
                 "Seed of the presentation order (default: a random one, kept in the results)");
  ab->add_option("--presentation-s", options->presentation_s, "Length of each presentation (s)")
      ->capture_default_str();
  ab->add_option("--out", options->out_dir,
                 "Folder for the sessions, answers.csv and ab-summary.{json,txt}")
      ->required();
  ab->add_option("--labels", options->labels,
                 "The two words the presentations are called and answered by (default 1 2)")
      ->expected(2);
  ab->add_flag("--real-time", options->real_time,
               "Play a simulated device in real time, as a HapticMaster would be, instead of "
               "simulated time");
  ab->add_option("--answers", options->answers_path,
                 "Answers one per line for a scripted run (default: read from stdin; with "
                 "--station: given on the station, and a file's answers are pressed there)");
  add_station_options(*ab, options->station);
  ab->callback([options, &action] { action = [options] { run_ab_command(*options); }; });
}

}  // namespace doorbench::app
