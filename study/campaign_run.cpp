#include "study/campaign_run.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <ostream>
#include <set>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "analysis/model/parameter_file.h"
#include "study/quest_plus.h"
#include "study/question.h"
#include "study/random_stream.h"
#include "study/staircase.h"
#include "study/trials_table.h"

namespace doorbench::study {
namespace fs = std::filesystem;
namespace {

std::string quoted(std::string_view text) {
  return std::string("\"").append(text).append("\"");
}

std::string utc_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm parts{};
  gmtime_r(&now, &parts);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &parts);
  return buffer;
}

std::string rendered_parameters(const DoorModel& model) {
  std::string text;
  for (int i = 0; i < model.parameter_count(); ++i) {
    char value[32];
    std::snprintf(value, sizeof value, "%.6g", model.parameter_values()[i]);
    if (i > 0) text += ' ';
    text += model.parameter_name(i);
    text += '=';
    text += value;
  }
  return text;
}

std::string trial_file(int trial, const std::string& suffix) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "t%03d%s", trial, suffix.c_str());
  return buffer;
}

[[noreturn]] void system_error(const fs::path& path, std::string_view what) {
  throw std::runtime_error(path.string() + ": " + std::string(what) + ": " + std::strerror(errno));
}

// Appends whole rows to trials.csv: one write() each, then fsync().
class TrialsAppender {
 public:
  explicit TrialsAppender(const fs::path& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) system_error(path, "cannot open for appending");
  }
  ~TrialsAppender() { ::close(fd_); }
  TrialsAppender(const TrialsAppender&) = delete;
  TrialsAppender& operator=(const TrialsAppender&) = delete;
  void append(const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) system_error(path_, "cannot write");
      done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd_) != 0) system_error(path_, "cannot sync");
  }

 private:
  fs::path path_;
  int fd_ = -1;
};

// An exclusive lock on DIR/locks/P.lock for the run's lifetime.
class ParticipantLock {
 public:
  ParticipantLock(const fs::path& dir, const std::string& participant) {
    fs::create_directories(dir / "locks");
    const fs::path path = dir / "locks" / (participant + ".lock");
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) system_error(path, "cannot open");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::runtime_error("participant " + participant +
                               " is being run by another doorbench (" + path.string() +
                               " is locked)");
    }
  }
  ~ParticipantLock() { ::close(fd_); }
  ParticipantLock(const ParticipantLock&) = delete;
  ParticipantLock& operator=(const ParticipantLock&) = delete;

 private:
  int fd_ = -1;
};

// Cuts a torn last line (no line end) off the file; returns the bytes cut.
std::size_t cut_torn_tail(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.empty() || text.back() == '\n') return 0;
  const std::size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
  fs::resize_file(path, keep);
  return text.size() - keep;
}

// Moves what an interrupted run left for `trial` (sessions, partial files, a tuned file) into
// sessions/P/interrupted/, under a name not yet taken.
void move_leftovers(const fs::path& folder, const fs::path& interrupted,
                    const std::string& prefix) {
  if (!fs::exists(folder)) return;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || name.rfind(prefix, 0) != 0) continue;
    fs::create_directories(interrupted);
    fs::path target = interrupted / name;
    for (int n = 2; fs::exists(target); ++n)
      target = interrupted / (name + "." + std::to_string(n));
    fs::rename(entry.path(), target);
  }
}

std::string neutral_question(std::string_view question) {
  const std::optional<Question> asked = Question::parse(question);
  return asked ? asked->prompt() : std::string(question) + "? ";
}

struct Existing {
  int attempt = 0;                // the latest attempt with rows (0: none)
  std::vector<std::size_t> rows;  // indices of that attempt's rows, in file order
};

Existing existing_rows(const TrialsTable& table, const std::string& participant) {
  Existing existing;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.value(r, "participant") != participant) continue;
    const int attempt = std::stoi(table.value(r, "attempt"));
    if (attempt > existing.attempt) {
      existing.attempt = attempt;
      existing.rows.clear();
    }
    if (attempt == existing.attempt) existing.rows.push_back(r);
  }
  return existing;
}

}  // namespace

