#include "study/campaign_plan.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <numeric>
#include <random>
#include <sstream>

#include "acquisition/session/output_file.h"
#include "analysis/model/perceptual_controls.h"
#include "study/latin_square.h"
#include "study/random_stream.h"
#include "study/trials_table.h"
#include "study/tuning_keys.h"

namespace doorbench::study {
namespace {

struct Pending {
  std::string question, first, second;
};

std::string level_text(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  std::string text = buffer;
  if (text.find('.') != std::string::npos) {
    while (text.back() == '0') text.pop_back();
    if (text.back() == '.') text.pop_back();
  }
  return text;
}

// The controls the tuning keys move, each once, in the key map's order.
std::vector<perceptual::Control> tuned_controls() {
  std::vector<perceptual::Control> controls;
  for (const TuningKey& key : tuning_keys()) {
    bool seen = false;
    for (perceptual::Control c : controls) seen = seen || c == key.control;
    if (!seen) controls.push_back(key.control);
  }
  return controls;
}

std::string tune_start(const Campaign& campaign, const Block& block, std::mt19937_64& random) {
  const DoorModel base = base_model(campaign);
  const double span = std::log1p(block.start_spread);
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::vector<Step> steps;
    for (perceptual::Control control : tuned_controls()) {
      const double factor = std::exp((2.0 * uniform_open01(random) - 1.0) * span);
      for (const perceptual::ControlInfo& info : perceptual::controls()) {
        if (info.control == control)
          steps.push_back({std::string(info.name), std::stod(level_text(factor, 3))});
      }
    }
    try {
      (void)apply_steps(base, steps);
      return steps_text(steps);
    } catch (const std::invalid_argument&) {
      // A start outside the bounds or the constraints: draw again.
    }
  }
  throw std::invalid_argument("block " + block.name +
                              ": no tuning start within the bounds after 100 draws (start_spread " +
                              level_text(block.start_spread, 3) + ")");
}

// The passes of a pair or rating block: a pair block repeats (the pairs one way, the pairs the
// other way) `repetitions` times; a rating block has one pass per repetition and attribute,
// the attributes of a repetition in cyclic order starting at attribute p mod A.
std::vector<std::string> pass_questions(const Block& block, int participant) {
  std::vector<std::string> questions;
  for (int r = 0; r < block.repetitions; ++r) {
    if (block.type == BlockType::kPair) {
      questions.insert(questions.end(), 2, std::string(to_string(block.question)));
      continue;
    }
    const int count = static_cast<int>(block.attributes.size());
    for (int a = 0; a < count; ++a) {
      questions.push_back("rating:" + block.attributes[(a + participant) % count] + ":" +
                          std::to_string(block.scale));
    }
  }
  return questions;
}

// A pair or rating block (docs/campaign.md, "Counterbalancing"): participant p takes row
// p mod R of the Williams design over the block's M pairs, its conditions relabelled by
// `labels` (the campaign's own permutation of the pairs). Pass k plays the row forwards
// when k is even and backwards when odd; pair j of the row is played as listed (a, b) when
// j + k + (p div R) is even, else (b, a). So each pair is played both ways in consecutive
// passes, and participants p and p + R see the same pair order with every presentation
// order swapped.
std::vector<Pending> paired_trials(const Block& block, int participant,
                                   const std::vector<int>& labels) {
  const std::vector<std::vector<int>> design =
      williams_design(static_cast<int>(block.pairs.size()));
  const std::vector<int>& row = design[participant % design.size()];
  const int swap = participant / static_cast<int>(design.size()) % 2;
  const std::vector<std::string> questions = pass_questions(block, participant);
  std::vector<Pending> trials;
  for (std::size_t k = 0; k < questions.size(); ++k) {
    for (std::size_t i = 0; i < row.size(); ++i) {
      const std::size_t position = k % 2 == 0 ? i : row.size() - 1 - i;
      const int j = labels[row[position]];
      const auto& [a, b] = block.pairs[j];
      const bool as_listed = (static_cast<std::size_t>(j) + k + swap) % 2 == 0;
      trials.push_back(as_listed ? Pending{questions[k], a, b} : Pending{questions[k], b, a});
    }
  }
  return trials;
}

// A random relabelling of a pair or rating block's pairs, one per campaign and block: the
// Williams design's condition c stands for pair labels[c]. Identity for other blocks.
std::vector<int> pair_labels(const Block& block, std::uint64_t seed, std::size_t block_index) {
  std::vector<int> labels(block.pairs.size());
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(i);
  if (block.type == BlockType::kPair || block.type == BlockType::kRating) {
    std::mt19937_64 random(substream_seed(seed, 0, block_index, Purpose::kSquareLabels));
    shuffle_in_place(labels, random);
  }
  return labels;
}

std::vector<Pending> block_trials(const Campaign& campaign, const Block& block, int participant,
                                  const std::vector<int>& labels, std::mt19937_64& random) {
  std::vector<Pending> trials;
  switch (block.type) {
    case BlockType::kTune:
      trials.push_back({"tune", tune_start(campaign, block, random), ""});
      return trials;
    case BlockType::kPair:
    case BlockType::kRating:
      return paired_trials(block, participant, labels);
    case BlockType::kJnd: {
      const std::string question = "stronger:" + block.parameter;
      const std::string standard = jnd_stimulus_name(block.parameter, 1.0);
      std::vector<std::string> comparisons;
      if (block.method == JndMethod::kConstantStimuli) {
        for (int r = 0; r < block.repetitions; ++r) {
          for (double level : block.levels)
            comparisons.push_back(jnd_stimulus_name(block.parameter, level));
        }
      } else {
        comparisons.assign(block.trials, block.parameter + "*?");
      }
      // The comparison first in half of the trials (one more chosen by the draw when odd).
      std::vector<bool> first(comparisons.size(), false);
      for (std::size_t i = 0; i < first.size(); ++i) first[i] = i % 2 == 0;
      if (first.size() % 2 == 1) first.back() = uniform_below(random, 2) == 0;
      shuffle_in_place(first, random);
      for (std::size_t i = 0; i < comparisons.size(); ++i) {
        trials.push_back(first[i] ? Pending{question, comparisons[i], standard}
                                  : Pending{question, standard, comparisons[i]});
      }
      if (block.method != JndMethod::kConstantStimuli)
        return trials;  // adaptive: slots stay in order
      break;
    }
  }
  shuffle_in_place(trials, random);
  return trials;
}

}  // namespace

