// study's analysis.json read back for the specification (analysis_for_spec.h).
#include "study/statistics/analysis_for_spec.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "core/numbers.h"

namespace doorbench::study {
namespace {

using json = nlohmann::json;

// Field access with errors naming the file and the field ("jnd[1].weber_fraction").
struct SpecFieldReader {
  std::string file;
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw std::runtime_error(file + ": " + field + ": " + what);
  }
  const json& member(const json& object, const std::string& path, const char* key) const {
    if (!object.contains(key)) fail(path + "." + key, "missing");
    return object.at(key);
  }
  std::string text(const json& object, const std::string& path, const char* key) const {
    const json& value = member(object, path, key);
    if (!value.is_string()) fail(path + "." + key, "a string expected");
    return value.get<std::string>();
  }
  // A number; null reads as NaN when `nullable`.
  double number(const json& object, const std::string& path, const char* key, bool nullable) const {
    const json& value = member(object, path, key);
    if (nullable && value.is_null()) return kNaN;
    if (!value.is_number())
      fail(path + "." + key, nullable ? "a number or null expected" : "a number expected");
    return value.get<double>();
  }
  const json& array(const json& root, const char* key) const {
    const json& value = root.at(key);
    if (!value.is_array()) fail(key, "an array expected");
    return value;
  }
};

std::string indexed(const char* section, std::size_t i) {
  return std::string(section) + "[" + std::to_string(i) + "]";
}

void read_preference(const SpecFieldReader& r, const json& root, CampaignForSpec& c) {
  if (!root.contains("preference_scale")) {
    c.notes.push_back("no preference_scale section in " + r.file);
    return;
  }
  const json& rows = r.array(root, "preference_scale");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string path = indexed("preference_scale", i);
    if (!rows[i].is_object()) r.fail(path, "an object expected");
    PanelPreference v;
    v.variant = r.text(rows[i], path, "variant");
    v.worth = r.number(rows[i], path, "worth", false);
    v.ci_low = r.number(rows[i], path, "ci_low", true);
    v.ci_high = r.number(rows[i], path, "ci_high", true);
    if (rows[i].contains("file")) {
      c.variant_files[v.variant] = c.analysis_path.parent_path() / r.text(rows[i], path, "file");
    }
    c.preference.push_back(std::move(v));
  }
}

// The panel's jnd rows (assign_felt_jnds makes them the felt quantities' JNDs).
void read_thresholds(const SpecFieldReader& r, const json& root, CampaignForSpec& c) {
  if (root.contains("jnd")) {
    const json& rows = r.array(root, "jnd");
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string path = indexed("jnd", i);
      if (!rows[i].is_object()) r.fail(path, "an object expected");
      PanelThreshold t;
      t.participant = r.text(rows[i], path, "participant");
      if (t.participant != "panel") continue;
      t.parameter = r.text(rows[i], path, "parameter");
      t.reference = r.text(rows[i], path, "reference");
      t.method = rows[i].contains("method") ? r.text(rows[i], path, "method") : "";
      t.criterion = rows[i].contains("criterion") ? r.text(rows[i], path, "criterion") : "";
      t.weber_fraction = r.number(rows[i], path, "weber_fraction", false);
      if (!(t.weber_fraction > 0) || !std::isfinite(t.weber_fraction)) {
        r.fail(path + ".weber_fraction", "a positive number expected");
      }
      t.ci_low = r.number(rows[i], path, "ci_low", true);
      t.ci_high = r.number(rows[i], path, "ci_high", true);
      c.thresholds.push_back(std::move(t));
    }
    if (c.thresholds.empty()) {
      c.notes.push_back("the jnd section of " + r.file +
                        " has no panel row: typical published JNDs used");
    }
  } else {
    c.notes.push_back("no jnd section in " + r.file +
                      ": typical published JNDs used (stiffness 15%, friction 20%)");
  }
}

void read_tuning(const SpecFieldReader& r, const json& root, CampaignForSpec& c) {
  if (!root.contains("tuning")) return;
  const json& tuning = root.at("tuning");
  if (!tuning.is_object()) r.fail("tuning", "an object expected");
  if (tuning.contains("doors")) {
    if (!tuning.at("doors").is_array()) r.fail("tuning.doors", "an array expected");
    c.tuned_doors = static_cast<int>(tuning.at("doors").size());
  }
  if (!tuning.contains("parameters")) return;
  const json& rows = tuning.at("parameters");
  if (!rows.is_array()) r.fail("tuning.parameters", "an array expected");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string path = "tuning.parameters[" + std::to_string(i) + "]";
    if (!rows[i].is_object()) r.fail(path, "an object expected");
    const std::string name = r.text(rows[i], path, "parameter");
    const double centre = r.number(rows[i], path, "centre", true);
    if (std::isfinite(centre)) c.tuned_centre[name] = centre;
  }
}

}  // namespace

CampaignForSpec read_campaign_for_spec(const std::filesystem::path& folder) {
  CampaignForSpec c;
  c.analysis_path = folder / "analysis.json";
  const std::string file = c.analysis_path.string();
  if (!std::filesystem::is_regular_file(c.analysis_path)) {
    throw std::runtime_error(file +
                             ": no such file (--campaign takes a `doorbench campaign "
                             "analyze` output folder)");
  }
  json root;
  try {
    root = json::parse(read_text_file(c.analysis_path));
  } catch (const json::exception& error) {
    throw std::runtime_error(file + ": not JSON: " + error.what());
  }
  if (!root.is_object()) throw std::runtime_error(file + ": a JSON object expected");
  const SpecFieldReader reader{file};
  read_preference(reader, root, c);
  read_thresholds(reader, root, c);
  read_tuning(reader, root, c);
  choose_favourite(c);
  assign_felt_jnds(c);
  return c;
}

}  // namespace doorbench::study
