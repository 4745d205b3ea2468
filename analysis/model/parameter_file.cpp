#include "analysis/model/parameter_file.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/number_format.h"

namespace doorbench {
namespace {

// Ordered, so that files keep the spec's parameter order and effects their file order.
using json = nlohmann::ordered_json;

[[noreturn]] void fail(std::string_view source, const std::string& message) {
  throw ParameterFileError(std::string(source) + ": " + message);
}

// A key given twice in one object (J given twice, where the last one would silently win):
// refused with both lines. Runs on text that parsed, so the scan only follows strings,
// nesting and the ':' after a key. Keys are compared as written (escapes decoded).
void refuse_duplicate_keys(std::string_view text, std::string_view source) {
  struct Level {
    bool object = false;
    std::string path;                  // "sensory" ("" at the top)
    std::map<std::string, int> lines;  // key -> its line
    std::string last_key;
  };
  std::vector<Level> levels;
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (c == '{' || c == '[') {
      std::string path = levels.empty() ? "" : levels.back().path;
      if (!levels.empty() && levels.back().object && !levels.back().last_key.empty()) {
        path += (path.empty() ? "" : ".") + levels.back().last_key;
      }
      levels.push_back({c == '{', path, {}, ""});
    } else if ((c == '}' || c == ']') && !levels.empty()) {
      levels.pop_back();
    } else if (c == '"') {
      const std::size_t start = i;
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') ++i;
      }
      std::size_t next = i + 1;
      while (next < text.size() && std::isspace(static_cast<unsigned char>(text[next]))) ++next;
      if (levels.empty() || !levels.back().object || next >= text.size() || text[next] != ':') {
        continue;
      }
      const std::string_view raw = text.substr(start, i - start + 1);
      const std::string key = raw.find('\\') == std::string_view::npos
                                  ? std::string(raw.substr(1, raw.size() - 2))
                                  : json::parse(raw).get<std::string>();
      Level& level = levels.back();
      level.last_key = key;
      const auto [at, inserted] = level.lines.emplace(key, line);
      if (!inserted) {
        fail(source, "line " + std::to_string(line) + ": " +
                         (level.path.empty() ? "" : level.path + ".") + key +
                         " is given twice (lines " + std::to_string(at->second) + " and " +
                         std::to_string(line) + "); a file says each thing once");
      }
    }
  }
}

json parse_json(std::string_view text, std::string_view source) {
  try {
    json root = json::parse(text.begin(), text.end());
    refuse_duplicate_keys(text, source);
    return root;
  } catch (const json::parse_error& error) {
    // nlohmann's message already gives line and column.
    std::string what = error.what();
    const auto tag_end = what.find("] ");
    fail(source, tag_end == std::string::npos ? what : what.substr(tag_end + 2));
  } catch (const json::exception& error) {
    // A number beyond a double (out_of_range.406: "number overflow parsing '1e999'") comes
    // without a place: the line is that of the number's first appearance.
    std::string what = error.what();
    const auto tag_end = what.find("] ");
    if (tag_end != std::string::npos) what = what.substr(tag_end + 2);
    const auto open = what.find('\'');
    const auto close = what.rfind('\'');
    if (open != std::string::npos && close > open + 1) {
      const std::string token = what.substr(open + 1, close - open - 1);
      const auto at = text.find(token);
      if (at != std::string_view::npos) {
        const auto line =
            1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
        fail(source,
             "line " + std::to_string(line) + ": " + what + " (beyond the range of a double)");
      }
    }
    fail(source, what);
  }
}

double number_at(const json& node, std::string_view source, const std::string& key) {
  if (!node.is_number()) fail(source, key + ": expected a number, found " + node.dump());
  return node.get<double>();
}

Bounds bounds_at(const json& node, std::string_view source, const std::string& key) {
  if (!node.is_array() || node.size() != 2 || !node[0].is_number() || !node[1].is_number()) {
    fail(source, key + ": expected [lower, upper], found " + node.dump());
  }
  const Bounds bounds{node[0].get<double>(), node[1].get<double>()};
  if (!(bounds.lower <= bounds.upper)) {
    fail(source, key + ": lower bound " + format_number(bounds.lower) + " is above upper bound " +
                     format_number(bounds.upper));
  }
  return bounds;
}

