// The ranked variants' parameter files (study/statistics/variant_files.h): a file for each
// variant the trials table renders one way, a note naming the variant and the reason for
// each one without.
#include <catch2/catch.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "study/statistics/variant_files.h"
#include "study/trials_table.h"

using doorbench::study::door_from_rendered;
using doorbench::study::variant_file_name;
using doorbench::study::variant_parameter_files;
using doorbench::study::write_variant_files;

namespace {

// The reference sensory door rendered as `campaign run` writes it, with J set to `j`.
std::string sensory_rendered(double j) {
  const doorbench::DoorModel door = doorbench::reference_model(doorbench::ModelKind::kSensory);
  std::string text;
  for (int i = 0; i < door.parameter_count(); ++i) {
    const double value = door.parameter_name(i) == "J" ? j : door.parameter_values()[i];
    text += (i ? " " : "") + door.parameter_name(i) + "=" + std::to_string(value);
  }
  return text;
}

nlohmann::json scale(std::initializer_list<const char*> variants) {
  nlohmann::json analysis = {{"preference_scale", nlohmann::json::array()},
                             {"preference_fit", {{"notes", nlohmann::json::array()}}}};
  for (const char* v : variants) analysis["preference_scale"].push_back({{"variant", v}});
  return analysis;
}

}  // namespace

TEST_CASE("variant files: one per variant rendered one way, a note for each other",
          "[study][campaign]") {
  const std::string a = sensory_rendered(1.0), b = sensory_rendered(1.25);
  const std::string text =
      "participant,block,trial,question,first,second,answer,first_parameters,second_parameters\n"
      "P1,pair,1,preference,A,B,1,\"" +
      a + "\",\"" + b +
      "\"\n"
      "P1,pair,2,preference,C,A,1,\"" +
      sensory_rendered(0.8) + "\",\"" + a +
      "\"\n"
      "P2,pair,3,preference,C,D/E,2,\"" +
      sensory_rendered(0.9) +
      "\",\"J=1 x=2\"\n"
      "P2,pair,4,preference,A,F,2,\"" +
      a + "\",\n";
  const auto table = doorbench::study::parse_trials_table(text, "trials.csv");
  nlohmann::json analysis = scale({"A", "B", "C", "D/E", "F"});
  const auto files = variant_parameter_files(table, analysis);
  REQUIRE(files.files.size() == 2);
  CHECK(files.files[0].variant == "A");
  CHECK(files.files[0].file == "variants/A.json");
  CHECK(files.files[1].variant == "B");
  const doorbench::ParameterFile parsed =
      doorbench::parse_parameter_file(files.files[1].text, "B.json");
  REQUIRE(parsed.sensory);
  const doorbench::DoorModel reference = doorbench::reference_model(doorbench::ModelKind::kSensory);
  CHECK(parsed.sensory->values[static_cast<std::size_t>(*reference.find_parameter("J"))] == 1.25);
  CHECK(analysis["preference_scale"][0]["file"] == "variants/A.json");
  CHECK(analysis["preference_scale"][1]["file"] == "variants/B.json");
  CHECK_FALSE(analysis["preference_scale"][2].contains("file"));
  CHECK(files.notes == std::vector<std::string>{
                           "variant C has no parameter file: the trials table gives it 2 "
                           "different sets of parameters",
                           "variant D/E has no parameter file: its parameters in the trials "
                           "table are not one door model's",
                           "variant F has no parameter file: no row of the trials table gives "
                           "its parameters"});
  CHECK(analysis["preference_fit"]["notes"].size() == 3);
  CHECK(variant_file_name("D/E x") == "variants/D_E_x.json");
  CHECK_FALSE(door_from_rendered("J=1 k=nope"));
  CHECK_FALSE(door_from_rendered(""));
  CHECK(door_from_rendered(a));
}

TEST_CASE("variant files: a table written by hand gives none, said once", "[study][campaign]") {
  const auto table = doorbench::study::parse_trials_table(
      "participant,block,trial,question,first,second,answer\nP1,pair,1,preference,A,B,1\n",
      "trials.csv");
  nlohmann::json analysis = scale({"A", "B"});
  const auto files = variant_parameter_files(table, analysis);
  CHECK(files.files.empty());
  CHECK(files.notes == std::vector<std::string>{"no variant parameter files: the trials table "
                                                "has no first_parameters or second_parameters "
                                                "column"});
  nlohmann::json none = {{"input", {}}};
  CHECK(variant_parameter_files(table, none).notes.empty());
}

TEST_CASE("variant files: is_variant_file takes NAME.json only", "[study][campaign]") {
  CHECK(doorbench::study::is_variant_file("heavier.json"));
  CHECK(doorbench::study::is_variant_file(
      std::filesystem::path(variant_file_name("D/E x")).filename().string()));
  CHECK_FALSE(doorbench::study::is_variant_file(".json"));
  CHECK_FALSE(doorbench::study::is_variant_file("heavier.json.bak"));
  CHECK_FALSE(doorbench::study::is_variant_file("notes.txt"));
}

TEST_CASE("variant files: writing them removes an earlier analysis's, not the user's files",
          "[study][campaign][outputs]") {
  const doorbench::testing::TempDir dir("variant_files");
  dir.write("variants/gone.json", "an earlier analysis's variant\n");
  dir.write("variants/notes.txt", "the user's\n");
  dir.write("variants/A.json", "the earlier A\n");
  doorbench::study::VariantFiles variants;
  variants.files.push_back({"A", variant_file_name("A"), "the new A\n"});
  write_variant_files(dir.path, variants);
  CHECK_FALSE(std::filesystem::exists(dir / "variants/gone.json"));
  CHECK(std::filesystem::exists(dir / "variants/notes.txt"));
  CHECK(doorbench::read_text_file(dir / "variants/A.json") == "the new A\n");
  // No files: the earlier ones go, and no variants folder is made where there was none.
  write_variant_files(dir.path, {});
  CHECK_FALSE(std::filesystem::exists(dir / "variants/A.json"));
  CHECK(std::filesystem::exists(dir / "variants/notes.txt"));
  const doorbench::testing::TempDir empty("variant_files_none");
  write_variant_files(empty.path, {});
  CHECK_FALSE(std::filesystem::exists(empty / "variants"));
}
