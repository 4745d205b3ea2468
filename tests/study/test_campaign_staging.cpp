// Sight and sound as variables (docs/campaign.md, "Scenes and sound sets"): a variant names a
// scene and a sound set beside its door; the campaign file checks that the files are there
// (errors word for word); trials.csv records what each presentation showed and played; a
// trials.csv begun before those columns is resumed, merged and analysed as it is.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fixtures/temp_dir.h"
#include "study/campaign_file.h"
#include "study/campaign_plan.h"
#include "study/campaign_run.h"
#include "study/trials_table.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/trials_rows.h"

using doorbench::testing::TempDir;
namespace study = doorbench::study;
namespace fs = std::filesystem;

namespace {

// Two variants staged in scenes and sound sets, one as it was (the string form), and a pair
// and a jnd block (whose stimuli are no variant: the station's own scene).
std::string staged_campaign(
    const std::string& variants_extra = "",
    const std::string& blocks =
        "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\n"
        "[[blocks]]\nname = \"jnd\"\ntype = \"jnd\"\nparameter = \"J\"\nlevels = [1.2]\n") {
  return "[campaign]\nname = \"staged\"\nseed = 5\nsimulated_presentation_s = 0.2\n"
         "[variants]\n"
         "oak = { door = \"base\", scene = \"scenes/oak.toml\" }\n"
         "steel = { door = \"heaviness*1.2\", scene = \"scenes/steel.toml\", sounds = "
         "\"sounds/steel.toml\" }\n"
         "plain = \"latch_effort*0.7\"\n" +
         variants_extra + "[participants]\ncount = 2\n" + blocks;
}

// The files the staged campaign names (their contents are the station's to read).
void write_staging_files(const TempDir& dir) {
  dir.write("scenes/oak.toml", "[colours]\ndoor_rgb = [0.6, 0.4, 0.2]\n");
  dir.write("scenes/steel.toml", "[colours]\ndoor_rgb = [0.8, 0.8, 0.85]\n");
  dir.write("sounds/steel.toml", "[sound]\nlatch_gain = 2.0\n");
}

study::Campaign staged(const TempDir& dir, const std::string& text) {
  return study::parse_campaign(text, (dir / "c.toml").string(), dir.path);
}

// The stimuli's names of presentation `position` (1, 2) per row.
std::vector<std::string> presented_names(const study::TrialsTable& table, int position) {
  std::vector<std::string> names;
  for (std::size_t r = 0; r < table.rows.size(); ++r)
    names.push_back(table.value(r, position == 1 ? "first" : "second"));
  return names;
}

}  // namespace

TEST_CASE("campaign variants: a scene and a sound set beside the door, relative to the file",
          "[study][campaign]") {
  TempDir dir("campaign_staging_parse");
  write_staging_files(dir);
  const study::Campaign campaign = staged(dir, staged_campaign());
  REQUIRE(campaign.variants.size() == 3);
  const study::Variant& oak = campaign.variants[0];
  CHECK(oak.name == "oak");
  CHECK(oak.kind == study::Variant::Kind::kBase);
  CHECK(oak.scene == "scenes/oak.toml");
  CHECK(oak.scene_file == dir.path / "scenes/oak.toml");
  CHECK(oak.sounds.empty());
  CHECK(oak.sounds_file.empty());
  const study::Variant& steel = campaign.variants[1];
  CHECK(steel.kind == study::Variant::Kind::kSteps);
  CHECK(steel.spec == "heaviness*1.2");
  CHECK(steel.sounds == "sounds/steel.toml");
  CHECK(steel.sounds_file == dir.path / "sounds/steel.toml");
  const study::Variant& plain = campaign.variants[2];
  CHECK(plain.scene.empty());
  CHECK(plain.scene_file.empty());
  // The door is the string form's.
  CHECK(study::variant_model(campaign, steel).parameter_values()[0] ==
        study::apply_steps(study::base_model(campaign), study::parse_steps("heaviness*1.2"))
            .parameter_values()[0]);

  // A plan folder keeps them: the folder's campaign.toml resolves against the campaign's
  // own folder.
  study::write_campaign_folder(dir / "folder", campaign, study::make_plan(campaign, 5), false);
  const study::CampaignFolder folder = study::open_campaign_folder(dir / "folder");
  CHECK(folder.campaign.find_variant("steel")->scene_file == dir.path / "scenes/steel.toml");
}

