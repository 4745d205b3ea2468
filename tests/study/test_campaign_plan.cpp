// The campaign file, the plan and its counterbalancing (docs/campaign.md).
#include <algorithm>
#include <catch2/catch.hpp>
#include <map>
#include <set>
#include <tuple>

#include "fixtures/temp_dir.h"
#include "study/campaign_file.h"
#include "study/campaign_plan.h"
#include "study/latin_square.h"
#include "tests/support/files.h"

using namespace doorbench::study;
using doorbench::testing::TempDir;

namespace {

// A small campaign: 4 variants, 5 blocks; `extra` goes at the end.
std::string campaign_text(const std::string& participants = "count = 20",
                          const std::string& extra = "") {
  return "[campaign]\nname = \"t\"\nseed = 7\n"
         "[variants]\nreference = \"base\"\nheavier = \"heaviness*1.2\"\n"
         "easier_unlatch = \"latch_effort*0.7\"\nlighter = \"J*0.85,smoothness*0.8\"\n"
         "[participants]\n" +
         participants +
         "\n"
         "[[blocks]]\nname = \"tune\"\ntype = \"tune\"\n"
         "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\nquestion = \"preference-2ac\"\n"
         "[[blocks]]\nname = \"rating\"\ntype = \"rating\"\nattributes = [\"heavy-light\"]\nscale "
         "= 5\n"
         "[[blocks]]\nname = \"jnd-J\"\ntype = \"jnd\"\nparameter = \"J\"\nlevels = [1.1, "
         "1.3]\nrepetitions = 2\n"
         "[[blocks]]\nname = \"jnd-latch\"\ntype = \"jnd\"\nparameter = \"latch_effort\"\nmethod = "
         "\"staircase\"\ntrials = 6\n" +
         extra;
}

Campaign parsed(const std::string& text) {
  return parse_campaign(text, "c.toml", ".");
}

// A campaign of `variants` variants (v1 = the base, v2... steps of J) and `participants`
// participants with a pair block and a rating block over `pairs`; `rating` holds the rating
// block's extra keys.
std::string paired_campaign(int variants, int participants, const std::string& pairs = "\"all\"",
                            const std::string& rating = "attributes = [\"heavy-light\"]\n") {
  std::string text = "[campaign]\nname = \"t\"\nseed = 11\n[variants]\nv1 = \"base\"\n";
  for (int v = 2; v <= variants; ++v) {
    text.append("v")
        .append(std::to_string(v))
        .append(" = \"J*1.")
        .append(std::to_string(v))
        .append("\"\n");
  }
  return text.append("[participants]\ncount = ")
      .append(std::to_string(participants))
      .append("\n")
      .append("[[blocks]]\nname = \"pair\"\ntype = \"pair\"\npairs = ")
      .append(pairs)
      .append("\n")
      .append("[[blocks]]\nname = \"rating\"\ntype = \"rating\"\npairs = ")
      .append(pairs)
      .append("\n")
      .append(rating);
}

// A plan.csv written by `campaign plan` into a folder and read back.
Plan plan_from_folder(const std::string& text, const std::string& name) {
  TempDir dir(name);
  const Campaign campaign = read_campaign(dir.write("c.toml", text));
  write_campaign_folder(dir / "out", campaign, make_plan(campaign, campaign.seed), false);
  return open_campaign_folder(dir / "out").plan;
}

// Counts over one block of a plan: which pair (unordered, "a|b") is at each block_trial,
// which variant at each (block_trial, place 1 or 2), and which pair directly follows which.
struct BlockCounts {
  std::map<std::pair<std::string, int>, int> pair_at;
  std::map<std::tuple<std::string, int, int>, int> variant_at;
  std::map<std::pair<std::string, std::string>, int> pair_after_pair;
  std::set<std::string> pairs, variants;
  std::set<int> positions;
};

BlockCounts count_block(const Plan& plan, const std::string& block) {
  BlockCounts counts;
  std::string previous, previous_participant;
  for (const PlanRow& row : plan.rows) {
    if (row.block != block) continue;
    const std::string pair =
        std::min(row.first, row.second) + "|" + std::max(row.first, row.second);
    counts.pairs.insert(pair);
    counts.variants.insert(row.first);
    counts.variants.insert(row.second);
    counts.positions.insert(row.block_trial);
    ++counts.pair_at[{pair, row.block_trial}];
    ++counts.variant_at[{row.first, row.block_trial, 1}];
    ++counts.variant_at[{row.second, row.block_trial, 2}];
    if (row.participant == previous_participant) ++counts.pair_after_pair[{previous, pair}];
    previous = pair;
    previous_participant = row.participant;
  }
  return counts;
}

// The spread (largest − smallest count) over all cells of `keys` × `positions`.
template <typename Key, typename Map, typename MakeKey>
int spread(const std::set<Key>& keys, const std::set<int>& positions, const Map& map,
           MakeKey make_key) {
  int lo = 1 << 30, hi = 0;
  for (const Key& key : keys) {
    for (int position : positions) {
      const auto it = map.find(make_key(key, position));
      const int n = it == map.end() ? 0 : it->second;
      lo = std::min(lo, n);
      hi = std::max(hi, n);
    }
  }
  return hi - lo;
}

}  // namespace

