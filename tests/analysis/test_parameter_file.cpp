// Parameter and effects files (the layout of reference-door.json): the reference door
// parses to the spec's values, and every malformed file is rejected with a message that
// names the file and the key.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinRel;
using doorbench::ModelKind;
using doorbench::ParameterFileError;
using doorbench::parse_parameter_file;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

json reference_json() {
  return json::parse(doorbench::reference_door_json());
}

// Parses `root` as the file "door.json".
void parse(const json& root) {
  parse_parameter_file(root.dump(2), "door.json");
}

using doorbench::testing::TempDir;

}  // namespace

TEST_CASE("Parameter file: the reference door parses to the spec's values", "[parameter_file]") {
  const doorbench::ParameterFile file =
      parse_parameter_file(doorbench::reference_door_json(), "reference door");
  CHECK(file.geometry.handle_radius_m == 0.58);
  CHECK(file.geometry.theta_max_rad == 1.5708);
  REQUIRE(file.sensory.has_value());
  REQUIRE(file.physical.has_value());
  const std::vector<double> sensory = {0.95,   40.0,    1054.0, 767.0,  0.00698, 0.02793,
                                       0.0384, 0.06109, 3.0,    2.6,    1.3,     25.0,
                                       0.6109, 3000.0,  10.0,   5000.0, 20.0};
  CHECK(file.sensory->values == sensory);
  REQUIRE(file.sensory->bounds.size() == 17);
  // k_inf in [0, 20000], beta in [100, 20000], J in [0.1, 5].
  CHECK(file.sensory->bounds[2].lower == 0.0);
  CHECK(file.sensory->bounds[2].upper == 20000.0);
  CHECK(file.sensory->bounds[13].lower == 100.0);
  CHECK(file.sensory->bounds[13].upper == 20000.0);
  CHECK(file.sensory->bounds[0].lower == 0.1);
  CHECK(file.sensory->bounds[0].upper == 5.0);
  REQUIRE(file.physical->values.size() == 26);
  // m_d = 7.5 first, e = 0.0003 in [5e-05, 0.002], c_stop = 20 last.
  CHECK(file.physical->values[0] == 7.5);
  CHECK(file.physical->values[21] == 0.0003);
  CHECK(file.physical->bounds[21].lower == 5e-05);
  CHECK(file.physical->bounds[21].upper == 0.002);
  CHECK(file.physical->values[25] == 20.0);
  // Every reference value lies inside its bounds.
  for (const auto* section : {&*file.sensory, &*file.physical}) {
    for (std::size_t i = 0; i < section->values.size(); ++i) {
      CHECK(section->bounds[i].lower <= section->values[i]);
      CHECK(section->values[i] <= section->bounds[i].upper);
    }
  }
}

TEST_CASE("Parameter file: unknown keys are rejected by name", "[parameter_file]") {
  json root = reference_json();
  root["colour"] = "white";
  CHECK_THROWS_AS(parse(root), ParameterFileError);
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: colour: unknown key"));

  root = reference_json();
  root["sensory"]["k_infinity"] = root["sensory"]["k_inf"];
  CHECK_THROWS_WITH(parse(root), std::string("door.json: sensory.k_infinity: unknown parameter"));

  root = reference_json();
  root["physical"]["spring"] = {{"value", 1.0}, {"bounds", {0.0, 2.0}}};
  CHECK_THROWS_WITH(parse(root), std::string("door.json: physical.spring: unknown parameter"));

  root = reference_json();
  root["sensory"]["k"]["unit"] = "N*m/rad";
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: sensory.k.unit: unknown field"));
}

