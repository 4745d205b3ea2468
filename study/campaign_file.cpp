#include "study/campaign_file.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>

#include "analysis/model/parameter_file.h"
#include "analysis/model/perceptual_controls.h"
#include "core/number_format.h"

namespace doorbench::study {
namespace {

int line_of(const toml::node& node) {
  return node.source().begin.line > 0 ? static_cast<int>(node.source().begin.line) : 1;
}

// A table of the campaign with its dotted name and line, and the file for messages.
class Table {
 public:
  Table(const std::string& source, const toml::table& table, std::string path, int line)
      : source_(&source), table_(&table), path_(std::move(path)), line_(line) {}

  [[noreturn]] void fail(std::string_view key, std::string_view what) const {
    const toml::node* node = key.empty() ? nullptr : table_->get(key);
    const int line = node ? line_of(*node) : line_;
    const std::string field = key.empty() ? path_ : path_ + "." + std::string(key);
    throw CampaignError(*source_ + ":" + std::to_string(line) + ": " +
                        (field.empty() ? "" : field + ": ") + std::string(what));
  }
  const toml::node* get(std::string_view key) const { return table_->get(key); }
  const toml::table& table() const { return *table_; }
  int line() const { return line_; }
  const std::string& path() const { return path_; }

  void allow_only(std::initializer_list<std::string_view> keys) const {
    for (auto&& [key, node] : *table_) {
      if (std::find(keys.begin(), keys.end(), key.str()) == keys.end()) {
        std::string valid;
        for (std::string_view k : keys) valid += (valid.empty() ? "" : ", ") + std::string(k);
        const int line =
            key.source().begin.line > 0 ? static_cast<int>(key.source().begin.line) : line_;
        throw CampaignError(*source_ + ":" + std::to_string(line) + ": " + path_ + "." +
                            std::string(key.str()) + ": unknown key; valid keys: " + valid);
      }
    }
  }
  std::optional<std::string> string(std::string_view key) const {
    const toml::node* node = get(key);
    if (!node) return std::nullopt;
    if (!node->is_string()) fail(key, "must be a string");
    return node->as_string()->get();
  }
  std::optional<double> number(std::string_view key, double low, double high) const {
    const toml::node* node = get(key);
    if (!node) return std::nullopt;
    double value = 0.0;
    if (node->is_integer()) {
      value = static_cast<double>(node->as_integer()->get());
    } else if (node->is_floating_point()) {
      value = node->as_floating_point()->get();
    } else {
      fail(key, "must be a number");
    }
    if (!(value >= low && value <= high)) {
      fail(key, "must be from " + format_readable(low) + " to " + format_readable(high) + ", got " +
                    format_readable(value));
    }
    return value;
  }
  std::optional<int> integer(std::string_view key, int low, int high) const {
    const toml::node* node = get(key);
    if (!node) return std::nullopt;
    if (!node->is_integer()) fail(key, "must be a whole number");
    const std::int64_t value = node->as_integer()->get();
    if (value < low || value > high) {
      fail(key, "must be from " + std::to_string(low) + " to " + std::to_string(high) + ", got " +
                    std::to_string(value));
    }
    return static_cast<int>(value);
  }
  // A sub-table; nullopt when absent and not required.
  std::optional<Table> child(std::string_view key, bool required) const {
    const toml::node* node = get(key);
    if (!node) {
      if (required) fail("", "missing table [" + std::string(key) + "]");
      return std::nullopt;
    }
    if (!node->is_table()) fail(key, "must be a table");
    return Table(*source_, *node->as_table(),
                 path_.empty() ? std::string(key) : path_ + "." + std::string(key), line_of(*node));
  }
  std::optional<std::vector<std::string>> strings(std::string_view key) const {
    const toml::node* node = get(key);
    if (!node) return std::nullopt;
    if (!node->is_array()) fail(key, "must be an array of strings");
    std::vector<std::string> values;
    for (const toml::node& item : *node->as_array()) {
      if (!item.is_string()) fail(key, "must be an array of strings");
      values.push_back(item.as_string()->get());
    }
    return values;
  }