TEST_CASE("Williams designs: each condition in each position equally often, carry-over balanced",
          "[study][campaign]") {
  for (int n = 1; n <= 9; ++n) {
    const auto rows = williams_design(n);
    const int expected_rows = (n % 2 == 0 || n == 1) ? n : 2 * n;
    REQUIRE(static_cast<int>(rows.size()) == expected_rows);
    const int per_cell = expected_rows / n;
    std::map<std::pair<int, int>, int> position_count, carry_over;
    for (const auto& row : rows) {
      REQUIRE(static_cast<int>(row.size()) == n);
      REQUIRE(std::set<int>(row.begin(), row.end()).size() == static_cast<std::size_t>(n));
      for (int p = 0; p < n; ++p) ++position_count[{row[p], p}];
      for (int p = 0; p + 1 < n; ++p) ++carry_over[{row[p], row[p + 1]}];
    }
    for (int c = 0; c < n; ++c) {
      for (int p = 0; p < n; ++p) CHECK(position_count[{c, p}] == per_cell);
    }
    // Every ordered pair a -> b (a != b) directly after each other equally often.
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) {
        if (a != b) CHECK(carry_over[{a, b}] == per_cell);
      }
    }
  }
}

TEST_CASE(
    "A plan's block order is balanced across participants and the same seed gives the same plan",
    "[study][campaign]") {
  const Campaign campaign = parsed(campaign_text());
  const Plan plan = make_plan(campaign, 7);
  // 5 blocks: the design has 10 rows, 20 participants take each twice.
  std::map<std::pair<std::string, int>, int> position_count;
  std::map<std::pair<std::string, std::string>, int> carry_over;
  for (const std::string& id : campaign.participants) {
    std::vector<std::string> order;
    for (const PlanRow& row : plan.of(id)) {
      if (order.empty() || order.back() != row.block) order.push_back(row.block);
    }
    REQUIRE(order.size() == 5);
    for (int p = 0; p < 5; ++p) ++position_count[{order[p], p}];
    for (int p = 0; p + 1 < 5; ++p) ++carry_over[{order[p], order[p + 1]}];
  }
  for (const Block& block : campaign.blocks) {
    for (int p = 0; p < 5; ++p) CHECK(position_count[{block.name, p}] == 4);
    for (const Block& next : campaign.blocks) {
      if (next.name != block.name) CHECK(carry_over[{block.name, next.name}] == 4);
    }
  }
  // Per participant: 1 tune + 12 pair + 6 rating + 4 constant + 6 staircase trials.
  CHECK(plan.of("P01").size() == 29);
  // Each pair in both orders; the jnd comparison first in half of its trials.
  std::map<std::pair<std::string, std::string>, int> ordered;
  int comparison_first = 0;
  for (const PlanRow& row : plan.of("P03")) {
    if (row.block == "pair") ++ordered[{row.first, row.second}];
    if (row.block == "jnd-latch") comparison_first += row.first == "latch_effort*?";
    if (row.block == "jnd-J") CHECK((row.first == "J*1" || row.second == "J*1"));
  }
  CHECK(ordered.size() == 12);
  for (const auto& [pair, count] : ordered) CHECK(count == 1);
  CHECK(comparison_first == 3);

  CHECK(plan_csv(make_plan(campaign, 7)) == plan_csv(plan));
  CHECK(plan_csv(make_plan(campaign, 8)) != plan_csv(plan));
  // The same on any machine: pinned (mt19937_64 and our own draws; a change here changes
  // every plan made before).
  CHECK(fnv1a64_hex(plan_csv(plan)) ==
        "1e2d209105b12fa8");  // since pair and rating blocks follow Williams designs
}