// --- answers -----------------------------------------------------------------------------

std::string normalized_answer(std::string_view question, std::string_view text) {
  const std::optional<Question> asked = Question::parse(question);
  if (!asked) throw std::invalid_argument("unknown question " + quoted(question));
  return parse_answer(*asked, text).normalized(*asked);
}

SimulatedRespondent::SimulatedRespondent(std::uint64_t seed, const DoorModel& base, int attempt,
                                         const ParticipantModelOptions& options)
    : participant_(draw_participant(seed, base, options)), seed_(seed), attempt_(attempt) {}

std::mt19937_64 SimulatedRespondent::stream(const PlanRow& row) const {
  return std::mt19937_64(substream_seed(seed_, static_cast<std::uint64_t>(attempt_),
                                        static_cast<std::uint64_t>(row.trial), Purpose::kAnswer));
}

std::string SimulatedRespondent::answer(const PlanRow& row, const Stimulus& first,
                                        const Stimulus& second, std::ostream&) {
  std::mt19937_64 random = stream(row);
  if (!first.model || !second.model) {
    // The real door: the model holds no notion of it, so its answers are guesses.
    return normalized_answer(row.question, uniform_below(random, 2) == 0 ? "1" : "2");
  }
  return answer_question(participant_, row.question, *first.model, *second.model, random);
}

DoorModel SimulatedRespondent::tune(const PlanRow& row, const DoorModel& start, std::ostream&) {
  std::mt19937_64 random = stream(row);
  return tune_door(participant_, start, random).model;
}

LineRespondent::LineRespondent(std::function<std::optional<std::string>()> next_line,
                               std::string source, bool interactive, bool tunes_at_the_device)
    : next_line_(std::move(next_line)),
      source_(std::move(source)),
      interactive_(interactive),
      tunes_at_the_device_(tunes_at_the_device) {}

std::optional<std::string> LineRespondent::next_line() {
  std::optional<std::string> text = next_line_();
  ++line_;
  return text;
}

std::string LineRespondent::answer(const PlanRow& row, const Stimulus&, const Stimulus&,
                                   std::ostream& prompts) {
  for (;;) {
    prompts << neutral_question(row.question) << std::flush;
    const std::optional<std::string> text = next_line();
    if (!text) {
      prompts << "\n";
      throw std::runtime_error(source_ + ": the answers ended at trial " +
                               std::to_string(row.trial));
    }
    if (!interactive_) prompts << *text << "\n";
    try {
      return normalized_answer(row.question, *text);
    } catch (const std::invalid_argument& wrong) {
      if (!interactive_) {
        throw std::runtime_error(source_ + ":" + std::to_string(line_) + ": trial " +
                                 std::to_string(row.trial) + ": " + wrong.what());
      }
      prompts << wrong.what() << "; again please\n";
    }
  }
}

std::optional<std::string> Respondent::scripted_tuning_keys(int trial, std::string&) {
  throw std::logic_error("trial " + std::to_string(trial) +
                         ": this respondent does not tune at the device");
}

std::optional<std::string> LineRespondent::scripted_tuning_keys(int trial, std::string& where) {
  if (interactive_) return std::nullopt;
  const std::optional<std::string> line = next_line();
  where = source_ + ":" + std::to_string(line_);
  if (!line)
    throw std::runtime_error(source_ + ": the answers ended at trial " + std::to_string(trial));
  return line;
}

DoorModel LineRespondent::tune(const PlanRow& row, const DoorModel&, std::ostream&) {
  // Only reached by a LineRespondent made without tunes_at_the_device (campaign run makes it
  // with): its lines cannot tune a door after the presentation.
  throw std::runtime_error(
      "trial " + std::to_string(row.trial) +
      ": this respondent answers lines and cannot tune after a presentation (a person tunes "
      "during it, with the keys: docs/campaign.md, A person's tune trial)");
}