 private:
  const std::string* source_;
  const toml::table* table_;
  std::string path_;
  int line_;
};

bool is_name(std::string_view name) {
  return !name.empty() && name.size() <= 40 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

}  // namespace

namespace {

Variant parse_variant(const Table& variants, const std::string& name, const std::string& spec,
                      const std::filesystem::path& folder) {
  Variant variant;
  variant.name = name;
  variant.spec = spec;
  if (!is_name(name)) {
    variants.fail(name, "a variant's name is letters, digits, '-' and '_' (at most 40)");
  }
  if (spec == "base") {
    variant.kind = Variant::Kind::kBase;
  } else if (spec == "real") {
    variant.kind = Variant::Kind::kReal;
  } else if (spec.rfind("file:", 0) == 0) {
    variant.kind = Variant::Kind::kFile;
    variant.file = folder / spec.substr(5);
  } else {
    variant.kind = Variant::Kind::kSteps;
    try {
      variant.steps = parse_steps(spec);
    } catch (const std::invalid_argument& wrong) {
      variants.fail(name, wrong.what());
    }
  }
  return variant;
}

// A variant's scene or sound set (`key` of its table): the path as written and resolved
// against the campaign file's folder; the file must exist.
void read_staging_file(const Table& table, std::string_view key,
                       const std::filesystem::path& folder, std::string& written,
                       std::filesystem::path& resolved) {
  const std::optional<std::string> path = table.string(key);
  if (!path) return;
  if (path->empty()) table.fail(key, "must name a file");
  const std::filesystem::path file = folder / *path;
  if (!std::filesystem::is_regular_file(file))
    table.fail(key, "no such file '" + *path + "' (looked for " + file.string() + ")");
  written = *path;
  resolved = file;
}

// A variant as a string ("J*1.2") or a table ({ door = "J*1.2", scene = ..., sounds = ... }).
Variant read_variant(const Table& variants, const std::string& name, const toml::node& node,
                     const std::filesystem::path& folder) {
  const char* what = "must be a string: base, real, file:PATH or steps such as \"J*1.2\"";
  if (node.is_string()) return parse_variant(variants, name, node.as_string()->get(), folder);
  if (!node.is_table())
    variants.fail(name,
                  std::string(what) + ", or a table { door = ..., scene = ..., sounds = ... }");
  const std::optional<Table> table = variants.child(name, true);
  table->allow_only({"door", "scene", "sounds"});
  const std::optional<std::string> door = table->string("door");
  if (!door) table->fail("", "missing door: base, real, file:PATH or steps such as \"J*1.2\"");
  Variant variant = parse_variant(variants, name, *door, folder);
  if (variant.kind == Variant::Kind::kReal && (table->get("scene") || table->get("sounds"))) {
    table->fail(table->get("scene") ? "scene" : "sounds",
                "the real door is seen and heard as it is on the bench; a scene and a sound set "
                "are for a model");
  }
  read_staging_file(*table, "scene", folder, variant.scene, variant.scene_file);
  read_staging_file(*table, "sounds", folder, variant.sounds, variant.sounds_file);
  return variant;
}

std::vector<std::pair<std::string, std::string>> parse_pairs(const Table& block,
                                                             const Campaign& campaign) {
  std::vector<std::pair<std::string, std::string>> pairs;
  const toml::node* node = block.get("pairs");
  if (!node || (node->is_string() && node->as_string()->get() == "all")) {
    for (std::size_t a = 0; a < campaign.variants.size(); ++a) {
      for (std::size_t b = a + 1; b < campaign.variants.size(); ++b) {
        pairs.emplace_back(campaign.variants[a].name, campaign.variants[b].name);
      }
    }
    return pairs;
  }
  const char* shape =
      "must be \"all\" or an array of pairs of variant names, e.g. [[\"a\", \"b\"]]";
  if (!node->is_array()) block.fail("pairs", shape);
  for (const toml::node& item : *node->as_array()) {
    const toml::array* pair = item.as_array();
    if (!pair || pair->size() != 2 || !(*pair)[0].is_string() || !(*pair)[1].is_string()) {
      block.fail("pairs", shape);
    }
    const std::string a = (*pair)[0].as_string()->get(), b = (*pair)[1].as_string()->get();
    for (const std::string& name : {a, b}) {
      if (!campaign.find_variant(name)) block.fail("pairs", "no variant named '" + name + "'");
    }
    if (a == b) block.fail("pairs", "a pair of '" + a + "' with itself");
    pairs.emplace_back(a, b);
  }
  if (pairs.empty()) block.fail("pairs", "holds no pair");
  return pairs;
}

// method = "quest+" (study/quest_plus.h).
void parse_quest_plus(const Table& table, Block& block) {
  for (const char* key : {"levels", "repetitions", "down", "start_level", "step_factor"}) {
    if (table.get(key))
      table.fail(
          key,
          "is not an option of quest+ (trials, min_level, max_level, stimuli, thresholds, lapse)");
  }
  block.method = JndMethod::kQuestPlus;
  block.min_level = table.number("min_level", 1.0001, 10.0).value_or(1.01);
  block.max_level = table.number("max_level", 1.0001, 10.0).value_or(2.0);
  block.trials = table.integer("trials", 1, 1000).value_or(40);
  block.quest_levels = table.integer("stimuli", 2, 200).value_or(30);
  block.quest_thresholds = table.integer("thresholds", 2, 400).value_or(40);
  block.lapse = table.number("lapse", 0.0, 0.2).value_or(0.03);
  if (!(block.max_level >= block.min_level * 1.01)) {
    table.fail("max_level", "must be at least 1 % above min_level");
  }
}

void parse_jnd(const Table& table, Block& block, const Campaign& campaign) {
  table.allow_only({"name", "type", "parameter", "method", "levels", "repetitions", "down",
                    "start_level", "step_factor", "min_level", "max_level", "trials", "stimuli",
                    "thresholds", "lapse"});
  block.parameter = table.string("parameter").value_or("");
  if (block.parameter.empty())
    table.fail("parameter", "missing: the parameter whose JND is measured");
  try {
    apply_steps(base_model(campaign), {Step{block.parameter, 1.05}});
  } catch (const std::invalid_argument& wrong) {
    table.fail("parameter", wrong.what());
  }
  const std::string method = table.string("method").value_or("constant");
  if (method != "quest+") {
    for (const char* key : {"stimuli", "thresholds", "lapse"}) {
      if (table.get(key)) table.fail(key, "is an option of method = \"quest+\" only");
    }
  }
  if (method == "constant") {
    block.method = JndMethod::kConstantStimuli;
    const toml::node* levels = table.get("levels");
    if (!levels || !levels->is_array() || levels->as_array()->empty()) {
      table.fail(
          "levels",
          "constant stimuli need levels: an array of factors above 1, e.g. [1.05, 1.1, 1.2]");
    }
    for (const toml::node& item : *levels->as_array()) {
      const std::optional<double> value = item.value<double>();
      if (!value || !(*value > 1.0 && *value <= 10.0)) {
        table.fail("levels", "each level is a factor above 1 and at most 10");
      }
      block.levels.push_back(*value);
    }
    block.repetitions = table.integer("repetitions", 1, 1000).value_or(1);
  } else if (method == "staircase") {
    block.method = JndMethod::kStaircase;
    block.down = table.integer("down", 1, 4).value_or(2);
    block.start_level = table.number("start_level", 1.0001, 10.0).value_or(1.4);
    block.step_factor = table.number("step_factor", 1.01, 10.0).value_or(1.5);
    block.min_level = table.number("min_level", 1.0001, 10.0).value_or(1.01);
    block.max_level = table.number("max_level", 1.0001, 10.0).value_or(3.0);
    block.trials = table.integer("trials", 1, 1000).value_or(20);
    if (!(block.min_level <= block.start_level && block.start_level <= block.max_level)) {
      table.fail("start_level", "must lie between min_level and max_level");
    }
  } else if (method == "quest+") {
    parse_quest_plus(table, block);
  } else {
    table.fail("method", "must be constant, staircase or quest+, not '" + method + "'");
  }
}

Block parse_block(const Table& table, const Campaign& campaign) {
  Block block;
  block.line = table.line();
  block.name = table.string("name").value_or("");
  if (!is_name(block.name)) {
    table.fail("name", "each block needs a name of letters, digits, '-' and '_' (at most 40)");
  }
  const std::string type = table.string("type").value_or("");
  if (type == "tune") {
    block.type = BlockType::kTune;
    table.allow_only({"name", "type", "start_spread"});
    block.start_spread = table.number("start_spread", 0.0, 1.0).value_or(0.2);
    if (campaign.model != ModelKind::kSensory) {
      table.fail(
          "type",
          "tune moves the perceptual controls of the sensory model (campaign.model = \"sensory\")");
    }
  } else if (type == "pair") {
    block.type = BlockType::kPair;
    table.allow_only({"name", "type", "question", "pairs", "repetitions"});
    const std::string question = table.string("question").value_or("preference");
    const std::optional<Question> asked = Question::parse(question);
    if (asked && (asked->is_preference() || asked->kind == QuestionKind::kIdentifyReal)) {
      block.question = asked->kind;
    } else {
      table.fail("question",
                 "must be preference, preference-2ac or identify-real, not '" + question + "'");
    }
    block.pairs = parse_pairs(table, campaign);
    block.repetitions = table.integer("repetitions", 1, 1000).value_or(1);
    if (block.question == QuestionKind::kIdentifyReal) {
      for (const auto& [a, b] : block.pairs) {
        if ((campaign.find_variant(a)->kind == Variant::Kind::kReal) ==
            (campaign.find_variant(b)->kind == Variant::Kind::kReal)) {
          table.fail("pairs",
                     "identify-real needs the real door in every pair ('" + a + "', '" + b + "')");
        }
      }
    }
  } else if (type == "rating") {
    block.type = BlockType::kRating;
    table.allow_only({"name", "type", "attributes", "scale", "repetitions", "pairs"});
    block.attributes = table.strings("attributes").value_or(std::vector<std::string>{});
    if (block.attributes.empty())
      table.fail("attributes", "missing: the attributes rated, e.g. [\"heavy-light\"]");
    for (const std::string& attribute : block.attributes) {
      if (!is_name(attribute))
        table.fail("attributes", "'" + attribute + "' is not letters, digits, '-' and '_'");
    }
    block.scale = table.integer("scale", 2, 100).value_or(7);
    block.repetitions = table.integer("repetitions", 1, 1000).value_or(1);
    block.pairs = parse_pairs(table, campaign);
    if (campaign.variants.size() < 2) table.fail("type", "rating needs at least two variants");
  } else if (type == "jnd") {
    block.type = BlockType::kJnd;
    parse_jnd(table, block, campaign);
  } else {
    table.fail("type", "must be tune, pair, rating or jnd, not '" + type + "'");
  }
  return block;
}

void parse_participants(const Table& table, Campaign& campaign) {
  table.allow_only({"ids", "count", "prefix"});
  if (const auto ids = table.strings("ids")) {
    if (table.get("count")) table.fail("count", "give ids or count, not both");
    campaign.participants = *ids;
  } else {
    const int count = table.integer("count", 1, 999).value_or(0);
    if (count == 0) table.fail("", "needs ids = [\"P01\", ...] or count = N");
    const std::string prefix = table.string("prefix").value_or("P");
    for (int i = 1; i <= count; ++i) {
      std::string number = std::to_string(i);
      if (number.size() < 2) number.insert(0, 2 - number.size(), '0');
      campaign.participants.push_back(prefix + number);
    }
  }
  std::set<std::string> seen;
  for (const std::string& id : campaign.participants) {
    if (const std::string problem = participant_id_problem(id); !problem.empty()) {
      table.fail(table.get("ids") ? "ids" : "prefix", problem);
    }
    if (!seen.insert(id).second) table.fail("ids", "participant '" + id + "' is listed twice");
  }
}

void parse_head(const Table& head, Campaign& campaign, const std::filesystem::path& folder) {
  head.allow_only(
      {"name", "seed", "model", "base", "real_rig", "presentation_s", "simulated_presentation_s"});
  campaign.name = head.string("name").value_or("campaign");
  if (const toml::node* seed = head.get("seed")) {
    if (!seed->is_integer() || seed->as_integer()->get() < 0)
      head.fail("seed", "must be a whole number >= 0");
    campaign.seed = static_cast<std::uint64_t>(seed->as_integer()->get());
  }
  const std::string model = head.string("model").value_or("sensory");
  const std::optional<ModelKind> kind = parse_model_kind(model);
  if (!kind) head.fail("model", "must be sensory or physical, not '" + model + "'");
  campaign.model = *kind;
  if (const auto base = head.string("base"); base && !base->empty())
    campaign.base_file = folder / *base;
  if (const auto rig = head.string("real_rig"); rig && !rig->empty())
    campaign.real_rig = folder / *rig;
  campaign.presentation_s = head.number("presentation_s", 0.1, 600.0).value_or(8.0);
  campaign.simulated_presentation_s =
      head.number("simulated_presentation_s", 0.1, 600.0).value_or(1.0);
  try {
    (void)base_model(campaign);
  } catch (const std::exception& wrong) {
    head.fail("base", wrong.what());
  }
}

}  // namespace

std::string_view to_string(BlockType type) {
  switch (type) {
    case BlockType::kTune:
      return "tune";
    case BlockType::kPair:
      return "pair";
    case BlockType::kRating:
      return "rating";
    case BlockType::kJnd:
      return "jnd";
  }
  return "?";
}

const Variant* Campaign::find_variant(std::string_view wanted) const {
  for (const Variant& variant : variants) {
    if (variant.name == wanted) return &variant;
  }
  return nullptr;
}

Campaign parse_campaign(std::string_view text, std::string_view source,
                        const std::filesystem::path& folder) {
  Campaign campaign;
  campaign.source = std::string(source);
  campaign.text = std::string(text);
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& error) {
    throw CampaignError(campaign.source + ":" + std::to_string(error.source().begin.line) + ": " +
                        std::string(error.description()));
  }
  const Table top(campaign.source, root, "", 1);
  top.allow_only({"campaign", "variants", "participants", "blocks"});
  parse_head(*top.child("campaign", true), campaign, folder);
  const Table variants = *top.child("variants", true);
  std::vector<std::pair<int, std::string>> order;
  for (auto&& [key, node] : variants.table()) {
    Variant variant = read_variant(variants, std::string(key.str()), node, folder);
    if (variant.kind == Variant::Kind::kReal && campaign.real_rig.empty()) {
      variants.fail(key.str(), "the real door needs campaign.real_rig (the bench's rig file)");
    }
    if (variant.kind != Variant::Kind::kReal) {
      try {
        (void)variant_model(campaign, variant);
      } catch (const std::exception& wrong) {
        variants.fail(key.str(), wrong.what());
      }
    }
    campaign.variants.push_back(std::move(variant));
    order.emplace_back(line_of(node), campaign.variants.back().name);
  }
  // In file order (toml++ keeps keys sorted).
  std::stable_sort(campaign.variants.begin(), campaign.variants.end(),
                   [&](const Variant& a, const Variant& b) {
                     auto line = [&](const Variant& v) {
                       for (const auto& [l, n] : order)
                         if (n == v.name) return l;
                       return 0;
                     };
                     return line(a) < line(b);
                   });
  if (campaign.variants.empty()) variants.fail("", "names no variant");
  parse_participants(*top.child("participants", true), campaign);
  const toml::node* blocks = root.get("blocks");
  if (!blocks || !blocks->is_array_of_tables() || blocks->as_array()->empty()) {
    top.fail("blocks", "missing: at least one [[blocks]] table");
  }
  std::set<std::string> names;
  int index = 0;
  for (const toml::node& node : *blocks->as_array()) {
    const Table table(campaign.source, *node.as_table(), "blocks[" + std::to_string(++index) + "]",
                      line_of(node));
    Block block = parse_block(table, campaign);
    if (!names.insert(block.name).second)
      table.fail("name", "block '" + block.name + "' is named twice");
    campaign.blocks.push_back(std::move(block));
  }
  return campaign;
}

Campaign read_campaign(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CampaignError(path.string() + ": cannot open for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_campaign(text, path.string(), path.parent_path());
}

std::string participant_id_problem(std::string_view id) {
  const std::string quoted = std::string("'").append(id).append("'");
  if (id.empty()) return "a participant id must not be empty";
  if (id.find('@') != std::string_view::npos) {
    return "participant id " + quoted +
           " looks like an e-mail address; use a pseudonymous id such as P07";
  }
  if (id.find_first_of(" \t") != std::string_view::npos) {
    return "participant id " + quoted +
           " looks like a name (it holds a space); use a pseudonymous id such as P07";
  }
  if (id.size() > 32) return "participant id " + quoted + " is longer than 32 characters";
  for (char c : id) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_';
    if (!ok) return "participant id " + quoted + " may hold only letters, digits, '-' and '_'";
  }
  for (std::size_t i = 0; i + 2 < id.size(); ++i) {
    const bool capital = id[i] >= 'A' && id[i] <= 'Z';
    const bool lower_after =
        id[i + 1] >= 'a' && id[i + 1] <= 'z' && id[i + 2] >= 'a' && id[i + 2] <= 'z';
    if (capital && lower_after) {
      return "participant id " + quoted +
             " looks like a name (a capitalised word); use a pseudonymous id such as P07";
    }
  }
  if (id.find_first_of("0123456789") == std::string_view::npos) {
    return "participant id " + quoted +
           " has no digit (a word alone may be a name); use a pseudonymous id such as P07";
  }
  return "";
}

std::vector<Step> parse_steps(std::string_view text) {
  std::vector<Step> steps;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    std::string_view item = text.substr(at, comma - at);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    const std::size_t star = item.find('*');
    const std::string expected =
        "expected steps such as \"J*1.2\" or \"heaviness*1.2,latch_effort*0.7\", got \"" +
        std::string(text) + "\"";
    if (star == std::string_view::npos || star == 0) throw std::invalid_argument(expected);
    Step step;
    step.target = std::string(item.substr(0, star));
    const std::string factor(item.substr(star + 1));
    std::size_t used = 0;
    try {
      step.factor = std::stod(factor, &used);
    } catch (const std::exception&) {
      throw std::invalid_argument(expected);
    }
    if (used != factor.size() || !(step.factor > 0.0) || !std::isfinite(step.factor)) {
      throw std::invalid_argument(expected + " (a factor is a number above 0)");
    }
    steps.push_back(step);
    at = comma + 1;
  }
  return steps;
}

