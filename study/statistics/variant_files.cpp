#include "study/statistics/variant_files.h"

#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "analysis/model/parameter_file.h"

namespace doorbench::study {

std::optional<DoorModel> door_from_rendered(std::string_view rendered) {
  std::vector<std::pair<std::string, double>> values;
  std::istringstream words{std::string(rendered)};
  std::string word;
  while (words >> word) {
    const std::size_t equals = word.find('=');
    if (equals == std::string::npos || equals == 0) return std::nullopt;
    const std::string number = word.substr(equals + 1);
    char* end = nullptr;
    const double value = std::strtod(number.c_str(), &end);
    if (number.empty() || end != number.c_str() + number.size()) return std::nullopt;
    values.emplace_back(word.substr(0, equals), value);
  }
  if (values.empty()) return std::nullopt;
  for (const ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel reference = reference_model(kind);
    if (static_cast<int>(values.size()) != reference.parameter_count()) continue;
    std::vector<double> set(reference.parameter_values().begin(),
                            reference.parameter_values().end());
    std::vector<bool> seen(set.size(), false);
    bool all = true;
    for (const auto& [name, value] : values) {
      const std::optional<int> index = reference.find_parameter(name);
      if (!index || seen[static_cast<std::size_t>(*index)]) {
        all = false;
        break;
      }
      seen[static_cast<std::size_t>(*index)] = true;
      set[static_cast<std::size_t>(*index)] = value;
    }
    if (!all) continue;
    try {
      return reference.with_parameter_values(std::move(set));
    } catch (const std::invalid_argument&) {
      return std::nullopt;
    }
  }
  return std::nullopt;
}

namespace {
constexpr std::string_view kVariantFolder = "variants";
constexpr std::string_view kVariantExtension = ".json";
}  // namespace

std::string variant_file_name(std::string_view variant) {
  std::string name = std::string(kVariantFolder) + "/";
  for (const char c : variant) {
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                       c == '.' || c == '_' || c == '-';
    name += plain ? c : '_';
  }
  return name + std::string(kVariantExtension);
}

bool is_variant_file(const std::string& name) {
  return name.size() > kVariantExtension.size() && name.ends_with(kVariantExtension);
}

void write_variant_files(const std::filesystem::path& analysis_folder,
                         const VariantFiles& variants) {
  const std::filesystem::path folder = analysis_folder / kVariantFolder;
  std::vector<std::string> written;
  for (const VariantFile& variant : variants.files)
    written.push_back(std::filesystem::path(variant.file).filename().string());
  remove_outputs_not_written(folder, is_variant_file, written);
  if (!variants.files.empty()) std::filesystem::create_directories(folder);
  for (const VariantFile& variant : variants.files)
    write_text_file_atomically(analysis_folder / variant.file, variant.text);
}

namespace {

// Each variant's rendered parameters as the table gives them (every distinct text).
std::map<std::string, std::vector<std::string>> rendered_by_variant(const TrialsTable& table) {
  std::map<std::string, std::vector<std::string>> rendered;
  const auto first = table.find_column("first_parameters");
  const auto second = table.find_column("second_parameters");
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const auto add = [&](const std::optional<std::size_t>& column, const char* name_column) {
      if (!column) return;
      const std::string& text = table.rows[r][*column];
      if (text.empty()) return;
      std::vector<std::string>& texts = rendered[table.value(r, name_column)];
      for (const std::string& known : texts)
        if (known == text) return;
      texts.push_back(text);
    };
    add(first, "first");
    add(second, "second");
  }
  return rendered;
}

}  // namespace

VariantFiles variant_parameter_files(const TrialsTable& table, nlohmann::json& analysis) {
  VariantFiles result;
  if (!analysis.contains("preference_scale")) return result;
  const bool has_columns =
      table.find_column("first_parameters") || table.find_column("second_parameters");
  const auto rendered = rendered_by_variant(table);
  if (!has_columns) {
    result.notes.push_back(
        "no variant parameter files: the trials table has no first_parameters or "
        "second_parameters column");
  }
  std::map<std::string, std::string> taken;  // file -> variant, for names that collide
  for (nlohmann::json& row : analysis["preference_scale"]) {
    if (!has_columns) break;
    const std::string variant = row.at("variant").get<std::string>();
    const auto found = rendered.find(variant);
    std::string why;
    std::optional<DoorModel> door;
    if (found == rendered.end()) {
      why = "no row of the trials table gives its parameters";
    } else if (found->second.size() > 1) {
      why = "the trials table gives it " + std::to_string(found->second.size()) +
            " different sets of parameters";
    } else if (door = door_from_rendered(found->second.front()); !door) {
      why = "its parameters in the trials table are not one door model's";
    }
    std::string file = variant_file_name(variant);
    if (why.empty() && taken.count(file) != 0) {
      why = "its file name " + file + " is " + taken[file] + "'s";
    }
    if (!why.empty()) {
      result.notes.push_back("variant " + variant + " has no parameter file: " + why);
      continue;
    }
    taken[file] = variant;
    row["file"] = file;
    result.files.push_back({variant, file, to_parameter_json(*door)});
  }
  if (!result.notes.empty()) {
    nlohmann::json& notes = analysis["preference_fit"]["notes"];
    if (!notes.is_array()) notes = nlohmann::json::array();
    for (const std::string& note : result.notes) notes.push_back(note);
  }
  return result;
}

}  // namespace doorbench::study