// --- stimuli -----------------------------------------------------------------------------

StimulusMaker::StimulusMaker(const Campaign& campaign)
    : campaign_(&campaign), base_(base_model(campaign)) {}

Stimulus StimulusMaker::named(const std::string& name) {
  if (const auto found = cache_.find(name); found != cache_.end()) return found->second;
  Stimulus stimulus;
  stimulus.name = name;
  if (const Variant* variant = campaign_->find_variant(name)) {
    if (variant->kind != Variant::Kind::kReal) stimulus.model = variant_model(*campaign_, *variant);
    if (variant->kind == Variant::Kind::kFile) stimulus.source = variant->file.string();
    stimulus.staging = {variant->scene, variant->sounds, variant->scene_file, variant->sounds_file};
  } else {
    stimulus.model = apply_steps(base_, parse_steps(name));
  }
  if (stimulus.model) stimulus.parameters = rendered_parameters(*stimulus.model);
  cache_.emplace(name, stimulus);
  return stimulus;
}

const Block& block_of(const Campaign& campaign, const PlanRow& row) {
  for (const Block& block : campaign.blocks) {
    if (block.name == row.block) return block;
  }
  throw std::invalid_argument("the plan's block '" + row.block + "' is not in the campaign file");
}

std::pair<Stimulus, Stimulus> StimulusMaker::make(const PlanRow& row,
                                                  const std::vector<bool>& correct) {
  std::string first = row.first, second = row.second;
  const Block& block = block_of(*campaign_, row);
  if (block.type == BlockType::kJnd && block.method != JndMethod::kConstantStimuli) {
    const double adaptive = block.method == JndMethod::kStaircase ? staircase_level(block, correct)
                                                                  : quest_level(block, correct);
    const std::string level = jnd_stimulus_name(block.parameter, adaptive);
    if (first == block.parameter + "*?") first = level;
    if (second == block.parameter + "*?") second = level;
  }
  if (block.type == BlockType::kTune) return {named(first), Stimulus{}};
  return {named(first), named(second)};
}

double StimulusMaker::quest_level(const Block& block, const std::vector<bool>& answers) {
  auto kept = quests_.find(block.name);
  if (kept == quests_.end() || answers.size() < kept->second.answers.size() ||
      !std::equal(kept->second.answers.begin(), kept->second.answers.end(), answers.begin())) {
    QuestPlus fresh(quest_plus_grid(block));
    const std::size_t next = fresh.next_level();
    kept = quests_.insert_or_assign(block.name, QuestTrack{std::move(fresh), {}, next}).first;
  }
  QuestTrack& track = kept->second;
  while (track.answers.size() < answers.size()) {
    const bool answer = answers[track.answers.size()];
    track.quest.update(track.next, answer);
    track.answers.push_back(answer);
    track.next = track.quest.next_level();
  }
  return track.quest.grid().levels[track.next];
}

bool names_comparison(const std::string& first, const std::string& second,
                      const std::string& answer, const std::string& parameter) {
  const std::string standard = jnd_stimulus_name(parameter, 1.0);
  const int comparison = first == standard ? 2 : 1;
  (void)second;
  return answer == std::to_string(comparison);
}

const std::vector<std::string>& trials_columns() {
  static const std::vector<std::string> columns{"participant",
                                                "block",
                                                "trial",
                                                "question",
                                                "first",
                                                "second",
                                                "answer",
                                                "attempt",
                                                "answered_utc",
                                                "sessions",
                                                "first_parameters",
                                                "second_parameters",
                                                "first_scene",
                                                "first_sounds",
                                                "second_scene",
                                                "second_sounds"};
  return columns;
}

// --- the run ------------------------------------------------------------------------------