std::string steps_text(const std::vector<Step>& steps) {
  std::string text;
  for (const Step& step : steps) {
    text += (text.empty() ? "" : ",") + step.target + "*" + format_readable(step.factor);
  }
  return text;
}

DoorModel base_model(const Campaign& campaign) {
  return load_model(campaign.model, campaign.base_file, "");
}

DoorModel apply_steps(const DoorModel& model, const std::vector<Step>& steps) {
  DoorModel result = model;
  for (const Step& step : steps) {
    const std::string what = "step " + step.target + "*" + format_readable(step.factor);
    if (const std::optional<perceptual::Control> control = perceptual::find(step.target)) {
      if (result.kind() != ModelKind::kSensory) {
        throw std::invalid_argument(what + ": the perceptual controls act on the sensory model");
      }
      try {
        result =
            perceptual::set(result, *control, perceptual::read(result, *control) * step.factor);
      } catch (const std::invalid_argument& wrong) {
        throw std::invalid_argument(what + ": " + wrong.what());
      }
      // The model does not hold its values to the bounds: a step must.
      for (int i = 0; i < result.parameter_count(); ++i) {
        const double value = result.parameter_values()[i];
        const Bounds bounds = result.parameter_bounds()[i];
        if (value < bounds.lower || value > bounds.upper) {
          throw std::invalid_argument(what + ": " + result.parameter_name(i) + " would be " +
                                      format_readable(value) + ", outside its bounds " +
                                      format_readable(bounds.lower) + ".." +
                                      format_readable(bounds.upper));
        }
      }
      continue;
    }
    const std::optional<int> index = result.find_parameter(step.target);
    if (!index) {
      std::string names;
      for (const perceptual::ControlInfo& info : perceptual::controls())
        names += std::string(info.name) + ", ";
      for (int i = 0; i < result.base_parameter_count(); ++i)
        names += (i ? ", " : "") + result.parameter_name(i);
      throw std::invalid_argument(what + ": '" + step.target +
                                  "' is neither a perceptual control nor a parameter of the " +
                                  std::string(to_string(result.kind())) + " model (" + names + ")");
    }
    std::vector<double> values(result.parameter_values().begin(), result.parameter_values().end());
    values[*index] *= step.factor;
    const Bounds bounds = result.parameter_bounds()[*index];
    if (values[*index] < bounds.lower || values[*index] > bounds.upper) {
      throw std::invalid_argument(what + ": " + step.target + " would be " +
                                  format_readable(values[*index]) + ", outside its bounds " +
                                  format_readable(bounds.lower) + ".." +
                                  format_readable(bounds.upper));
    }
    try {
      result = result.with_parameter_values(values);
    } catch (const std::invalid_argument& wrong) {
      throw std::invalid_argument(what + ": " + wrong.what());
    }
  }
  return result;
}

DoorModel variant_model(const Campaign& campaign, const Variant& variant) {
  switch (variant.kind) {
    case Variant::Kind::kBase:
      return base_model(campaign);
    case Variant::Kind::kFile:
      return load_model(campaign.model, variant.file, "");
    case Variant::Kind::kSteps:
      return apply_steps(base_model(campaign), variant.steps);
    case Variant::Kind::kReal:
      break;
  }
  throw std::invalid_argument("variant '" + variant.name +
                              "' is the real door on the bench, not a model");
}

}  // namespace doorbench::study