TEST_CASE(
    "campaign variants: a missing scene or sound set names the file, the variant and the path",
    "[study][campaign]") {
  TempDir dir("campaign_staging_errors");
  write_staging_files(dir);
  const std::string file = (dir / "c.toml").string();
  fs::remove(dir / "scenes/steel.toml");
  CHECK_THROWS_WITH(staged(dir, staged_campaign()),
                    file +
                        ":7: variants.steel.scene: no such file 'scenes/steel.toml' (looked for " +
                        (dir.path / "scenes/steel.toml").string() + ")");
  write_staging_files(dir);
  fs::remove(dir / "sounds/steel.toml");
  CHECK_THROWS_WITH(staged(dir, staged_campaign()),
                    file +
                        ":7: variants.steel.sounds: no such file 'sounds/steel.toml' (looked for " +
                        (dir.path / "sounds/steel.toml").string() + ")");
  write_staging_files(dir);
  // The same check when the plan's folder is opened (the files moved after planning).
  const study::Campaign campaign = staged(dir, staged_campaign());
  study::write_campaign_folder(dir / "folder", campaign, study::make_plan(campaign, 5), false);
  fs::remove(dir / "scenes/oak.toml");
  CHECK_THROWS_WITH(study::open_campaign_folder(dir / "folder"),
                    (dir / "folder" / "campaign.toml").string() +
                        ":6: variants.oak.scene: no such file 'scenes/oak.toml' (looked for " +
                        (dir.path / "scenes/oak.toml").string() + ")");
  write_staging_files(dir);

  CHECK_THROWS_WITH(staged(dir, staged_campaign("odd = { door = \"base\", colour = \"red\" }\n")),
                    file + ":9: variants.odd.colour: unknown key; valid keys: door, scene, sounds");
  CHECK_THROWS_WITH(staged(dir, staged_campaign("bare = { scene = \"scenes/oak.toml\" }\n")),
                    file +
                        ":9: variants.bare: missing door: base, real, file:PATH or steps such "
                        "as \"J*1.2\"");
  CHECK_THROWS_WITH(staged(dir, staged_campaign("empty = { door = \"base\", scene = \"\" }\n")),
                    file + ":9: variants.empty.scene: must name a file");
  CHECK_THROWS_WITH(staged(dir, staged_campaign("number = 3\n")),
                    file +
                        ":9: variants.number: must be a string: base, real, file:PATH or "
                        "steps such as \"J*1.2\", or a table { door = ..., scene = ..., "
                        "sounds = ... }");
  dir.write("rig.toml", "");
  std::string text =
      staged_campaign("bench = { door = \"real\", sounds = \"sounds/steel.toml\" }\n");
  text.replace(text.find("[campaign]\n"), 11, "[campaign]\nreal_rig = \"rig.toml\"\n");
  CHECK_THROWS_WITH(staged(dir, text),
                    file +
                        ":10: variants.bench.sounds: the real door is seen and heard as it is "
                        "on the bench; a scene and a sound set are for a model");
}

TEST_CASE("trials.csv: each presentation's scene and sounds, none without a screen",
          "[study][campaign]") {
  TempDir dir("campaign_staging_run");
  write_staging_files(dir);
  const study::Campaign campaign = staged(dir, staged_campaign());
  study::write_campaign_folder(dir / "folder", campaign, study::make_plan(campaign, 5), false);
  const study::CampaignFolder folder = study::open_campaign_folder(dir / "folder");
  // A presenter without a screen: shows nothing (leaves Presented as it is).
  std::vector<std::string> staged_scenes;
  const study::Presenter presenter = [&](const study::PresentationCall& call) {
    staged_scenes.push_back(call.stimulus->staging.scene_file.string());
  };
  study::SimulatedRespondent respondent(3, study::base_model(folder.campaign));
  std::ostringstream prompts;
  REQUIRE(
      study::run_participant(folder, {"P01", false}, respondent, presenter, prompts).finished());
  const study::TrialsTable table = study::read_trials_table(dir / "folder" / "trials.csv");
  CHECK(table.column_names == study::trials_columns());
  for (const char* column : {"first_scene", "first_sounds", "second_scene", "second_sounds"}) {
    for (std::size_t r = 0; r < table.rows.size(); ++r) CHECK(table.value(r, column) == "none");
  }
  // The presenter was handed each variant's scene file, in the order presented.
  std::vector<std::string> expected;
  const std::vector<std::string> first = presented_names(table, 1);
  const std::vector<std::string> second = presented_names(table, 2);
  for (std::size_t r = 0; r < first.size(); ++r) {
    for (const std::string& name : {first[r], second[r]}) {
      const study::Variant* variant = folder.campaign.find_variant(name);
      expected.push_back(variant ? variant->scene_file.string() : "");
    }
  }
  CHECK(staged_scenes == expected);
  CHECK(std::count(expected.begin(), expected.end(), (dir.path / "scenes/oak.toml").string()) ==
        4);  // oak in the pair block: two pairs, each both ways
}

