// Not a timing: the residual loop's datasheet (docs/residual-loop.md, "The datasheet"). For
// each catalogue effect at each size of its ladder, the loop runs on recordings drawn from
// the recording family (fixtures/recording_family.h), the truth being the sensory
// reference door with the effect added; and on clean recordings (the reference door alone)
// for the false additions. Every run is one line of a CSV (resumed: runs already in it are
// skipped); the markdown tables are made from the whole CSV.
//
//   doorbench_loop_datasheet --csv FILE [--effects LIST] [--sizes LIST] [--draws N]
//                            [--clean-draws N] [--strokes N] [--jobs N] [--first-seed S]
//                            [--table-only] [--full-loop]
//   --effects: catalogue names and/or "clean", comma-separated (default: all and clean)
//   --sizes: amplitudes in the effect's unit (d_s - d1 for stribeck), with one effect only
//            (default: the effect's ladder)
//   --draws N: recordings per size (default 20); --clean-draws N: clean ones (default 100)
//   --strokes N: FamilyOptions::strokes (default 12); --jobs N: runs at once (default 1)
//   --first-seed S: draw d (from 1) has seed S + d - 1 (default 1)
//   --table-only: no runs, the tables of FILE; with the same choice of runs, it also lists
//                 the runs asked for that FILE does not hold yet
//   --full-loop: the whole loop (max_steps and the structure check at their defaults), for
//                its CPU time per recording (docs/PERFORMANCE.md); "found first" is still
//                the first step's effect. Keep its runs in a CSV of their own.
//   --rate HZ: every draw sampled at HZ (the other conditions as drawn)
//   --stroke-seconds LO:HI, --total-seconds LO:HI: only draws whose clean recording has
//                `--strokes` strokes, each lasting LO-HI s, summing to LO-HI s; draw d is then
//                the d-th such seed from --first-seed on (a class of recordings, e.g. the
//                12-stroke, 32 s ones of docs/PERFORMANCE.md's CPU bar)
//
// Each run: LoopOptions' defaults but max_steps = 1 (the first added effect is the answer),
// no structure check, one fit thread and the refits one after another (the jobs run
// at once instead; the loop's decisions do not depend on threads, docs/fitting.md); for the
// inertia error J is held, as the loop's tests do (J free absorbs it).
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "analysis/loop/residual_loop.h"
#include "analysis/model/parameter_file.h"
#include "core/number_format.h"
#include "core/parallel.h"
#include "fixtures/recording_family.h"
#include "studies/loop_datasheet_table.h"

using namespace doorbench;
using datasheet::RunRecord;