TEST_CASE("Parameter file: missing parameters, keys and fields are rejected by name",
          "[parameter_file]") {
  json root = reference_json();
  root["sensory"].erase("c");
  CHECK_THROWS_WITH(parse(root), std::string("door.json: sensory.c: missing parameter"));

  root = reference_json();
  root["physical"].erase("mu_l");
  CHECK_THROWS_WITH(parse(root), std::string("door.json: physical.mu_l: missing parameter"));

  root = reference_json();
  root["sensory"]["k"].erase("bounds");
  CHECK_THROWS_WITH(parse(root), std::string("door.json: sensory.k: missing field bounds"));

  root = reference_json();
  root["physical"]["e"].erase("value");
  CHECK_THROWS_WITH(parse(root), std::string("door.json: physical.e: missing field value"));

  root = reference_json();
  root.erase("handle_radius_m");
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: handle_radius_m:") && Contains("missing"));

  root = reference_json();
  root.erase("sensory");
  root.erase("physical");
  CHECK_THROWS_WITH(parse(root),
                    StartsWith("door.json: ") && Contains("sensory") && Contains("physical"));
}

TEST_CASE("Parameter file: values of the wrong kind are rejected by name", "[parameter_file]") {
  json root = reference_json();
  root["sensory"]["k"]["value"] = "forty";
  CHECK_THROWS_WITH(parse(root),
                    std::string("door.json: sensory.k.value: expected a number, found \"forty\""));

  root = reference_json();
  root["theta_max_rad"] = "90deg";
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: theta_max_rad: expected a number"));

  root = reference_json();
  root["sensory"]["beta"]["bounds"] = {100.0, "lots"};
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: sensory.beta.bounds: expected"));

  root = reference_json();
  root["sensory"]["beta"]["bounds"] = {100.0};
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: sensory.beta.bounds: expected"));

  root = reference_json();
  root["physical"]["k_l"] = 6000.0;  // a bare number: base parameters need their bounds
  CHECK_THROWS_WITH(parse(root), StartsWith("door.json: physical.k_l: expected"));
}

TEST_CASE("Parameter file: lower bound above upper bound is rejected", "[parameter_file]") {
  json root = reference_json();
  root["sensory"]["k"]["bounds"] = {500.0, 0.0};
  CHECK_THROWS_WITH(parse(root), std::string("door.json: sensory.k.bounds: lower bound 500 is "
                                             "above upper bound 0"));
  // Equal bounds (a fixed parameter) are fine.
  root["sensory"]["k"]["bounds"] = {40.0, 40.0};
  CHECK_NOTHROW(parse(root));
}

TEST_CASE("Parameter file: bad JSON is reported with its line", "[parameter_file]") {
  // Line 4 holds the stray closing brace after a trailing comma.
  const std::string text =
      "{\n"
      "  \"handle_radius_m\": 0.58,\n"
      "  \"theta_max_rad\": 1.5708,\n"
      "}\n";
  CHECK_THROWS_AS(parse_parameter_file(text, "door.json"), ParameterFileError);
  CHECK_THROWS_WITH(parse_parameter_file(text, "door.json"),
                    StartsWith("door.json: ") && Contains("line 4"));
  // A missing comma on line 3.
  const std::string missing_comma =
      "{\n"
      "  \"handle_radius_m\": 0.58\n"
      "  \"theta_max_rad\": 1.5708\n"
      "}\n";
  CHECK_THROWS_WITH(parse_parameter_file(missing_comma, "door.json"),
                    StartsWith("door.json: ") && Contains("line 3"));
  CHECK_THROWS_WITH(parse_parameter_file("", "empty.json"), StartsWith("empty.json: "));
  CHECK_THROWS_WITH(parse_parameter_file("[1, 2]", "door.json"), StartsWith("door.json: "));
}

