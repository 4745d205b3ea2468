#pragma once
// The rig file's TOML reading (acquisition/rig/ only; rig_toml.cpp, and the readers of the
// tables in rig_file.cpp, rig_channels.cpp and rig_triggers.cpp): a Section is one table
// with its dotted path and line, whose accessors check each key's type and range and end
// the parse with a RigError `FILE:LINE: KEY: what is wrong` (docs/rig-format.md); the text
// helpers of the messages; the readers' declarations in the order parse_rig() calls them.
// Single-threaded use of one parse; the helpers are pure.
#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "core/number_format.h"

namespace doorbench::rig_detail {

// Upper bounds on what a rig can ask for (docs/rig-format.md, "Limits"): beyond them a
// recording would exhaust memory or disk, or run for longer than anyone records a door.
inline constexpr double kMaxRecordingS = 86400.0;  // a day, as `record --duration-s`

// `text` in double quotes, for the messages.
std::string in_quotes(std::string_view text);

// "a, b, c".
std::string joined(std::span<const std::string_view> items);

bool one_of(std::string_view value, std::span<const std::string_view> allowed);

// The line of a value or a region (1 when the parser gives none).
int line_of(const toml::source_region& region);
int line_of(const toml::node& node);

// Whether `a` comes before `b` in the file.
bool before(const toml::source_position& a, const toml::source_position& b);

// "a table", "an integer", ...: a value's type as the messages name it.
std::string type_name(const toml::node& node);

// Letters, digits and underscores, not empty.
bool is_name(std::string_view name);

class Failer {
 public:
  explicit Failer(std::string_view source) : source_(source) {}
  [[noreturn]] void fail(int line, std::string_view key, std::string_view what) const {
    throw RigError(source_ + ":" + std::to_string(line) + ": " + std::string(key) + ": " +
                   std::string(what));
  }

 private:
  std::string source_;
};

// One TOML table of the rig with its dotted path (for messages) and its line.
class Section {
 public:
  Section(const Failer& failer, const toml::table& table, std::string path, int line)
      : failer_(&failer), table_(&table), path_(std::move(path)), line_(line) {}

  const std::string& path() const { return path_; }
  int line() const { return line_; }
  std::string key_path(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }
  const toml::node* find(std::string_view key) const { return table_->get(key); }
  // The line of `key`'s value, or the table's line when the key is absent.
  int line_of_key(std::string_view key) const {
    const toml::node* node = find(key);
    return node ? line_of(*node) : line_;
  }
  [[noreturn]] void fail(std::string_view key, std::string_view what) const {
    failer_->fail(line_of_key(key), key_path(key), what);
  }
  // At the table itself: its path and line.
  [[noreturn]] void fail_here(std::string_view what) const { failer_->fail(line_, path_, what); }
  [[noreturn]] void fail_at(const toml::node& node, std::string_view key,
                            std::string_view what) const {
    failer_->fail(line_of(node), key_path(key), what);
  }

  // The table's keys in file order.
  std::vector<std::pair<const toml::key*, const toml::node*>> entries() const {
    std::vector<std::pair<const toml::key*, const toml::node*>> result;
    for (auto&& [key, node] : *table_) result.emplace_back(&key, &node);
    std::stable_sort(result.begin(), result.end(), [](const auto& a, const auto& b) {
      return before(a.first->source().begin, b.first->source().begin);
    });
    return result;
  }

  // Rejects the first key (in file order) that is not in `allowed`.
  void allow_only(std::span<const std::string_view> allowed) const {
    for (const auto& [key, node] : entries()) {
      if (!one_of(key->str(), allowed)) {
        failer_->fail(line_of(key->source()), key_path(key->str()),
                      "unknown key; valid keys: " + joined(allowed));
      }
    }
  }
  void allow_only(std::initializer_list<std::string_view> allowed) const {
    allow_only(std::span<const std::string_view>(allowed.begin(), allowed.size()));
  }