TEST_CASE(
    "Pair and rating blocks: each pair and each variant in each position equally often, carry-over "
    "balanced",
    "[study][campaign]") {
  // 3 variants: 3 pairs (odd: the square and its mirror, 6 rows); 4: 6 pairs (6 rows);
  // 5: 10 pairs (10 rows). A full set is 2 x rows participants; take two full sets.
  for (const auto& [variants, rows] : {std::pair{3, 6}, std::pair{4, 6}, std::pair{5, 10}}) {
    CAPTURE(variants);
    const std::string text = paired_campaign(variants, 4 * rows);
    CHECK(balanced_participant_count(parsed(text)).participants == 2 * rows);
    CHECK(balance_note(parsed(text)) == "");
    const Plan plan = plan_from_folder(text, "balanced");
    const int pairs = variants * (variants - 1) / 2;
    for (const std::string block : {"pair", "rating"}) {
      CAPTURE(block);
      const BlockCounts counts = count_block(plan, block);
      REQUIRE(static_cast<int>(counts.pairs.size()) == pairs);
      REQUIRE(static_cast<int>(counts.positions.size()) ==
              (block == std::string("pair") ? 2 * pairs : pairs));
      const int participants = 4 * rows;
      // Each pair at each trial position: participants / pairs times.
      for (const std::string& pair : counts.pairs) {
        for (int position : counts.positions)
          CHECK(counts.pair_at.at({pair, position}) * pairs == participants);
      }
      // Each variant in each place of each trial: it is in (variants − 1) of the pairs and
      // in each place of them half of the time.
      for (const std::string& variant : counts.variants) {
        for (int position : counts.positions) {
          for (int place : {1, 2}) {
            CHECK(2 * pairs * counts.variant_at.at({variant, position, place}) ==
                  participants * (variants - 1));
          }
        }
      }
      // First-order carry-over: each pair directly after each other pair equally often;
      // in a pair block the turn (forwards, then backwards) repeats one pair, each equally often.
      std::set<int> seen;
      for (const std::string& a : counts.pairs) {
        for (const std::string& b : counts.pairs) {
          const auto it = counts.pair_after_pair.find({a, b});
          const int n = it == counts.pair_after_pair.end() ? 0 : it->second;
          if (a != b) seen.insert(n);
          if (a == b) CHECK(n * pairs == (block == std::string("pair") ? participants : 0));
        }
      }
      CHECK(seen.size() == 1);
      CHECK(*seen.begin() > 0);
    }
    // Within one participant's pair block each pair is played both ways once.
    std::map<std::pair<std::string, std::string>, int> ordered;
    for (const PlanRow& row : plan.of("P03")) {
      if (row.block == "pair") ++ordered[{row.first, row.second}];
    }
    CHECK(static_cast<int>(ordered.size()) == 2 * pairs);
  }
}