TEST_CASE("load_model: files on disk", "[parameter_file]") {
  const TempDir dir;
  json root = reference_json();
  root["sensory"]["k_inf"]["value"] = 2000.0;
  const fs::path params = dir.write("door.json", root.dump(2));
  const fs::path effects = dir.write("effects.json", R"({"viscous_damping": {"b": 0.4}})");

  const doorbench::DoorModel model = doorbench::load_model(ModelKind::kSensory, params, {});
  // θ = 0.02, ω = 0: −(40 · 0.02 + 2000 · (0.02 − 0.00698)) = −(0.8 + 26.04) = −26.84.
  CHECK_THAT(model.torque_Nm(0.02, 0.0), WithinRel(-26.84, 1e-9));

  const doorbench::DoorModel damped = doorbench::load_model(ModelKind::kSensory, params, effects);
  CHECK(damped.term_count() == 6);
  // Adds −0.4 ω: −26.84 − 0.2 plus the friction at ω = 0.5, both in the undamped model too.
  CHECK_THAT(damped.torque_Nm(0.02, 0.5) - model.torque_Nm(0.02, 0.5), WithinRel(-0.2, 1e-12));

  // The physical section of the same file.
  const doorbench::DoorModel physical = doorbench::load_model(ModelKind::kPhysical, params, {});
  CHECK(physical.parameter_count() == 26);

  // No file: the reference door.
  const doorbench::DoorModel reference = doorbench::load_model(ModelKind::kSensory, {}, {});
  CHECK_THAT(reference.torque_Nm(0.02, 0.0), WithinRel(-14.52308, 1e-9));
}

TEST_CASE("load_model: errors name the file", "[parameter_file]") {
  const TempDir dir;
  const std::string missing = (dir.path / "nowhere.json").string();
  CHECK_THROWS_AS(doorbench::load_model(ModelKind::kSensory, missing, {}), ParameterFileError);
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kSensory, missing, {}),
                    StartsWith(missing + ": "));

  // Only a sensory section: asking for the physical model fails.
  json root = reference_json();
  root.erase("physical");
  const fs::path sensory_only = dir.write("sensory-only.json", root.dump(2));
  CHECK_NOTHROW(doorbench::load_model(ModelKind::kSensory, sensory_only, {}));
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kPhysical, sensory_only, {}),
                    StartsWith(sensory_only.string() + ": ") && Contains("physical"));

  // A constraint broken in the file: the file's name, then the constraint.
  root = reference_json();
  root["sensory"]["theta0"]["value"] = 0.03;
  const fs::path broken = dir.write("broken.json", root.dump(2));
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kSensory, broken, {}),
                    std::string(broken.string() + ": sensory parameter theta0 = 0.03 breaks "
                                                  "0 < theta0 < theta1 (theta1 = 0.02793)"));

  // Malformed JSON on disk: the file's name and the line.
  const fs::path bad = dir.write("bad.json", "{\n  \"handle_radius_m\": 0.58,\n  oops\n}\n");
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kSensory, bad, {}),
                    StartsWith(bad.string() + ": ") && Contains("line 3"));

  // Problems in the effects file name the effects file.
  const fs::path params = dir.write("door.json", reference_json().dump(2));
  const fs::path negative = dir.write("negative.json", R"({"viscous_damping": {"b": -1}})");
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kSensory, params, negative),
                    std::string(negative.string() + ": effect parameter viscous_damping.b = -1 "
                                                    "breaks viscous_damping.b >= 0"));
  const fs::path unknown = dir.write("unknown.json", R"({"magnetism": {"k": 1}})");
  CHECK_THROWS_WITH(doorbench::load_model(ModelKind::kSensory, params, unknown),
                    StartsWith(unknown.string() + ": magnetism: unknown effect"));
}