  std::optional<std::string> string(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_string()) fail(key, "must be a string, not " + type_name(*node));
    std::string value = node->as_string()->get();
    if (value.empty()) fail(key, "must not be empty");
    return value;
  }
  std::string required_string(std::string_view key) const {
    std::optional<std::string> value = string(key);
    if (!value) fail(key, "missing required key");
    return *value;
  }
  // A string that must be one of `allowed`; `what` names the kind of value.
  std::string choice(std::string_view key, std::span<const std::string_view> allowed,
                     std::string_view what, std::optional<std::string_view> fallback) const {
    std::optional<std::string> value = string(key);
    if (!value) {
      if (!fallback) fail(key, "missing required key");
      return std::string(*fallback);
    }
    if (!one_of(*value, allowed)) {
      fail(key, in_quotes(*value) + " is not " + std::string(what) + "; valid: " + joined(allowed));
    }
    return *value;
  }

  std::optional<double> number(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    return number_value(*node, key);
  }
  double number_value(const toml::node& node, std::string_view key) const {
    double value = 0;
    if (node.is_integer()) {
      value = static_cast<double>(node.as_integer()->get());
    } else if (node.is_floating_point()) {
      value = node.as_floating_point()->get();
    } else {
      fail_at(node, key, "must be a number, not " + type_name(node));
    }
    if (!std::isfinite(value)) {
      fail_at(node, key, "must be a finite number (got " + format_number(value) + ")");
    }
    return value;
  }

  std::optional<std::int64_t> integer(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_integer()) fail(key, "must be an integer, not " + type_name(*node));
    return node->as_integer()->get();
  }

  std::optional<bool> boolean(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_boolean()) fail(key, "must be true or false, not " + type_name(*node));
    return node->as_boolean()->get();
  }

  // `key = [min, max]` in volts, min < max.
  std::optional<std::pair<double, double>> range(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    const toml::array* array = node->as_array();
    if (!array || array->size() != 2 || !(*array)[0].is_number() || !(*array)[1].is_number()) {
      fail(key, "must be [min, max], two numbers in volts");
    }
    const double min = number_value((*array)[0], key);
    const double max = number_value((*array)[1], key);
    if (!(min < max)) {
      fail(key, "min " + format_number(min) + " V must be below max " + format_number(max) + " V");
    }
    return std::pair{min, max};
  }

  std::optional<Section> table(std::string_view key) const {
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    if (!node->is_table()) fail(key, "must be a table, not " + type_name(*node));
    return Section(*failer_, *node->as_table(), key_path(key), line_of(*node));
  }

  // `[[key]]`: the array's tables (empty when the key is absent).
  std::vector<Section> array_of_tables(std::string_view key) const {
    std::vector<Section> result;
    const toml::node* node = find(key);
    if (!node) return result;
    const toml::array* array = node->as_array();
    if (!array) {
      fail(key,
           "must be an array of tables ([[" + std::string(key) + "]]), not " + type_name(*node));
    }
    for (std::size_t i = 0; i < array->size(); ++i) {
      const std::string element_path = key_path(key) + "[" + std::to_string(i) + "]";
      const toml::node& element = (*array)[i];
      if (!element.is_table()) {
        failer_->fail(line_of(element), element_path, "must be a table, not " + type_name(element));
      }
      result.emplace_back(*failer_, *element.as_table(), element_path, line_of(element));
    }
    return result;
  }

 private:
  const Failer* failer_;
  const toml::table* table_;
  std::string path_;
  int line_;
};

struct ParsedChannels {
  std::vector<RigChannel> channels;
  std::vector<int> backend_lines;  // per channel: the line of its backend key
};

// The tables of the rig, read and checked (rig_channels.cpp).
void read_modbus_devices(const Section& root, RigDefinition& rig);
ParsedChannels read_channels(const Section& root, const RigDefinition& rig, const Failer& failer);
// The multiplexed converter must finish a scan within one sample period; then the DAQ
// model's own validation, as a last guard.
void check_scan_fits(const Section& root, const RigDefinition& rig, const Failer& failer);

// The triggers and the recording (rig_triggers.cpp).
std::vector<RigTrigger> read_triggers(const Section& root, const RigDefinition& rig);
void check_start_trigger(const Section& root, const RigDefinition& rig);
void read_recording(const Section& root, RigDefinition& rig);

}  // namespace doorbench::rig_detail