namespace {

using testing::draw_conditions;
using testing::family_recording;
using testing::FamilyOptions;
using testing::RecordingConditions;

// An effect's ladder of sizes: its amplitude (d_s − d1 for stribeck), from small to the size
// of the loop's tests (docs/residual-loop.md, "Measured"); the truth's other parameters are
// effect_values'.
struct EffectLadder {
  effects::Kind kind;
  std::vector<double> sizes;
  std::string unit;
  std::size_t typical = 0;  // the size of the loop's tests: run first
};

const std::vector<EffectLadder>& ladders() {
  static const std::vector<EffectLadder> all = {
      {effects::Kind::kViscousDamping, {0.05, 0.15, 0.5}, "N·m·s/rad", 2},
      {effects::Kind::kGravityImbalance, {0.3, 1.0, 3.0}, "N·m", 2},
      {effects::Kind::kStribeck, {0.5, 1.0, 1.5, 3.0}, "N·m", 2},
      {effects::Kind::kDirectionFriction, {0.15, 0.5, 1.5}, "N·m", 2},
      {effects::Kind::kSoftClose, {0.5, 1.5, 5.0}, "N·m·s/rad", 2},
      {effects::Kind::kEndStop, {20.0, 60.0, 200.0}, "N·m/rad", 2},
      {effects::Kind::kForceOffset, {0.3, 1.0, 3.0}, "N", 2},
      {effects::Kind::kInertiaError, {0.02, 0.06, 0.2}, "kg·m²", 2},
  };
  return all;
}

// The truth's effect values at amplitude `size`.
std::vector<double> effect_values(effects::Kind kind, double size, double d1) {
  switch (kind) {
    case effects::Kind::kStribeck:
      return {d1 + size, 0.05};
    case effects::Kind::kSoftClose:
      return {size, 0.15, 50.0};
    case effects::Kind::kEndStop:
      return {size, 1.2, 3000.0};
    default:
      return {size};
  }
}

DoorModel with_effect(const DoorModel& model, effects::Kind kind, std::vector<double> values) {
  EffectSetting setting{kind, std::move(values), {}};
  for (const effects::EffectParameter& p : effects::info(kind).parameters) {
    setting.bounds.push_back(p.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

// One run to do.
struct Job {
  std::string effect;  // catalogue name or "clean"
  int size_rank = 0;
  double size = 0.0;
  std::string unit;
  int draw = 0;
};

// A closed interval of seconds, "LO:HI" on the command line.
struct SecondsRange {
  double lo_s = 0.0, hi_s = std::numeric_limits<double>::infinity();
  bool contains(double s) const { return s >= lo_s && s <= hi_s; }
};

struct Settings {
  std::string csv;
  std::vector<std::string> effects;
  std::vector<double> sizes;
  int draws = 20, clean_draws = 100, strokes = 12, jobs = 1;
  unsigned long first_seed = 1;
  bool table_only = false;
  bool full_loop = false;
  double rate_hz = 0.0;  // 0: as drawn
  std::optional<SecondsRange> stroke_s, total_s;
  std::vector<unsigned long> draw_seeds;  // draw d's seed is draw_seeds[d - 1] (run_pending)
};

std::vector<std::string> split(const std::string& text, char by) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, by)) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

int positive(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  int value = 0;
  try {
    value = std::stoi(text, &used);
  } catch (const std::logic_error&) {
    used = 0;
  }
  if (used != text.size() || value < 1) {
    throw std::invalid_argument(flag + " must be a whole number >= 1, not '" + text + "'");
  }
  return value;
}

SecondsRange seconds_range(const std::string& flag, const std::string& text) {
  const std::vector<std::string> parts = split(text, ':');
  SecondsRange range;
  std::size_t used_lo = 0, used_hi = 0;
  try {
    if (parts.size() == 2) {
      range.lo_s = std::stod(parts[0], &used_lo);
      range.hi_s = std::stod(parts[1], &used_hi);
    }
  } catch (const std::logic_error&) {
    used_lo = 0;
  }
  if (parts.size() != 2 || used_lo != parts[0].size() || used_hi != parts[1].size() ||
      !(range.lo_s >= 0.0) || !(range.hi_s >= range.lo_s)) {
    throw std::invalid_argument(flag + " must be LO:HI seconds with 0 <= LO <= HI, not '" + text +
                                "'");
  }
  return range;
}

Settings parse_arguments(int argc, char** argv) {
  Settings s;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--table-only" || flag == "--full-loop") {
      (flag == "--table-only" ? s.table_only : s.full_loop) = true;
      continue;
    }
    if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--csv")
      s.csv = value;
    else if (flag == "--effects")
      s.effects = split(value, ',');
    else if (flag == "--sizes") {
      for (const std::string& v : split(value, ',')) s.sizes.push_back(std::stod(v));
    } else if (flag == "--draws")
      s.draws = positive(flag, value);
    else if (flag == "--clean-draws")
      s.clean_draws = positive(flag, value);
    else if (flag == "--strokes")
      s.strokes = positive(flag, value);
    else if (flag == "--jobs")
      s.jobs = positive(flag, value);
    else if (flag == "--first-seed")
      s.first_seed = std::stoul(value);
    else if (flag == "--rate")
      s.rate_hz = positive(flag, value);
    else if (flag == "--stroke-seconds")
      s.stroke_s = seconds_range(flag, value);
    else if (flag == "--total-seconds")
      s.total_s = seconds_range(flag, value);
    else
      throw std::invalid_argument("unknown option " + flag);
  }
  if (s.csv.empty()) throw std::invalid_argument("--csv FILE is required");
  if (s.effects.empty()) {
    for (const EffectLadder& l : ladders()) s.effects.emplace_back(effects::info(l.kind).name);
    s.effects.emplace_back("clean");
  }
  for (const std::string& e : s.effects) {
    if (e != "clean" && !effects::find(e)) throw std::invalid_argument("unknown effect " + e);
  }
  const auto catalogue_effects = std::count_if(s.effects.begin(), s.effects.end(),
                                               [](const std::string& e) { return e != "clean"; });
  if (!s.sizes.empty() && catalogue_effects != 1) {
    throw std::invalid_argument("--sizes needs exactly one catalogue effect in --effects");
  }
  return s;
}