TEST_CASE("Named pairs, repetitions and attributes keep the balance over a full set",
          "[study][campaign]") {
  // 5 named pairs (odd: 10 rows, 20 participants a full set), 2 repetitions; the rating
  // block's 2 attributes in cyclic order.
  const std::string pairs =
      "[[\"v1\", \"v2\"], [\"v1\", \"v3\"], [\"v2\", \"v3\"], [\"v3\", \"v4\"], [\"v1\", \"v4\"]]";
  std::string text = paired_campaign(
      4, 20, pairs, "attributes = [\"heavy-light\", \"pleasant\"]\nrepetitions = 2\n");
  text.insert(text.find("[[blocks]]\nname = \"rating\""), "repetitions = 2\n");
  REQUIRE(balanced_participant_count(parsed(text)).participants == 20);
  const Plan plan = plan_from_folder(text, "named");
  for (const std::string block : {"pair", "rating"}) {
    CAPTURE(block);
    const BlockCounts counts = count_block(plan, block);
    REQUIRE(counts.positions.size() ==
            20);  // 5 pairs x 2 orders (pair) or x 2 attributes (rating), x 2
    for (const std::string& pair : counts.pairs) {
      for (int position : counts.positions) CHECK(counts.pair_at.at({pair, position}) == 4);
    }
    std::set<int> seen;
    for (const auto& [key, n] : counts.pair_after_pair) {
      if (key.first != key.second) seen.insert(n);
    }
    CHECK(seen.size() == 1);
    CHECK(counts.pair_after_pair.size() ==
          25);  // every ordered pair of pairs, and each after itself
  }
  // Each attribute first for half of the participants, each rated on every pair twice.
  int heavy_first = 0;
  for (int p = 1; p <= 20; ++p) {
    const std::string id = std::string(p < 10 ? "P0" : "P").append(std::to_string(p));
    std::map<std::string, int> per_question;
    bool first_seen = false;
    for (const PlanRow& row : plan.of(id)) {
      if (row.block != "rating") continue;
      if (!first_seen) heavy_first += row.question == "rating:heavy-light:7";
      first_seen = true;
      ++per_question[row.question];
    }
    CHECK(per_question["rating:heavy-light:7"] == 10);
    CHECK(per_question["rating:pleasant:7"] == 10);
  }
  CHECK(heavy_first == 10);
}

TEST_CASE(
    "A participant count that is not a multiple of the design is noted and stays nearly balanced",
    "[study][campaign]") {
  // 4 variants: 6 pairs, 6 rows, full set 12 (2 blocks: block order 2). 15 participants:
  // rows 0..2 are taken three times, rows 3..5 twice, so a pair's count at a position is 3 or 2.
  const std::string text = paired_campaign(4, 15);
  CHECK(balance_note(parsed(text)) ==
        "note: 15 participants; the counterbalancing is exact for a multiple of 12 (block order 2, "
        "block 'pair' 12, "
        "block 'rating' 12); participant i takes row i mod rows of each design (docs/campaign.md, "
        "Counterbalancing)");
  const Plan plan = plan_from_folder(text, "partial");
  for (const std::string block : {"pair", "rating"}) {
    const BlockCounts counts = count_block(plan, block);
    CHECK(spread(counts.pairs, counts.positions, counts.pair_at,
                 [](const std::string& pair, int position) {
                   return std::pair{pair, position};
                 }) == 1);
  }
}