// One {"value": v, "bounds": [lo, hi]} entry; a bare number when `fallback` is given.
void read_entry(const json& node, std::string_view source, const std::string& key,
                const Bounds* fallback, double& value, Bounds& bounds) {
  if (node.is_number() && fallback != nullptr) {
    value = node.get<double>();
    bounds = *fallback;
    return;
  }
  if (!node.is_object()) {
    fail(source, key + ": expected {\"value\": ..., \"bounds\": [lower, upper]}" +
                     std::string(fallback ? " or a number" : "") + ", found " + node.dump());
  }
  for (const auto& [field, unused] : node.items()) {
    if (field != "value" && field != "bounds") {
      fail(source, key + "." + field + ": unknown field (expected value, bounds)");
    }
  }
  if (!node.contains("value")) fail(source, key + ": missing field value");
  value = number_at(node["value"], source, key + ".value");
  if (node.contains("bounds")) {
    bounds = bounds_at(node["bounds"], source, key + ".bounds");
  } else if (fallback != nullptr) {
    bounds = *fallback;
  } else {
    fail(source, key + ": missing field bounds");
  }
}

template <std::size_t N>
ModelSection read_section(const json& node, std::string_view source, std::string_view section,
                          const std::array<ParameterInfo, N>& infos) {
  const std::string prefix(section);
  if (!node.is_object()) fail(source, prefix + ": expected an object of parameters");
  for (const auto& [key, unused] : node.items()) {
    bool known = false;
    for (const ParameterInfo& info : infos) known = known || info.name == key;
    if (!known) fail(source, prefix + "." + key + ": unknown parameter");
  }
  ModelSection result{std::vector<double>(N), std::vector<Bounds>(N)};
  for (std::size_t i = 0; i < N; ++i) {
    const std::string name(infos[i].name);
    if (!node.contains(name)) fail(source, prefix + "." + name + ": missing parameter");
    read_entry(node[name], source, prefix + "." + name, nullptr, result.values[i],
               result.bounds[i]);
  }
  return result;
}

}  // namespace

ParameterFile parse_parameter_file(std::string_view json_text, std::string_view source) {
  const json root = parse_json(json_text, source);
  if (!root.is_object()) fail(source, "expected a JSON object at the top level");
  for (const auto& [key, unused] : root.items()) {
    if (key != "about" && key != "handle_radius_m" && key != "theta_max_rad" && key != "sensory" &&
        key != "physical" && key != "bench") {
      fail(source, key +
                       ": unknown key (expected about, handle_radius_m, theta_max_rad, "
                       "sensory, physical, bench)");
    }
  }
  ParameterFile file;
  for (const char* key : {"handle_radius_m", "theta_max_rad"}) {
    if (!root.contains(key)) fail(source, std::string(key) + ": missing key");
  }
  file.geometry.handle_radius_m = number_at(root["handle_radius_m"], source, "handle_radius_m");
  file.geometry.theta_max_rad = number_at(root["theta_max_rad"], source, "theta_max_rad");
  if (root.contains("sensory")) {
    file.sensory = read_section(root["sensory"], source, "sensory", sensory::kParameterInfo);
  }
  if (root.contains("physical")) {
    file.physical = read_section(root["physical"], source, "physical", physical::kParameterInfo);
  }
  if (!file.sensory && !file.physical) {
    fail(source, "neither a sensory nor a physical section");
  }
  return file;
}