// The runs the settings ask for, in the order they run, so that a run cut short leaves
// whole rows of the most useful kind: the clean recordings first, then every effect at its
// typical size, then each effect's next smaller size, and so on, the sizes above the
// typical one last; within a row the draws in order.
std::vector<Job> planned_jobs(const Settings& s) {
  struct Ranked {
    std::size_t level;
    Job job;
  };
  std::vector<Ranked> ranked;
  for (const std::string& e : s.effects) {
    if (e == "clean") {
      for (int d = 1; d <= s.clean_draws; ++d) ranked.push_back({0, {"clean", 0, 0.0, "", d}});
      continue;
    }
    const effects::Kind kind = effects::find(e).value();
    const EffectLadder& ladder = ladders()[static_cast<std::size_t>(kind)];
    const std::vector<double>& sizes = s.sizes.empty() ? ladder.sizes : s.sizes;
    const std::size_t typical = s.sizes.empty() ? ladder.typical : sizes.size() - 1;
    for (std::size_t k = 0; k < sizes.size(); ++k) {
      const std::size_t level = 1 + (k <= typical ? typical - k : k + sizes.size());
      for (int d = 1; d <= s.draws; ++d) {
        ranked.push_back({level, {e, static_cast<int>(k) + 1, sizes[k], ladder.unit, d}});
      }
    }
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const Ranked& a, const Ranked& b) { return a.level < b.level; });
  std::vector<Job> jobs;
  for (const Ranked& r : ranked) jobs.push_back(r.job);
  return jobs;
}

bool same_run(const Job& job, const RunRecord& r) {
  return job.effect == r.effect && job.size == r.size && job.draw == r.draw;
}

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

LoopOptions loop_options_for(const Job& job, bool full_loop, std::string& described) {
  LoopOptions options;
  if (!full_loop) {
    options.max_steps = 1;
    options.structure_check = false;
  }
  options.parallel_refits = false;
  options.fit.num_threads = 1;
  described = full_loop ? "the whole loop (max_steps " + std::to_string(options.max_steps) +
                              ", structure check)"
                        : std::string("max_steps 1, no structure check");
  if (job.effect == "inertia_error") {
    options.fit.fixed_parameters = {"J"};
    described += ", J held";
  }
  return options;
}

// The true effect's and the best candidate's evidence in the first examination.
void record_evidence(const std::vector<CandidateEvidence>& ranking, RunRecord& r) {
  if (!ranking.empty()) {
    r.best_name = ranking.front().name;
    r.best_share = ranking.front().explained_fraction;
    r.best_z = ranking.front().score_z;
  }
  for (const CandidateEvidence& c : ranking) {
    if (c.name != r.effect) continue;
    r.true_rank = c.rank;
    r.true_share = c.explained_fraction;
    r.true_z = c.score_z;
    r.true_screen_share = c.screened ? c.screen_explained_fraction : 0.0;
    r.true_screen_z = c.screened ? c.screen_score_z : 0.0;
    r.true_verdict = c.verdict;
  }
}

// The added effect's fitted parameters against the truth's values (`truth` empty for a
// wrong effect or clean: truth "nan").
std::string recovered_parameters(const LoopStep& step, const std::vector<double>& truth) {
  std::vector<datasheet::ParameterRecovery> out;
  const auto& catalogue_parameters = effects::info(step.effect).parameters;
  for (std::size_t i = 0; i < catalogue_parameters.size(); ++i) {
    const std::string name =
        std::string(step.effect_name) + "." + std::string(catalogue_parameters[i].info.name);
    for (const FittedParameter& p : step.parameters) {
      if (p.name != name || !p.free) continue;
      const double u = p.determined ? p.uncertainty : std::nan("");
      out.push_back({std::string(catalogue_parameters[i].info.name),
                     i < truth.size() ? truth[i] : std::nan(""), p.value, u});
    }
  }
  return datasheet::format_parameters(out);
}