TEST_CASE("A plan folder keeps the campaign, the plan and its identity, read back and checked",
          "[study][campaign]") {
  TempDir dir("campaign_plan");
  const auto path = dir.write("c.toml", campaign_text("ids = [\"P01\", \"sub-02\"]"));
  const Campaign campaign = read_campaign(path);
  write_campaign_folder(dir / "out", campaign, make_plan(campaign, 3), false);
  const CampaignFolder folder = open_campaign_folder(dir / "out");
  CHECK(folder.identity.seed == 3);
  CHECK(plan_csv(folder.plan) == plan_csv(make_plan(campaign, 3)));
  CHECK(doorbench::testing::read_file(dir / "out" / "campaign.toml") == campaign.text);
  CHECK_THROWS_WITH(
      write_campaign_folder(dir / "out", campaign, make_plan(campaign, 3), false),
      (dir / "out").string() + ": exists and is not empty (give --overwrite to write into it)");
  dir.write("out/plan.csv", "participant,block,trial,question,first,second,block_trial\n");
  CHECK_THROWS_WITH(open_campaign_folder(dir / "out"),
                    Catch::Matchers::StartsWith((dir / "out" / "plan.csv").string() +
                                                ": does not match plan-id.txt"));
}

TEST_CASE("A participant id that looks like a name or an e-mail is refused", "[study][campaign]") {
  CHECK(participant_id_problem("P07") == "");
  CHECK(participant_id_problem("sub-07") == "");
  CHECK(participant_id_problem("s_12") == "");
  CHECK(participant_id_problem("anna.berg@example.org") ==
        "participant id 'anna.berg@example.org' looks like an e-mail address; use a pseudonymous "
        "id such as P07");
  CHECK(participant_id_problem("Anna Berg") ==
        "participant id 'Anna Berg' looks like a name (it holds a space); use a pseudonymous id "
        "such as P07");
  CHECK(participant_id_problem("AnnaBerg1") ==
        "participant id 'AnnaBerg1' looks like a name (a capitalised word); use a pseudonymous id "
        "such as P07");
  CHECK(participant_id_problem("anna") ==
        "participant id 'anna' has no digit (a word alone may be a name); use a pseudonymous id "
        "such as P07");
  CHECK(participant_id_problem("p.07") ==
        "participant id 'p.07' may hold only letters, digits, '-' and '_'");
  CHECK_THROWS_WITH(parsed(campaign_text("ids = [\"P01\", \"Anna Berg\"]")),
                    "c.toml:10: participants.ids: participant id 'Anna Berg' looks like a name (it "
                    "holds a space); "
                    "use a pseudonymous id such as P07");
}

TEST_CASE("A campaign file's errors name the file, the line and the field", "[study][campaign]") {
  CHECK_THROWS_WITH(
      parsed(campaign_text("count = 2",
                           "[[blocks]]\nname = \"x\"\ntype = \"pair\"\nquestion = \"best\"\n")),
      "c.toml:38: blocks[6].question: must be preference, preference-2ac or identify-real, not "
      "'best'");
  CHECK_THROWS_WITH(
      parsed(campaign_text(
          "count = 2",
          "[[blocks]]\nname = \"x\"\ntype = \"jnd\"\nparameter = \"J_d\"\nlevels = [1.1]\n")),
      Catch::Matchers::StartsWith(
          "c.toml:38: blocks[6].parameter: step J_d*1.05: 'J_d' is neither a "
          "perceptual control nor a parameter of the sensory model"));
  CHECK_THROWS_WITH(
      parsed(campaign_text("count = 2", "[[blocks]]\nname = \"pair\"\ntype = \"tune\"\n")),
      "c.toml:36: blocks[6].name: block 'pair' is named twice");
  std::string text = campaign_text("count = 2");
  text.replace(text.find("heaviness*1.2"), 13, "heaviness*x");
  CHECK_THROWS_WITH(parsed(text),
                    "c.toml:6: variants.heavier: expected steps such as \"J*1.2\" or "
                    "\"heaviness*1.2,latch_effort*0.7\", "
                    "got \"heaviness*x\"");
  text = campaign_text("count = 2");
  text.replace(text.find("heaviness*1.2"), 13, "heaviness*9");
  CHECK_THROWS_WITH(
      parsed(text),
      "c.toml:6: variants.heavier: step heaviness*9: J would be 8.55, outside its bounds 0.1..5");
  CHECK_THROWS_WITH(
      parsed(
          campaign_text("count = 2", "[[blocks]]\nname = \"y\"\ntype = \"rating\"\ncolour = 1\n")),
      Catch::Matchers::StartsWith("c.toml:38: blocks[6].colour: unknown key; valid keys: "));
  CHECK_THROWS_WITH(parsed("[campaign]\nseed = \n"), Catch::Matchers::StartsWith("c.toml:2: "));
}

