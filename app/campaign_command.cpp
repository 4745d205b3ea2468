// doorbench campaign: a study across a panel (docs/campaign.md). `plan` turns a campaign file
// into the folder with the whole plan (and with --simulate N, the power of the plan);
// `run` runs or resumes one participant's schedule on a device, blinded; `merge` joins
// folders of one plan. The campaign's logic is study/, and its presentations are played by
// study/presenter.h (as `doorbench ab`'s are); this file is the command line.
//
// Other campaign subcommands (`campaign analyze`) attach to the CLI::App that
// add_campaign_command returns (app/commands.h).
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "app/play_run.h"
#include "app/session_recording.h"
#include "app/station_screen.h"
#include "core/number_format.h"
#include "study/campaign_plan.h"
#include "study/campaign_run.h"
#include "study/campaign_summary.h"
#include "study/participant_screen.h"
#include "study/power.h"
#include "study/presenter.h"
#include "study/random_stream.h"

namespace doorbench::app {
namespace {

struct PlanCommandOptions {
  std::string campaign_path;
  std::string out_dir;
  std::optional<std::uint64_t> seed;
  int simulate = 0;
  bool overwrite = false;
};

struct RunCommandOptions {
  std::string dir;
  std::string participant;
  std::string device = "sim";
  std::string respondent = "person";
  std::string answers_path;
  std::optional<double> presentation_s;
  bool real_time = false;
  bool redo = false;
  StationCommandOptions station;
};

struct MergeCommandOptions {
  std::vector<std::string> dirs;
  std::string out_dir;
};

void run_plan(const PlanCommandOptions& options) {
  if (options.out_dir.empty() && options.simulate == 0) {
    throw UsageError("campaign plan needs --out DIR (or --simulate N for the power alone)");
  }
  const study::Campaign campaign = study::read_campaign(options.campaign_path);
  const std::uint64_t seed = options.seed.value_or(campaign.seed);
  if (!options.out_dir.empty()) {
    const study::Plan plan = study::make_plan(campaign, seed);
    study::write_campaign_folder(options.out_dir, campaign, plan, options.overwrite);
    std::cout << "campaign " << campaign.name << ": " << campaign.participants.size()
              << " participants, " << campaign.blocks.size() << " blocks, " << plan.rows.size()
              << " trials (seed " << seed << ") in " << options.out_dir
              << " (plan.csv, campaign.toml, plan-id.txt)\n";
    const std::string note = study::balance_note(campaign);
    if (!note.empty()) std::cout << note << "\n";
  }
  if (options.simulate > 0) {
    study::PowerOptions power;
    power.panels = options.simulate;
    std::cout << "power: " << options.simulate << " simulated panels of "
              << campaign.participants.size()
              << " participants (docs/campaign.md; exact binomial / sign tests, alpha 0.05)\n";
    for (const study::PowerLine& line : study::simulate_power(campaign, seed, power)) {
      std::cout << "  " << line.text() << "\n";
    }
  }
}

// The presenter of `campaign run`: the device of --device, the campaign's rig for the real
// door, presentations of --presentation-s or the campaign's length (simulated or real time).
study::DevicePresenter make_presenter(const RunCommandOptions& options,
                                      const study::Campaign& campaign) {
  study::PresenterOptions presenting;
  presenting.device = options.device;
  presenting.real_time = options.real_time;
  presenting.operator_name = "doorbench campaign";
  presenting.presentation_s = options.presentation_s.value_or(
      presenting.simulated_time() ? campaign.simulated_presentation_s : campaign.presentation_s);
  if (const std::string problem = presenting.validate(); !problem.empty())
    throw UsageError(problem);
  std::shared_ptr<const RigDefinition> rig;
  if (!campaign.real_rig.empty())
    rig = std::make_shared<const RigDefinition>(load_rig(campaign.real_rig.string()));
  return study::DevicePresenter(presenting, presentation_player(), real_door_recorder(rig),
                                std::cerr);
}

std::unique_ptr<study::Respondent> make_respondent(const RunCommandOptions& options,
                                                   const study::CampaignFolder& folder) {
  if (options.respondent == "person") {
    std::shared_ptr<std::ifstream> file;
    if (!options.answers_path.empty()) {
      file = std::make_shared<std::ifstream>(options.answers_path);
      if (!*file) throw std::runtime_error(options.answers_path + ": cannot open the answers file");
    }
    auto next = [file]() -> std::optional<std::string> {
      std::string line;
      std::istream& in = file ? static_cast<std::istream&>(*file) : std::cin;
      if (!std::getline(in, line)) return std::nullopt;
      return line;
    };
    const bool interactive = !file && ::isatty(STDIN_FILENO) == 1;
    return std::make_unique<study::LineRespondent>(next, file ? options.answers_path : "stdin",
                                                   interactive,
                                                   /*tunes_at_the_device=*/true);
  }
  if (!options.answers_path.empty()) throw UsageError("--answers is for --respondent person");
  std::uint64_t seed = 0;
  if (options.respondent == "sim") {
    // The participant's own: from the plan's seed and the participant's place in the campaign.
    const auto& ids = folder.campaign.participants;
    const auto at = static_cast<std::uint64_t>(
        std::find(ids.begin(), ids.end(), options.participant) - ids.begin());
    seed = study::substream_seed(folder.identity.seed, at, 0, study::Purpose::kParticipantModel);
  } else if (options.respondent.rfind("sim:", 0) == 0 && options.respondent.size() > 4 &&
             options.respondent.find_first_not_of("0123456789", 4) == std::string::npos &&
             options.respondent.size() <= 24) {
    seed = std::stoull(options.respondent.substr(4));
  } else {
    throw UsageError("--respondent must be person, sim or sim:SEED, not " + options.respondent);
  }
  return std::make_unique<study::SimulatedRespondent>(seed, study::base_model(folder.campaign));
}

void run_run(const RunCommandOptions& options) {
  // The issue's spelling `--participant sim:SEED`: a participant is one of the plan's ids (its
  // schedule); who answers is --respondent (docs/campaign.md, "Running a participant").
  if (options.participant == "sim" || options.participant.rfind("sim:", 0) == 0) {
    throw UsageError("--participant names a participant of the plan (such as P01), not " +
                     options.participant +
                     "; a simulated participant answers that participant's trials with "
                     "--participant P01 --respondent " +
                     (options.participant == "sim" ? std::string("sim") : options.participant));
  }
  if (const std::string problem = study::participant_id_problem(options.participant);
      !problem.empty()) {
    throw UsageError(problem);
  }
  const study::CampaignFolder folder = study::open_campaign_folder(options.dir);
  // With --station a person answers on it (no respondent behind it); an answers file or a
  // simulated participant answers through it.
  const bool person_at_station =
      options.station.station && options.respondent == "person" && options.answers_path.empty();
  const std::unique_ptr<study::Respondent> respondent =
      person_at_station ? nullptr : make_respondent(options, folder);
  study::DevicePresenter presenter = make_presenter(options, folder.campaign);
  std::unique_ptr<StationScreen> station;
  std::optional<study::ScreenRespondent> on_station;
  if (options.station.station) {
    if (const std::string problem = study::screen_problem(folder.plan.of(options.participant));
        !problem.empty()) {
      throw UsageError("--station: " + problem);
    }
    // Opened now: a bad scene or display stops the run before the device moves.
    station =
        std::make_unique<StationScreen>(campaign_station_request(options.station, folder.campaign));
    presenter.show_on(station.get());
    on_station.emplace(*station, respondent.get());
  }
  std::cerr << "doorbench campaign run: participant " << options.participant << " on "
            << options.device << (station ? ", answers on the station" : "") << "\n";
  study::RunOptions run;
  run.participant = options.participant;
  run.redo = options.redo;
  const study::RunResult result = study::run_participant(
      folder, run, on_station ? static_cast<study::Respondent&>(*on_station) : *respondent,
      presenter.as_presenter(), std::cerr);
  if (station) std::cout << station->close() << "\n";
  std::cout << "participant " << options.participant << ": "
            << result.answered_before + result.answered_now << " of " << result.planned
            << " trials answered (attempt " << result.attempt << ", " << result.answered_now
            << " in this run); answers in "
            << (std::filesystem::path(options.dir) / "trials.csv").string() << "\n";
}

// The demo's campaign: campaigns/example.toml's variants and blocks, made short (2
// participants, fewer levels and trials, presentations of 0.2 s in simulated time).
constexpr const char* kDemoCampaign = R"(
[campaign]
name = "demo"
seed = 2026
simulated_presentation_s = 0.2
[variants]
reference = "base"
heavier = "heaviness*1.2"
easier_unlatch = "latch_effort*0.7"
lighter_smoother = "J*0.85,smoothness*0.8"
[participants]
count = 2
[[blocks]]
name = "tune"
type = "tune"
[[blocks]]
name = "pair"
type = "pair"
question = "preference-2ac"
[[blocks]]
name = "rating"
type = "rating"
attributes = ["heavy-light"]
pairs = [["reference", "heavier"], ["reference", "lighter_smoother"]]
[[blocks]]
name = "jnd-heaviness"
type = "jnd"
parameter = "J"
levels = [1.1, 1.3]
[[blocks]]
name = "jnd-latch"
type = "jnd"
parameter = "latch_effort"
method = "staircase"
trials = 8
)";

// True when `folder` is a campaign folder planned from a campaign named `name` (its
// plan-id.txt says so and its plan.csv matches it).
bool holds_campaign_named(const std::filesystem::path& folder, const std::string& name) {
  if (!std::filesystem::exists(folder / "plan-id.txt")) return false;
  try {
    return study::read_plan_identity(folder).campaign == name;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

void run_demo_campaign(const std::filesystem::path& dir, std::ostream& out) {
  const std::filesystem::path campaign_path = dir / "demo-campaign.toml";
  std::filesystem::create_directories(dir);
  write_file_atomically(campaign_path, [](std::ostream& file) { file << kDemoCampaign; });
  const study::Campaign campaign = study::read_campaign(campaign_path);
  const std::filesystem::path folder = dir / "folder";
  // The demo owns its campaign: an earlier demo's run there is replaced (its answers are the
  // seeded simulation's, made again below). Any other folder there is refused as a plan's
  // output is.
  const bool replaced = holds_campaign_named(folder, campaign.name);
  if (replaced) remove_output_folder(folder);
  study::write_campaign_folder(folder, campaign, study::make_plan(campaign, campaign.seed), false);
  const study::CampaignFolder opened = study::open_campaign_folder(folder);
  RunCommandOptions options;
  options.dir = folder.string();
  options.respondent = "sim";
  const study::DevicePresenter presenter = make_presenter(options, opened.campaign);
  std::ostringstream prompts;  // the operator's lines, not shown in the demo
  for (const std::string& participant : opened.campaign.participants) {
    options.participant = participant;
    const std::unique_ptr<study::Respondent> respondent = make_respondent(options, opened);
    study::run_participant(opened, study::RunOptions{participant, false}, *respondent,
                           presenter.as_presenter(), prompts);
  }
  out << "\na simulated campaign (" << opened.campaign.participants.size()
      << " simulated participants on the simulated HapticMaster, " << opened.plan.rows.size()
      << " trials; docs/campaign.md):\n";
  for (const std::string& line :
       study::block_summaries(opened.campaign, study::read_trials_table(folder / "trials.csv"))) {
    out << "  " << line << "\n";
  }
  out << "  answers in " << (folder / "trials.csv").string()
      << (replaced ? " (an earlier demo's campaign there replaced)" : "") << "\n";
}

CLI::App* add_campaign_command(CLI::App& app, Action& action) {
  CLI::App* campaign = app.add_subcommand(
      "campaign",
      "A study across a panel: plan a campaign file into a folder (counterbalanced, seeded), run "
      "or resume a "
      "participant blinded on the device, merge folders of one plan (docs/campaign.md).");
  campaign->require_subcommand(1);

  auto plan_options = std::make_shared<PlanCommandOptions>();
  CLI::App* plan =
      campaign->add_subcommand("plan", "Write the whole plan of a campaign file into a folder");
  plan->add_option("campaign", plan_options->campaign_path, "The campaign file (TOML)")->required();
  plan->add_option("--out", plan_options->out_dir, "The campaign folder (created; must be empty)");
  plan->add_option("--seed", plan_options->seed, "The plan's seed (default: the campaign file's)");
  plan->add_option("--simulate", plan_options->simulate,
                   "Run the plan with N simulated panels and print how often each question detects "
                   "its effect")
      ->check(number_range(1, 100000));
  plan->add_flag("--overwrite", plan_options->overwrite, "Write into a folder that is not empty");
  plan->callback([plan_options, &action] { action = [plan_options] { run_plan(*plan_options); }; });

  auto run_options = std::make_shared<RunCommandOptions>();
  CLI::App* run =
      campaign->add_subcommand("run", "Run or resume one participant's trials, blinded");
  run->add_option("dir", run_options->dir, "The campaign folder (from campaign plan)")->required();
  run->add_option("--participant", run_options->participant,
                  "The participant's pseudonymous id, as in the plan")
      ->required();
  run->add_option("--device", run_options->device,
                  "sim (simulated time) or hapticmaster://HOST[:PORT]")
      ->capture_default_str();
  run->add_option("--respondent", run_options->respondent,
                  "person (answers from stdin or --answers; a tune trial tuned with the keys), sim "
                  "(a simulated participant seeded from the plan) "
                  "or sim:SEED")
      ->capture_default_str();
  run->add_option(
      "--answers", run_options->answers_path,
      "A person's answers, one a line (a tune trial's line: the keys pressed; default: stdin)");
  run->add_flag("--real-time", run_options->real_time,
                "Play a simulated device in real time, as a HapticMaster would be (presentations "
                "of the campaign file's presentation_s), instead of simulated time");
  run->add_option("--presentation-s", run_options->presentation_s,
                  "Length of each presentation (default: the campaign file's)")
      ->check(number_range(0.001, 600.0));
  run->add_flag("--redo", run_options->redo,
                "Run a finished participant again (earlier answers kept, marked)");
  add_station_options(*run, run_options->station);
  run->callback([run_options, &action] { action = [run_options] { run_run(*run_options); }; });

  auto merge_options = std::make_shared<MergeCommandOptions>();
  CLI::App* merge =
      campaign->add_subcommand("merge", "Join campaign folders of the same plan into one");
  merge->add_option("dirs", merge_options->dirs, "Two or more campaign folders")
      ->required()
      ->expected(2, -1);
  merge->add_option("--out", merge_options->out_dir, "The merged folder (created; must be empty)")
      ->required();
  merge->callback([merge_options, &action] {
    action = [merge_options] {
      std::vector<std::filesystem::path> dirs(merge_options->dirs.begin(),
                                              merge_options->dirs.end());
      study::merge_campaign_folders(dirs, merge_options->out_dir);
      std::cout << "merged " << dirs.size() << " campaign folders into " << merge_options->out_dir
                << "\n";
    };
  });
  return campaign;
}

}  // namespace doorbench::app