namespace {

struct RunState {
  const CampaignFolder* folder;
  std::string participant;
  int attempt = 1;
  fs::path session_dir;                                // sessions/P/aN
  std::map<std::string, std::vector<bool>> staircase;  // block -> answers named the comparison
};

// Checks the participant's rows of this attempt against the plan and rebuilds the staircases
// (and QUEST+ posteriors: both are replayed from the block's answers).
void check_existing(const TrialsTable& table, const std::vector<std::size_t>& rows,
                    const std::vector<PlanRow>& plan, RunState& state) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::size_t r = rows[i];
    const int line = table.line_numbers[r];
    if (i >= plan.size())
      throw TrialsTableError(table.source, line,
                             "more rows for " + state.participant + " than the plan has trials");
    const PlanRow& planned = plan[i];
    const Block& block = block_of(state.folder->campaign, planned);
    const bool staircase =
        block.type == BlockType::kJnd && block.method != JndMethod::kConstantStimuli;  // or quest+
    const bool same = table.value(r, "trial") == std::to_string(planned.trial) &&
                      table.value(r, "block") == planned.block &&
                      table.value(r, "question") == planned.question &&
                      (staircase || (table.value(r, "first") == planned.first &&
                                     table.value(r, "second") == planned.second));
    if (!same) {
      throw TrialsTableError(table.source, line,
                             "participant " + state.participant + ", trial " +
                                 table.value(r, "trial") + " does not match the plan's trial " +
                                 std::to_string(planned.trial) +
                                 " (is this trials.csv from another plan?)");
    }
    if (block.type == BlockType::kJnd) {
      state.staircase[block.name].push_back(
          names_comparison(table.value(r, "first"), table.value(r, "second"),
                           table.value(r, "answer"), block.parameter));
    }
  }
}

// The trial's row, in trials_columns()'s order.
std::vector<std::string> run_one_trial(RunState& state, const PlanRow& row, int planned,
                                       StimulusMaker& maker, Respondent& respondent,
                                       const Presenter& presenter, std::ostream& prompts) {
  const Block& block = block_of(state.folder->campaign, row);
  auto [first, second] = maker.make(row, state.staircase[block.name]);
  move_leftovers(state.session_dir, state.session_dir.parent_path() / "interrupted",
                 trial_file(row.trial, "-"));
  fs::create_directories(state.session_dir);
  const fs::path relative_dir =
      fs::path("sessions") / state.participant / (std::string("a") + std::to_string(state.attempt));
  std::string sessions, answer;
  Presented presented[2];
  auto present = [&](int position, const Stimulus& stimulus,
                     std::optional<DoorModel>* tuned = nullptr) {
    prompts << "trial " << row.trial << " of " << planned << ": presentation " << position
            << std::endl;
    const std::string file =
        trial_file(row.trial, std::string("-") + std::to_string(position) + ".h5");
    PresentationCall call{state.participant,
                          row.trial,
                          position,
                          &stimulus,
                          state.session_dir / file,
                          tuned,
                          tuned ? &respondent : nullptr,
                          0.0,
                          std::to_string(position),
                          &presented[position - 1]};
    presenter(call);
    if (!sessions.empty()) sessions += ' ';
    sessions += (relative_dir / file).generic_string();
  };
  if (block.type == BlockType::kTune) {
    std::optional<DoorModel> tuned_at_the_device;
    if (respondent.tunes_at_the_device()) {
      present(1, first, &tuned_at_the_device);
      if (!tuned_at_the_device)
        throw std::logic_error("the presenter gave no tuned door for trial " +
                               std::to_string(row.trial));
    } else {
      present(1, first);
      prompts << "trial " << row.trial << " of " << planned << ": tuning with the keys"
              << std::endl;
    }
    const DoorModel tuned =
        tuned_at_the_device ? *tuned_at_the_device : respondent.tune(row, *first.model, prompts);
    const std::string file = trial_file(row.trial, "-tuned.json");
    write_file_atomically(state.session_dir / file,
                          [&](std::ostream& out) { out << to_parameter_json(tuned); });
    second = Stimulus{"tuned", tuned, rendered_parameters(tuned), "the tuned door", {}};
    present(2, second);
    answer = (relative_dir / file).generic_string();
  } else {
    present(1, first);
    present(2, second);
    answer = respondent.answer(row, first, second, prompts);
  }
  if (block.type == BlockType::kJnd) {
    state.staircase[block.name].push_back(
        names_comparison(first.name, second.name, answer, block.parameter));
  }
  return {state.participant,
          row.block,
          std::to_string(row.trial),
          row.question,
          first.name,
          block.type == BlockType::kTune ? "" : second.name,
          answer,
          std::to_string(state.attempt),
          utc_now(),
          sessions,
          first.parameters,
          second.parameters,
          presented[0].scene,
          presented[0].sounds,
          presented[1].scene,
          presented[1].sounds};
}