std::vector<PlanRow> Plan::of(const std::string& participant) const {
  std::vector<PlanRow> result;
  for (const PlanRow& row : rows) {
    if (row.participant == participant) result.push_back(row);
  }
  return result;
}

std::string jnd_stimulus_name(const std::string& parameter, double level) {
  return parameter + "*" + level_text(level, 4);
}

Plan make_plan(const Campaign& campaign, std::uint64_t seed) {
  Plan plan;
  plan.seed = seed;
  const std::vector<std::vector<int>> orders =
      williams_design(static_cast<int>(campaign.blocks.size()));
  std::vector<std::vector<int>> labels;
  for (std::size_t b = 0; b < campaign.blocks.size(); ++b)
    labels.push_back(pair_labels(campaign.blocks[b], seed, b));
  for (std::size_t p = 0; p < campaign.participants.size(); ++p) {
    const std::vector<int>& order = orders[p % orders.size()];
    int trial = 0;
    for (int b : order) {
      const Block& block = campaign.blocks[b];
      std::mt19937_64 random(substream_seed(seed, p, b, Purpose::kTrialOrder));
      int block_trial = 0;
      for (Pending& pending :
           block_trials(campaign, block, static_cast<int>(p), labels[b], random)) {
        PlanRow row;
        row.participant = campaign.participants[p];
        row.block = block.name;
        row.trial = ++trial;
        row.block_trial = ++block_trial;
        row.question = std::move(pending.question);
        row.first = std::move(pending.first);
        row.second = std::move(pending.second);
        plan.rows.push_back(std::move(row));
      }
    }
  }
  return plan;
}

BalancedCount balanced_participant_count(const Campaign& campaign) {
  BalancedCount count;
  const auto add = [&count](long long rows, std::string part) {
    count.participants = std::lcm(count.participants, rows);
    count.parts.push_back(std::move(part.append(" ").append(std::to_string(rows))));
  };
  add(static_cast<long long>(williams_design(static_cast<int>(campaign.blocks.size())).size()),
      "block order");
  for (const Block& block : campaign.blocks) {
    if (block.type != BlockType::kPair && block.type != BlockType::kRating) continue;
    long long rows =
        2 * static_cast<long long>(williams_design(static_cast<int>(block.pairs.size())).size());
    if (block.type == BlockType::kRating)
      rows = std::lcm(rows, static_cast<long long>(block.attributes.size()));
    add(rows, std::string("block '").append(block.name).append("'"));
  }
  return count;
}

std::string balance_note(const Campaign& campaign) {
  const BalancedCount count = balanced_participant_count(campaign);
  const long long n = static_cast<long long>(campaign.participants.size());
  if (n % count.participants == 0) return "";
  std::string parts;
  for (const std::string& part : count.parts) parts.append(parts.empty() ? "" : ", ").append(part);
  return std::string("note: ")
      .append(std::to_string(n))
      .append(" participants; the counterbalancing is exact for a multiple of ")
      .append(std::to_string(count.participants))
      .append(" (")
      .append(parts)
      .append(
          "); participant i takes row i mod rows of each design (docs/campaign.md, "
          "Counterbalancing)");
}

std::string plan_csv(const Plan& plan) {
  std::string text =
      csv_row({"participant", "block", "trial", "question", "first", "second", "block_trial"});
  for (const PlanRow& row : plan.rows) {
    text += csv_row({row.participant, row.block, std::to_string(row.trial), row.question, row.first,
                     row.second, std::to_string(row.block_trial)});
  }
  return text;
}