std::vector<EffectSetting> parse_effects_file(std::string_view json_text, std::string_view source) {
  const json root = parse_json(json_text, source);
  if (!root.is_object()) fail(source, "expected a JSON object of effects at the top level");
  std::vector<EffectSetting> settings;
  for (const auto& [name, node] : root.items()) {
    if (name == "about") continue;
    const std::optional<effects::Kind> kind = effects::find(name);
    if (!kind) {
      std::string known;
      for (const effects::EffectInfo& info : effects::catalogue()) {
        known += (known.empty() ? "" : ", ") + std::string(info.name);
      }
      fail(source, name + ": unknown effect (the catalogue has " + known + ")");
    }
    const effects::EffectInfo& info = effects::info(*kind);
    if (!node.is_object()) fail(source, name + ": expected an object of parameters");
    for (const auto& [key, unused] : node.items()) {
      bool known = false;
      for (const effects::EffectParameter& parameter : info.parameters) {
        known = known || parameter.info.name == key;
      }
      if (!known) fail(source, name + "." + key + ": unknown parameter");
    }
    EffectSetting setting{*kind, {}, {}};
    for (const effects::EffectParameter& parameter : info.parameters) {
      const std::string key = name + "." + std::string(parameter.info.name);
      const std::string field(parameter.info.name);
      if (!node.contains(field)) fail(source, key + ": missing parameter");
      double value = 0;
      Bounds bounds;
      read_entry(node[field], source, key, &parameter.default_bounds, value, bounds);
      setting.values.push_back(value);
      setting.bounds.push_back(bounds);
    }
    settings.push_back(std::move(setting));
  }
  return settings;
}

std::string read_text_file(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw ParameterFileError(path.string() + ": cannot open for reading");
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

namespace {

DoorModel build(ModelKind kind, const ParameterFile& file, std::string_view source,
                std::vector<EffectSetting> effects, std::string_view effects_source) {
  const std::optional<ModelSection>& section =
      kind == ModelKind::kSensory ? file.sensory : file.physical;
  if (!section) fail(source, std::string("no ") + std::string(to_string(kind)) + " section");
  try {
    return DoorModel(kind, file.geometry, section->values, section->bounds, std::move(effects));
  } catch (const std::invalid_argument& error) {
    // Name the file whose value broke the constraint.
    const std::string message = error.what();
    const bool from_effects = message.rfind("effect", 0) == 0;
    fail(from_effects ? effects_source : source, message);
  }
}

}  // namespace

DoorModel reference_model(ModelKind kind) {
  static const ParameterFile file = parse_parameter_file(reference_door_json(), "reference door");
  return build(kind, file, "reference door", {}, "");
}

DoorModel load_model(ModelKind kind, const std::filesystem::path& params_path,
                     const std::filesystem::path& effects_path) {
  const std::string source = params_path.empty() ? "reference door" : params_path.string();
  const ParameterFile file = params_path.empty()
                                 ? parse_parameter_file(reference_door_json(), source)
                                 : parse_parameter_file(read_text_file(params_path), source);
  std::vector<EffectSetting> effects;
  if (!effects_path.empty()) {
    effects = parse_effects_file(read_text_file(effects_path), effects_path.string());
  }
  return build(kind, file, source, std::move(effects), effects_path.string());
}

std::string to_parameter_json(const DoorModel& model) {
  json section = json::object();
  for (int i = 0; i < model.base_parameter_count(); ++i) {
    const Bounds& bounds = model.parameter_bounds()[i];
    section[model.parameter_name(i)] = {{"value", model.parameter_values()[i]},
                                        {"bounds", {bounds.lower, bounds.upper}}};
  }
  json root = {{"handle_radius_m", model.geometry().handle_radius_m},
               {"theta_max_rad", model.geometry().theta_max_rad},
               {std::string(to_string(model.kind())), section}};
  return root.dump(2) + "\n";
}

std::string to_effects_json(const DoorModel& model) {
  json root = json::object();
  int index = model.base_parameter_count();
  for (const EffectSetting& effect : model.effects()) {
    const effects::EffectInfo& info = effects::info(effect.kind);
    json node = json::object();
    for (const effects::EffectParameter& parameter : info.parameters) {
      const Bounds& bounds = model.parameter_bounds()[index];
      node[std::string(parameter.info.name)] = {{"value", model.parameter_values()[index]},
                                                {"bounds", {bounds.lower, bounds.upper}}};
      ++index;
    }
    root[std::string(info.name)] = node;
  }
  return root.dump(2) + "\n";
}

}  // namespace doorbench