// `fields` (in trials_columns()'s order) as a row of a file whose header is `header`: a
// column the header lacks is left out, one that trials_columns() lacks is left empty.
std::string row_in_header(const std::vector<std::string>& fields,
                          const std::vector<std::string>& header) {
  const std::vector<std::string>& columns = trials_columns();
  std::vector<std::string> row;
  for (const std::string& name : header) {
    const auto at = std::find(columns.begin(), columns.end(), name);
    row.push_back(at == columns.end() ? "" : fields[std::size_t(at - columns.begin())]);
  }
  return csv_row(row);
}

// The columns of trials_columns() that `header` lacks, as "a, b" ("" when none).
std::string missing_columns(const std::vector<std::string>& header) {
  std::string missing;
  for (const std::string& name : trials_columns()) {
    if (std::find(header.begin(), header.end(), name) == header.end())
      missing += (missing.empty() ? "" : ", ") + name;
  }
  return missing;
}

}  // namespace

RunResult run_participant(const CampaignFolder& folder, const RunOptions& options,
                          Respondent& respondent, const Presenter& presenter,
                          std::ostream& prompts) {
  const std::vector<PlanRow> plan = folder.plan.of(options.participant);
  if (plan.empty()) {
    std::string ids;
    for (const std::string& id : folder.campaign.participants)
      ids += (ids.empty() ? "" : ", ") + id;
    throw std::runtime_error("participant " + options.participant +
                             " is not in the plan (its participants: " + ids + ")");
  }
  ParticipantLock lock(folder.dir, options.participant);
  const fs::path trials_path = folder.dir / "trials.csv";
  if (!fs::exists(trials_path)) {
    TrialsAppender(trials_path).append(csv_row(trials_columns()));
  } else if (const std::size_t cut = cut_torn_tail(trials_path); cut > 0) {
    prompts << trials_path.string() << ": cut off a torn last line (" << cut
            << " bytes) left by an interrupted write\n";
  }
  const TrialsTable table = read_trials_table(trials_path);
  const Existing existing = existing_rows(table, options.participant);
  RunState state;
  state.folder = &folder;
  state.participant = options.participant;
  RunResult result;
  result.planned = static_cast<int>(plan.size());
  result.attempt = std::max(existing.attempt, 1);
  std::vector<std::size_t> rows = existing.rows;
  if (rows.size() == plan.size()) {
    if (!options.redo) {
      throw std::runtime_error(
          "participant " + options.participant + " has answered all " +
          std::to_string(plan.size()) + " trials (attempt " + std::to_string(existing.attempt) +
          "); give --redo to run them again (the earlier answers are kept, marked by attempt)");
    }
    ++result.attempt;
    rows.clear();
  } else if (options.redo) {
    throw std::runtime_error("--redo is for a participant who has finished; " +
                             options.participant + " has answered " + std::to_string(rows.size()) +
                             " of " + std::to_string(plan.size()) +
                             " trials: run without --redo to resume");
  }
  state.attempt = result.attempt;
  state.session_dir = folder.dir / "sessions" / options.participant /
                      (std::string("a") + std::to_string(state.attempt));
  check_existing(table, rows, plan, state);
  result.answered_before = static_cast<int>(rows.size());
  respondent.set_attempt(state.attempt);
  StimulusMaker maker(folder.campaign);
  TrialsAppender appender(trials_path);
  if (result.answered_before > 0) {
    prompts << "resuming at trial " << result.answered_before + 1 << " of " << result.planned
            << "\n";
  }
  if (const std::string missing = missing_columns(table.column_names); !missing.empty()) {
    prompts << trials_path.string() << " was begun by an earlier doorbench without the columns "
            << missing << ": its rows are written without them\n";
  }
  for (std::size_t t = rows.size(); t < plan.size(); ++t) {
    std::vector<std::string> row;
    try {
      row = run_one_trial(state, plan[t], result.planned, maker, respondent, presenter, prompts);
    } catch (const std::exception& failure) {
      throw std::runtime_error("trial " + std::to_string(plan[t].trial) + " of " +
                               std::to_string(result.planned) + " stopped: " + failure.what() +
                               " (the " + std::to_string(t) + " answers before it are in " +
                               trials_path.string() + "; run the same command again to resume)");
    }
    appender.append(row_in_header(row, table.column_names));
    ++result.answered_now;
    prompts << "trial " << plan[t].trial << " of " << result.planned << ": answered" << std::endl;
  }
  return result;
}

