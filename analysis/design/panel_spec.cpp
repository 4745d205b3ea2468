#include "analysis/design/panel_spec.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "core/numbers.h"

namespace doorbench {

void choose_favourite(CampaignForSpec& c) {
  c.favourite.clear();
  c.favourite_file.clear();
  const PanelPreference* best = nullptr;
  for (const PanelPreference& v : c.preference) {
    if (best == nullptr || v.worth > best->worth) best = &v;
  }
  if (best == nullptr) return;
  c.favourite = best->variant;
  if (const auto file = c.variant_files.find(best->variant); file != c.variant_files.end()) {
    c.favourite_file = file->second;
  }
}

void assign_felt_jnds(CampaignForSpec& c) {
  c.jnds.clear();
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

}  // namespace doorbench