TEST_CASE("Parameter file: a model written out reads back the same", "[parameter_file]") {
  doorbench::DoorModel model = doorbench::reference_model(ModelKind::kPhysical);
  model = model.with_effect(doorbench::parse_effects_file(
      R"({"stribeck": {"d_s": {"value": 1.1, "bounds": [0.5, 2]}, "w_s": 0.03}})", "e.json")[0]);
  const doorbench::ParameterFile file =
      parse_parameter_file(doorbench::to_parameter_json(model), "written.json");
  REQUIRE(file.physical.has_value());
  CHECK_FALSE(file.sensory.has_value());
  const auto values = model.parameter_values();
  for (int i = 0; i < 26; ++i) {
    CHECK(file.physical->values[i] == values[i]);
    CHECK(file.physical->bounds[i].lower == model.parameter_bounds()[i].lower);
    CHECK(file.physical->bounds[i].upper == model.parameter_bounds()[i].upper);
  }
  const auto effects =
      doorbench::parse_effects_file(doorbench::to_effects_json(model), "written-effects.json");
  REQUIRE(effects.size() == 1);
  CHECK(effects[0].values == std::vector<double>{1.1, 0.03});
  CHECK(effects[0].bounds[0].lower == 0.5);
  CHECK(effects[0].bounds[0].upper == 2.0);
}

// §2: "Parameters, in the order that files and reports list them" — J, k, k_inf, ...,
// c_stop. A file written by to_parameter_json should list them in that order too.
TEST_CASE("Parameter file: written files list the sensory parameters in the spec's order",
          "[parameter_file]") {
  const std::string text =
      doorbench::to_parameter_json(doorbench::reference_model(ModelKind::kSensory));
  const std::vector<std::string> order = {
      "J",  "k",  "k_inf", "k_lock", "theta0", "theta1", "theta2", "theta3", "c",
      "d1", "d2", "s",     "theta4", "beta",   "beta_f", "k_stop", "c_stop"};
  std::size_t previous = 0;
  for (const std::string& name : order) {
    const std::size_t at = text.find("\"" + name + "\":");
    INFO(name << " at " << at << ", the one before it at " << previous);
    REQUIRE(at != std::string::npos);
    CHECK(at >= previous);
    previous = at;
  }
}

TEST_CASE("Parameter file: a key or a section given twice is refused with both lines",
          "[parameter_file]") {
  // J given twice (4.0, then 0.95), and a section given twice: refused, not the last kept.
  CHECK_THROWS_WITH(parse_parameter_file("{\n"
                                         "  \"handle_radius_m\": 0.7,\n"
                                         "  \"sensory\": {\n"
                                         "    \"J\": {\"value\": 4.0},\n"
                                         "    \"J\": {\"value\": 0.95}\n"
                                         "  }\n"
                                         "}\n",
                                         "door.json"),
                    std::string("door.json: line 5: sensory.J is given twice (lines 4 and 5); a "
                                "file says each thing once"));
  CHECK_THROWS_WITH(parse_parameter_file("{\n"
                                         "  \"sensory\": {},\n"
                                         "  \"theta_max_rad\": 1.5,\n"
                                         "  \"sensory\": {\"J\": {\"value\": 1}}\n"
                                         "}\n",
                                         "door.json"),
                    std::string("door.json: line 4: sensory is given twice (lines 2 and 4); a "
                                "file says each thing once"));
  // Written differently, the same key (an escape), and in an effects file.
  CHECK_THROWS_WITH(
      parse_parameter_file("{\"physical\": {\"k\": 1,\n\"\\u006b\": 2}}", "door.json"),
      std::string("door.json: line 2: physical.k is given twice (lines 1 and 2); a "
                  "file says each thing once"));
  CHECK_THROWS_WITH(doorbench::parse_effects_file("{\"viscous_damping\": {},\n\n"
                                                  "\"viscous_damping\": {}}",
                                                  "effects.json"),
                    std::string("effects.json: line 3: viscous_damping is given twice (lines 1 "
                                "and 3); a file says each thing once"));
  // The same name in two different objects is two things.
  CHECK_THROWS_WITH(parse_parameter_file("{\"sensory\": {\"J\": 1}, \"physical\": {\"J\": 1}, "
                                         "\"list\": [{\"a\": 1}, {\"a\": 2}]}",
                                         "door.json"),
                    !Contains("twice"));
}