TEST_CASE("Steps from the base move exactly what they name", "[study][campaign]") {
  const Campaign campaign = parsed(campaign_text("count = 2"));
  const doorbench::DoorModel base = base_model(campaign);
  const doorbench::DoorModel lighter = variant_model(campaign, *campaign.find_variant("lighter"));
  const int j = *base.find_parameter("J");
  CHECK(lighter.parameter_values()[j] == Approx(0.85 * base.parameter_values()[j]).epsilon(1e-12));
  CHECK(steps_text(parse_steps("J*1.2, latch_effort*0.7")) == "J*1.2,latch_effort*0.7");
}

TEST_CASE("A quest+ jnd block: its defaults, its errors word for word, its slots in the plan",
          "[study][campaign][quest]") {
  const std::string quest =
      "[[blocks]]\nname = \"q\"\ntype = \"jnd\"\nparameter = \"J\"\nmethod = \"quest+\"\n";
  const Campaign campaign = parsed(campaign_text("count = 2", quest));
  const Block& block = campaign.blocks.back();
  CHECK(block.method == JndMethod::kQuestPlus);
  CHECK(block.trials == 40);
  CHECK(block.min_level == 1.01);
  CHECK(block.max_level == 2.0);
  CHECK(block.quest_levels == 30);
  CHECK(block.quest_thresholds == 40);
  CHECK(block.lapse == 0.03);
  int slots = 0;
  for (const PlanRow& row : make_plan(campaign, 5).of("P01")) {
    if (row.block != "q") continue;
    ++slots;
    CHECK(row.block_trial == slots);
    CHECK(row.question == "stronger:J");
    CHECK((row.first == "J*?") != (row.second == "J*?"));
  }
  CHECK(slots == 40);
  CHECK_THROWS_WITH(parsed(campaign_text("count = 2", quest + "lapse = 0.5\n")),
                    "c.toml:40: blocks[6].lapse: must be from 0 to 0.2, got 0.5");
  CHECK_THROWS_WITH(parsed(campaign_text("count = 2", quest + "stimuli = 1\n")),
                    "c.toml:40: blocks[6].stimuli: must be from 2 to 200, got 1");
  CHECK_THROWS_WITH(
      parsed(campaign_text("count = 2", quest + "min_level = 1.5\nmax_level = 1.4\n")),
      "c.toml:41: blocks[6].max_level: must be at least 1 % above min_level");
  CHECK_THROWS_WITH(
      parsed(campaign_text("count = 2", quest + "step_factor = 1.5\n")),
      "c.toml:40: blocks[6].step_factor: is not an option of quest+ (trials, min_level, max_level, "
      "stimuli, thresholds, lapse)");
  CHECK_THROWS_WITH(
      parsed(campaign_text(
          "count = 2",
          "[[blocks]]\nname = \"q\"\ntype = \"jnd\"\nparameter = \"J\"\nmethod = \"quest\"\n")),
      "c.toml:39: blocks[6].method: must be constant, staircase or quest+, not 'quest'");
  CHECK_THROWS_WITH(parsed(campaign_text("count = 2",
                                         "[[blocks]]\nname = \"q\"\ntype = \"jnd\"\nparameter = "
                                         "\"J\"\nmethod = \"staircase\"\nlapse = 0.02\n")),
                    "c.toml:40: blocks[6].lapse: is an option of method = \"quest+\" only");
}
