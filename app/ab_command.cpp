// doorbench ab: a blinded A/B comparison (docs/ab-testing.md). Variant A against variant B
// on the device, or the real door on the bench against a virtual one; the plan, answers and
// statistics are haptic/ab_trials.h, the playing of one presentation is a
// PresentationPlayer (make_presentation_player below).
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
#include "core/number_format.h"
#include "haptic/ab_trials.h"

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
};

// "preference", "identify-real", "rating" (K = 7) or "rating:K".
void parse_question(const std::string& text, haptic::AbOptions& options) {
  if (text == "preference") {
    options.question = haptic::AbQuestion::kPreference;
  } else if (text == "identify-real") {
    options.question = haptic::AbQuestion::kIdentifyReal;
  } else if (text == "rating") {
    options.question = haptic::AbQuestion::kRating;
  } else if (text.rfind("rating:", 0) == 0) {
    options.question = haptic::AbQuestion::kRating;
    const std::string scale = text.substr(7);
    const bool digits = !scale.empty() && scale.size() <= 3 &&
                        scale.find_first_not_of("0123456789") == std::string::npos;
    if (!digits) throw UsageError("--question rating:K needs a whole number K, got " + text);
    options.rating_scale = std::stoi(scale);
  } else {
    throw UsageError("--question must be preference, identify-real, rating or rating:K, not " +
                     text);
  }
}

// The presentation player for --device: a virtual variant is rendered on the device by the
// render loop (play_model), the real door recorded from the rig.
haptic::PresentationPlayer make_presentation_player(const AbCommandOptions& options) {
  const std::optional<ModelKind> kind = parse_model_kind(options.model);
  if (!kind) throw UsageError("--model must be sensory or physical, not " + options.model);
  const bool simulated = options.device.rfind("sim", 0) == 0;
  if (!simulated && options.device.rfind("hapticmaster://", 0) != 0) {
    throw UsageError("--device must be sim, sim:rotary or hapticmaster://HOST[:PORT], not " +
                     options.device);
  }
  if (options.real_time && !simulated) {
    throw UsageError(
        "--real-time is for a simulated device (sim, sim:rotary); a HapticMaster "
        "always plays in real time");
  }
  const bool simulated_time = simulated && !options.real_time;
  // Loaded once, before the first trial, so that a bad file stops the run at once.
  auto models = std::make_shared<std::map<std::string, DoorModel>>();
  models->emplace("B", doorbench::load_model(*kind, options.params_b, ""));
  std::shared_ptr<RigDefinition> rig;
  if (options.real_rig.empty()) {
    models->emplace("A", doorbench::load_model(*kind, options.params_a, ""));
  } else {
    rig = std::make_shared<RigDefinition>(load_rig(options.real_rig));
  }
  const std::string device = options.device;
  return [models, rig, device, simulated_time](const haptic::PresentationRequest& request) {
    const std::string notes = "doorbench ab: trial " + std::to_string(request.trial) +
                              ", presentation " + std::to_string(request.position);
    if (request.variant == "real") {
      // The real door on the bench, recorded from the rig for the presentation's time.
      SessionRecordingOptions recording;
      recording.duration_s = request.duration_s;
      recording.show_progress = false;
      recording.operator_name = "doorbench ab";
      recording.notes = notes + ", variant real (" + request.params_path + ")";
      record_rig_session(*rig, recording, request.session_path);
      return;
    }
    // The virtual door rendered on the device. A simulated device (with its virtual user)
    // runs in simulated time unless --real-time; a HapticMaster in real time, with the person
    // at its handle.
    PlayRequest play;
    play.device.uri = device;
    play.device.simulated_time = simulated_time;
    // The virtual user's open-close cycle: the presentation's, between 4 s (faster would be a
    // slam the velocity trip stops) and 10 s.
    play.device.hand.duration_s = std::clamp(request.duration_s, 4.0, 10.0);
    play.device.seed = static_cast<std::uint64_t>(1000 * request.trial + request.position);
    play.playback.duration_s = request.duration_s;
    play.session_path = request.session_path;
    play.model_source = request.params_path;
    play.operator_name = "doorbench ab";
    play.product_id = "virtual door";
    play.notes = notes + ", variant " + request.variant + " (" + request.params_path + ")";
    play.show_status = false;
    const haptic::PlaybackSummary summary = play_model(models->at(request.variant), play);
    if (!summary.stop_cause.empty()) {
      throw std::runtime_error("the presentation stopped after " +
                               format_significant(summary.duration_s, 3) +
                               " s: " + summary.stop_cause);
    }
  };
}

void run_ab_command(const AbCommandOptions& options) {
  if (options.params_a.empty() == options.real_rig.empty()) {
    throw UsageError("ab needs exactly one of --a PARAMS.json and --real-rig RIG.toml");
  }
  haptic::AbRunInputs inputs;
  inputs.options.trials = options.trials;
  parse_question(options.question, inputs.options);
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
  const haptic::PresentationPlayer player = make_presentation_player(options);

  haptic::AnswerSource answers;
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
  std::cerr << "doorbench ab: " << inputs.options.trials << " trials, "
            << haptic::to_string(inputs.options.question) << ", presentations of "
            << inputs.options.presentation_s << " s on " << options.device << "\n";
  const haptic::AbSummary summary = haptic::run_ab(inputs, player, answers, std::cerr);
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
                 "Answers one per line for a scripted run (default: read from stdin)");
  ab->callback([options, &action] { action = [options] { run_ab_command(*options); }; });
}

}  // namespace doorbench::app