// --- merge --------------------------------------------------------------------------------

namespace {

void link_or_copy_tree(const fs::path& from, const fs::path& to) {
  if (!fs::exists(from)) return;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(from)) {
    const fs::path target = to / fs::relative(entry.path(), from);
    if (entry.is_directory()) {
      fs::create_directories(target);
      continue;
    }
    if (!entry.is_regular_file()) continue;
    fs::create_directories(target.parent_path());
    if (fs::exists(target))
      throw std::runtime_error(target.string() + ": exists (two folders hold the same file)");
    std::error_code linked;
    fs::create_hard_link(entry.path(), target, linked);
    if (linked) fs::copy_file(entry.path(), target);
  }
}

}  // namespace

void merge_campaign_folders(const std::vector<fs::path>& dirs, const fs::path& out) {
  if (dirs.size() < 2) throw std::runtime_error("merge needs at least two campaign folders");
  std::vector<PlanIdentity> identities;
  for (const fs::path& dir : dirs) identities.push_back(read_plan_identity(dir));
  for (std::size_t i = 1; i < dirs.size(); ++i) {
    if (identities[i].plan_hash != identities[0].plan_hash ||
        identities[i].seed != identities[0].seed) {
      throw std::runtime_error(
          dirs[i].string() + " and " + dirs[0].string() + " are not of the same plan (plan " +
          identities[i].plan_hash + " seed " + std::to_string(identities[i].seed) + " vs plan " +
          identities[0].plan_hash + " seed " + std::to_string(identities[0].seed) + ")");
    }
  }
  check_output_folder(out, dirs, false);
  std::string merged = csv_row(trials_columns());
  std::map<std::string, fs::path> owner;
  for (const fs::path& dir : dirs) {
    if (!fs::exists(dir / "trials.csv")) continue;
    const TrialsTable table = read_trials_table(dir / "trials.csv");
    for (std::size_t r = 0; r < table.rows.size(); ++r) {
      const std::string& participant = table.value(r, "participant");
      const auto [it, fresh] = owner.emplace(participant, dir);
      if (!fresh && it->second != dir) {
        throw std::runtime_error("participant " + participant + " has rows in both " +
                                 it->second.string() + " and " + dir.string() +
                                 "; merge joins folders of different participants");
      }
      std::vector<std::string> fields;
      for (const std::string& column : trials_columns())
        fields.push_back(table.find_column(column) ? table.value(r, column) : "");
      merged += csv_row(fields);
    }
  }
  fs::create_directories(out);
  for (const char* name : {"campaign.toml", "plan.csv", "plan-id.txt"})
    fs::copy_file(dirs[0] / name, out / name);
  for (const fs::path& dir : dirs) link_or_copy_tree(dir / "sessions", out / "sessions");
  write_file_atomically(out / "trials.csv", [&](std::ostream& stream) { stream << merged; });
}

}  // namespace doorbench::study