Plan read_plan_csv(const std::filesystem::path& path, std::uint64_t seed) {
  static constexpr std::string_view kColumns[] = {"participant", "block",  "trial",      "question",
                                                  "first",       "second", "block_trial"};
  const TrialsTable table = read_trials_table(path, kColumns);
  Plan plan;
  plan.seed = seed;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    PlanRow row;
    row.participant = table.value(r, "participant");
    row.block = table.value(r, "block");
    row.question = table.value(r, "question");
    row.first = table.value(r, "first");
    row.second = table.value(r, "second");
    try {
      row.trial = std::stoi(table.value(r, "trial"));
      row.block_trial = std::stoi(table.value(r, "block_trial"));
    } catch (const std::exception&) {
      throw TrialsTableError(path.string(), table.line_numbers[r],
                             "trial and block_trial must be whole numbers");
    }
    plan.rows.push_back(std::move(row));
  }
  return plan;
}

std::string fnv1a64_hex(std::string_view text) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(hash));
  return buffer;
}

std::string PlanIdentity::text() const {
  return "campaign = " + campaign + "\nseed = " + std::to_string(seed) +
         "\nplan_fnv1a64 = " + plan_hash + "\ncampaign_fnv1a64 = " + campaign_hash +
         "\ncampaign_folder = " + campaign_folder.string() + "\n";
}

void write_campaign_folder(const std::filesystem::path& dir, const Campaign& campaign,
                           const Plan& plan, bool overwrite) {
  check_output_folder(dir, {campaign.source}, overwrite);
  std::filesystem::create_directories(dir);
  const std::string csv = plan_csv(plan);
  PlanIdentity identity;
  identity.campaign = campaign.name;
  identity.seed = plan.seed;
  identity.plan_hash = fnv1a64_hex(csv);
  identity.campaign_hash = fnv1a64_hex(campaign.text);
  identity.campaign_folder =
      std::filesystem::absolute(std::filesystem::path(campaign.source)).parent_path();
  const auto write = [&](const char* name, const std::string& text) {
    write_file_atomically(dir / name, [&](std::ostream& out) { out << text; });
  };
  write("campaign.toml", campaign.text);
  write("plan.csv", csv);
  write("plan-id.txt", identity.text());
}

PlanIdentity read_plan_identity(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "plan-id.txt";
  std::ifstream in(path);
  if (!in)
    throw CampaignError(path.string() + ": cannot open for reading (is " + dir.string() +
                        " a campaign folder made by `doorbench campaign plan`?)");
  PlanIdentity identity;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos)
      throw CampaignError(path.string() + ":" + std::to_string(number) + ": expected KEY = VALUE");
    const std::string key = line.substr(0, eq), value = line.substr(eq + 3);
    if (key == "campaign")
      identity.campaign = value;
    else if (key == "seed")
      identity.seed = std::stoull(value);
    else if (key == "plan_fnv1a64")
      identity.plan_hash = value;
    else if (key == "campaign_fnv1a64")
      identity.campaign_hash = value;
    else if (key == "campaign_folder")
      identity.campaign_folder = value;
    else
      throw CampaignError(path.string() + ":" + std::to_string(number) + ": " + key +
                          ": unknown key");
  }
  std::ifstream plan_in(dir / "plan.csv", std::ios::binary);
  const std::string csv((std::istreambuf_iterator<char>(plan_in)),
                        std::istreambuf_iterator<char>());
  if (fnv1a64_hex(csv) != identity.plan_hash) {
    throw CampaignError((dir / "plan.csv").string() +
                        ": does not match plan-id.txt (plan_fnv1a64 " + identity.plan_hash +
                        ", the file's " + fnv1a64_hex(csv) +
                        "): the plan was changed after it was made");
  }
  return identity;
}

CampaignFolder open_campaign_folder(const std::filesystem::path& dir) {
  CampaignFolder folder;
  folder.dir = dir;
  folder.identity = read_plan_identity(dir);
  std::ifstream in(dir / "campaign.toml", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  folder.campaign =
      parse_campaign(text, (dir / "campaign.toml").string(), folder.identity.campaign_folder);
  folder.plan = read_plan_csv(dir / "plan.csv", folder.identity.seed);
  return folder;
}

std::string plan_reference_variant(const std::filesystem::path& folder, const TrialsTable& table) {
  if (!std::filesystem::is_directory(folder) || !std::filesystem::exists(folder / "campaign.toml"))
    return "";
  std::string first;
  try {
    const CampaignFolder opened = open_campaign_folder(folder);
    if (opened.campaign.variants.empty()) return "";
    first = opened.campaign.variants.front().name;
  } catch (const std::exception&) {
    return "";  // not a readable campaign folder: its table alone decides
  }
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::optional<Question> question = Question::parse(table.value(r, "question"));
    if (!question || !question->is_preference()) continue;
    if (table.value(r, "first") == first || table.value(r, "second") == first) return first;
  }
  return "";
}

}  // namespace doorbench::study
