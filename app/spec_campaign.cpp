// `doorbench spec --campaign`: reading a `campaign analyze` folder's analysis.json.
#include "app/spec_campaign.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "core/number_format.h"
#include "core/numbers.h"

namespace doorbench::app {
namespace {

using json = nlohmann::json;

// Field access with errors naming the file and the field ("jnd[1].weber_fraction").
struct Reader {
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

void read_preference(const Reader& r, const json& root, CampaignForSpec& c) {
  if (!root.contains("preference_scale")) {
    c.notes.push_back("no preference_scale section in " + r.file);
    return;
  }
  const json& rows = r.array(root, "preference_scale");
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string path = indexed("preference_scale", i);
    if (!rows[i].is_object()) r.fail(path, "an object expected");
    PanelPreference v;
    v.variant = r.text(rows[i], path, "variant");
    v.worth = r.number(rows[i], path, "worth", false);
    v.ci_low = r.number(rows[i], path, "ci_low", true);
    v.ci_high = r.number(rows[i], path, "ci_high", true);
    if (v.worth > best) {
      best = v.worth;
      c.favourite = v.variant;
      c.favourite_file.clear();
      if (rows[i].contains("file")) {
        const std::string file = r.text(rows[i], path, "file");
        c.favourite_file = c.analysis_path.parent_path() / file;
      }
    }
    c.preference.push_back(std::move(v));
  }
}

// The panel's jnd rows; each felt quantity takes the first one measuring a parameter that
// stands for it (felt_jnd_kinds), else its typical JND.
void read_thresholds(const Reader& r, const json& root, CampaignForSpec& c) {
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
  std::vector<bool> used(c.thresholds.size(), false);
  for (const FeltJndKind& kind : felt_jnd_kinds()) {
    FeltJnd jnd = typical_felt_jnd(kind.quantity);
    for (std::size_t i = 0; i < c.thresholds.size() && !jnd.measured; ++i) {
      const PanelThreshold& t = c.thresholds[i];
      if (std::find(kind.parameters.begin(), kind.parameters.end(), t.parameter) ==
          kind.parameters.end()) {
        continue;
      }
      jnd.measured = true;
      jnd.weber_fraction = t.weber_fraction;
      jnd.ci_low = t.ci_low;
      jnd.ci_high = t.ci_high;
      jnd.source =
          "measured: " + t.parameter + " (panel" + (t.method.empty() ? "" : ", ") + t.method + ")";
      used[i] = true;
    }
    c.jnds.push_back(std::move(jnd));
  }
  for (std::size_t i = 0; i < c.thresholds.size(); ++i) {
    if (!used[i]) {
      c.notes.push_back("the panel's JND of " + c.thresholds[i].parameter +
                        " stands for no felt quantity of the specification: not used");
    }
  }
}

void read_tuning(const Reader& r, const json& root, CampaignForSpec& c) {
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
  const Reader reader{file};
  read_preference(reader, root, c);
  read_thresholds(reader, root, c);
  read_tuning(reader, root, c);
  return c;
}

namespace {

// The door a parameter file describes: its physical section, else its sensory one.
DoorModel variant_model(const std::filesystem::path& file) {
  const ParameterFile parsed = parse_parameter_file(read_text_file(file), file.string());
  return load_model(parsed.physical ? ModelKind::kPhysical : ModelKind::kSensory, file, "");
}

// `base` with the parameters `value_of` gives (NaN: kept); the number set.
int set_parameters(DoorModel& base, const std::function<double(const std::string&)>& value_of) {
  std::vector<double> values(base.parameter_values().begin(), base.parameter_values().end());
  int set = 0;
  for (int i = 0; i < base.base_parameter_count(); ++i) {
    const double value = value_of(base.parameter_name(i));
    if (!std::isfinite(value)) continue;
    values[static_cast<std::size_t>(i)] = value;
    ++set;
  }
  if (set > 0) base = base.with_parameter_values(std::move(values));
  return set;
}

}  // namespace

DoorModel campaign_tobe_model(const CampaignForSpec& campaign, const DoorModel& asis,
                              std::string& source) {
  const std::string file = campaign.analysis_path.string();
  if (!campaign.favourite_file.empty()) {
    if (!std::filesystem::is_regular_file(campaign.favourite_file)) {
      throw std::runtime_error(file + ": the favourite variant " + campaign.favourite + "'s file " +
                               campaign.favourite_file.string() + ": no such file");
    }
    source = "the panel's favourite variant " + campaign.favourite +
             " (largest worth on the "
             "preference scale), its parameter file " +
             campaign.favourite_file.string() + ", opened and closed by the virtual hand";
    return variant_model(campaign.favourite_file);
  }
  const auto centre = [&campaign](const std::string& name) {
    const auto found = campaign.tuned_centre.find(name);
    return found == campaign.tuned_centre.end() ? kNaN : found->second;
  };
  const DoorModel sensory = reference_model(ModelKind::kSensory);
  DoorModel physical = asis;
  const int physical_set = set_parameters(physical, [&](const std::string& name) {
    const double prefixed = centre("physical." + name);
    if (std::isfinite(prefixed)) return prefixed;
    return sensory.find_parameter(name) ? kNaN : centre(name);
  });
  const std::string why =
      campaign.favourite.empty()
          ? std::string("there is no preference scale")
          : "the favourite variant " + campaign.favourite + " names no parameter file";
  if (physical_set > 0) {
    source = "the centre of the panel's " + std::to_string(campaign.tuned_doors) +
             " tuned doors (tuning section; " + std::to_string(physical_set) +
             " physical parameters, the rest AS-IS), because " + why;
    return physical;
  }
  DoorModel tuned = sensory;
  const int sensory_set = set_parameters(tuned, centre);
  if (sensory_set > 0) {
    source = "the centre of the panel's " + std::to_string(campaign.tuned_doors) +
             " tuned doors (tuning section; " + std::to_string(sensory_set) +
             " sensory parameters on the reference sensory door), because " + why;
    return tuned;
  }
  throw std::runtime_error(file + ": no TO-BE feel: " + why +
                           " and no tuning section gives a door's parameters (give TO-BE "
                           "recordings instead)");
}

double parse_felt_share(std::string_view text) {
  std::string number(text);
  const bool percent = !number.empty() && number.back() == '%';
  if (percent) number.pop_back();
  std::size_t used = 0;
  double value = kNaN;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (percent) value /= 100.0;
  if (used == 0 || used != number.size() || !(value > 0 && value < 1)) {
    throw UsageError("--felt-share: '" + std::string(text) +
                     "' is not a share between 0 and 1 (e.g. 5% or 0.05)");
  }
  return value;
}

}  // namespace doorbench::app