// Seed `seed`'s recording conditions: drawn, then the settings' rate.
RecordingConditions conditions_of(unsigned long seed, const Settings& s) {
  FamilyOptions family;
  family.strokes = s.strokes;
  RecordingConditions conditions = draw_conditions(static_cast<std::uint32_t>(seed), family);
  if (s.rate_hz > 0) conditions.sample_rate_hz = s.rate_hz;
  return conditions;
}

// Whether seed `seed`'s clean recording is of the class --stroke-seconds and --total-seconds
// ask for: s.strokes strokes, each and their sum within the ranges.
bool in_class(unsigned long seed, const Settings& s, const DoorModel& reference) {
  const PreparedData data =
      family_recording(reference, conditions_of(seed, s), static_cast<std::uint32_t>(seed));
  if (static_cast<int>(data.strokes.size()) != s.strokes) return false;
  double total_s = 0.0;
  for (const Stroke& stroke : data.strokes) {
    const double stroke_s = stroke.time_s.back() - stroke.time_s.front();
    if (s.stroke_s && !s.stroke_s->contains(stroke_s)) return false;
    total_s += stroke_s;
  }
  return !s.total_s || s.total_s->contains(total_s);
}

// Each draw's seed: first_seed + d - 1, or with --stroke-seconds / --total-seconds the
// d-th seed from first_seed on whose recording is of the class (at most 100 seeds per draw
// are tried).
std::vector<unsigned long> draw_seeds(const Settings& s, const DoorModel& reference) {
  int wanted = 0;
  for (const std::string& e : s.effects)
    wanted = std::max(wanted, e == "clean" ? s.clean_draws : s.draws);
  std::vector<unsigned long> seeds;
  if (!s.stroke_s && !s.total_s) {
    for (int d = 0; d < wanted; ++d) seeds.push_back(s.first_seed + static_cast<unsigned long>(d));
    return seeds;
  }
  const unsigned long last = s.first_seed + 100UL * static_cast<unsigned long>(wanted) - 1;
  for (unsigned long seed = s.first_seed; seed <= last && static_cast<int>(seeds.size()) < wanted;
       ++seed) {
    if (in_class(seed, s, reference)) seeds.push_back(seed);
  }
  if (static_cast<int>(seeds.size()) < wanted) {
    throw std::runtime_error(printf_text(
        "only %zu of the %d draws asked for have recordings of the class among seeds %lu-%lu",
        seeds.size(), wanted, s.first_seed, last));
  }
  std::string list;
  for (unsigned long seed : seeds) list += (list.empty() ? "" : " ") + std::to_string(seed);
  std::fprintf(stderr, "draws of the class: seeds %s\n", list.c_str());
  return seeds;
}

RunRecord run_one(const Job& job, const Settings& s, const DoorModel& reference, double d1) {
  const double cpu0 = thread_cpu_s();
  const auto wall0 = std::chrono::steady_clock::now();
  RunRecord r;
  r.effect = job.effect;
  r.size_rank = job.size_rank;
  r.size = job.size;
  r.size_unit = job.unit;
  r.draw = job.draw;
  r.seed = s.draw_seeds[static_cast<std::size_t>(job.draw) - 1];
  const LoopOptions options = loop_options_for(job, s.full_loop, r.loop_options);
  std::vector<double> truth;
  DoorModel model = reference;
  if (job.effect != "clean") {
    const effects::Kind kind = effects::find(job.effect).value();
    truth = effect_values(kind, job.size, d1);
    model = with_effect(reference, kind, truth);
  }
  try {
    const auto seed = static_cast<std::uint32_t>(r.seed);
    const RecordingConditions conditions = conditions_of(r.seed, s);
    r.hand = conditions.hand;
    r.sample_rate_hz = conditions.sample_rate_hz;
    r.sensors = conditions.sensors;
    r.conditions = conditions.describe();
    const PreparedData data = family_recording(model, conditions, seed);
    r.strokes = static_cast<int>(data.strokes.size());
    const LoopResult loop = run_residual_loop(reference, data, options);
    r.status = "ok";
    r.start_held_out_rad_s = model_figures(loop.start_fit.summary).held_out_rmse_rad_s;
    r.final_held_out_rad_s = model_figures(loop.final_fit.summary).held_out_rmse_rad_s;
    r.first_added = loop.steps.empty() ? "none" : loop.steps.front().effect_name;
    record_evidence(loop.steps.empty() ? loop.last_candidates : loop.steps.front().candidates, r);
    if (!loop.steps.empty()) {
      const bool right = loop.steps.front().effect_name == job.effect;
      r.parameters =
          recovered_parameters(loop.steps.front(), right ? truth : std::vector<double>{});
    }
  } catch (const std::exception& e) {
    r.status = std::string("error: ").append(e.what());
  }
  r.cpu_s = thread_cpu_s() - cpu0;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return r;
}