TEST_CASE("trials.csv begun before the staging columns: resumed, merged and analysed as it is",
          "[study][campaign]") {
  TempDir dir("campaign_staging_old");
  write_staging_files(dir);
  // Enough pairs for campaign analyze's preference scale.
  const study::Campaign campaign = staged(
      dir, staged_campaign("", "[[blocks]]\nname = \"pair\"\ntype = \"pair\"\nrepetitions = 4\n"));
  const study::Plan plan = study::make_plan(campaign, 5);
  for (const char* name : {"whole", "old", "new"})
    study::write_campaign_folder(dir / name, campaign, plan, false);
  const study::Presenter presenter = [](const study::PresentationCall&) {};
  std::ostringstream prompts;
  auto run = [&](const char* name, const std::string& participant) {
    const study::CampaignFolder folder = study::open_campaign_folder(dir / name);
    study::SimulatedRespondent respondent(3, study::base_model(folder.campaign));
    return study::run_participant(folder, {participant, false}, respondent, presenter, prompts);
  };
  REQUIRE(run("whole", "P01").finished());

  // The first three rows of P01, as a doorbench without the staging columns wrote them.
  const std::vector<std::string> old_columns(study::trials_columns().begin(),
                                             study::trials_columns().end() - 4);
  const std::vector<std::vector<std::string>> whole =
      doorbench::testing::trials_rows_without(dir / "whole" / "trials.csv", {});
  std::string old_text = study::csv_row(old_columns);
  for (std::size_t r = 0; r < 3; ++r)
    old_text += study::csv_row(std::vector<std::string>(whole[r].begin(), whole[r].end() - 4));
  dir.write("old/trials.csv", old_text);

  prompts.str("");
  const study::RunResult resumed = run("old", "P01");
  CHECK(resumed.answered_before == 3);
  CHECK(resumed.finished());
  CHECK(prompts.str().find((dir / "old" / "trials.csv").string() +
                           " was begun by an earlier doorbench without the columns first_scene, "
                           "first_sounds, second_scene, second_sounds: its rows are written "
                           "without them\n") != std::string::npos);
  // Every row in the file's own twelve columns; the same rows as the uninterrupted run's.
  const study::TrialsTable old_table = study::read_trials_table(dir / "old" / "trials.csv");
  CHECK(old_table.column_names == old_columns);
  std::vector<std::vector<std::string>> expected;
  for (const std::vector<std::string>& row :
       doorbench::testing::trials_rows_without_time_and_staging(dir / "whole" / "trials.csv"))
    expected.push_back(row);
  CHECK(doorbench::testing::trials_rows_without_time(dir / "old" / "trials.csv") == expected);

  // Merged with a folder of the new columns: the old rows hold "" there (not recorded).
  REQUIRE(run("new", "P02").finished());
  study::merge_campaign_folders({dir / "old", dir / "new"}, dir / "merged");
  const study::TrialsTable merged = study::read_trials_table(dir / "merged" / "trials.csv");
  CHECK(merged.column_names == study::trials_columns());
  REQUIRE(merged.rows.size() == 2 * old_table.rows.size());
  for (std::size_t r = 0; r < merged.rows.size(); ++r) {
    const bool old = merged.value(r, "participant") == "P01";
    CHECK(merged.value(r, "first_scene") == (old ? "" : "none"));
    CHECK(merged.value(r, "second_sounds") == (old ? "" : "none"));
  }

  // campaign analyze reads the old file as it is, and the merged one.
  for (const fs::path& trials : {dir / "old" / "trials.csv", dir / "merged" / "trials.csv"}) {
    const doorbench::testing::DoorbenchRun analysed = doorbench::testing::run_doorbench_shell(
        "campaign analyze '" + trials.string() + "' --out '" +
            (dir / ("analysis-" + trials.parent_path().filename().string())).string() +
            "' --no-pdf -q",
        dir);
    INFO(analysed.err);
    CHECK(analysed.status == 0);
  }
}