// Runs the jobs not yet in `records` on s.jobs threads, rewriting the CSV after each.
void run_pending(Settings& s, std::vector<RunRecord>& records) {
  std::vector<Job> pending;
  for (const Job& job : planned_jobs(s)) {
    bool done = false;
    for (const RunRecord& r : records) done = done || same_run(job, r);
    if (!done) pending.push_back(job);
  }
  std::fprintf(stderr, "%zu runs planned, %zu already in %s, %zu to run on %d thread(s)\n",
               planned_jobs(s).size(), planned_jobs(s).size() - pending.size(), s.csv.c_str(),
               pending.size(), s.jobs);
  const DoorModel reference = reference_model(ModelKind::kSensory);
  const double d1 = reference.parameter_values()[reference.find_parameter("d1").value()];
  if (!pending.empty()) s.draw_seeds = draw_seeds(s, reference);
  std::mutex mutex;
  std::atomic<int> finished{0};
  parallel_for(static_cast<int>(pending.size()), s.jobs, [&](int i) {
    const RunRecord r = run_one(pending[static_cast<std::size_t>(i)], s, reference, d1);
    const std::lock_guard<std::mutex> lock(mutex);
    records.push_back(r);
    write_text_file_atomically(s.csv, datasheet::run_csv(records));
    std::fprintf(stderr, "[%d/%zu] %s %g draw %d (%s): %s, first added %s; %.1f s CPU\n",
                 ++finished, pending.size(), r.effect.c_str(), r.size, r.draw, r.conditions.c_str(),
                 r.status.c_str(), r.first_added.c_str(), r.cpu_s);
  });
}

// The rows the settings ask for that the CSV does not hold in full: "stribeck 0.5 N·m:
// 12 of 20 draws", for the tables' last section.
std::string missing_rows(const Settings& s, const std::vector<RunRecord>& records) {
  std::vector<std::pair<std::string, int>> rows;  // "effect size unit", runs missing
  for (const Job& job : planned_jobs(s)) {
    bool done = false;
    for (const RunRecord& r : records) done = done || same_run(job, r);
    if (done) continue;
    const std::string name =
        job.effect == "clean" ? std::string("clean")
                              : job.effect + " " + format_significant(job.size, 4) + " " + job.unit;
    if (rows.empty() || rows.back().first != name) rows.emplace_back(name, 0);
    ++rows.back().second;
  }
  if (rows.empty()) return "";
  std::string out = "\n### Not run yet\n\n";
  for (const auto& [name, missing] : rows) {
    out += "- " + name + ": " + std::to_string(missing) + (missing == 1 ? " run" : " runs") +
           " missing\n";
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Settings settings;
  try {
    settings = parse_arguments(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "doorbench_loop_datasheet: %s\n", e.what());
    return 2;
  }
  try {
    std::vector<RunRecord> records = datasheet::read_run_csv(settings.csv);
    if (!settings.table_only) run_pending(settings, records);
    std::printf("%s%s", datasheet::datasheet_tables(records).c_str(),
                missing_rows(settings, records).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "doorbench_loop_datasheet: %s\n", e.what());
    return 1;
  }
  return 0;
}
