#pragma once
// The syntax of `doorbench import --map`, shared by TDMS files (TARGET=GROUP/CHANNEL,
// acquisition/session/tdms.h) and CSV files (TARGET=COLUMN, acquisition/session/import_units.h):
// items separated by commas, each TARGET=NAME; inside a name '\,', '\=', '\/' and '\\' stand
// for ',', '=', '/' and '\'.
//
// Thread safety: free functions without shared state.
#include <cstddef>
#include <string>
#include <vector>

namespace doorbench {

// One item as given: `target` before its first unescaped '=' (empty when there is none or it
// starts the item), `text` after it with escapes kept, `item` the whole.
struct MapItemText {
  std::string target, text, item;
};
// `text` split at its unescaped commas, each item at its first unescaped '='.
std::vector<MapItemText> split_map_items(const std::string& text);

// The positions of `separator` in `text` not escaped by a backslash.
std::vector<std::size_t> unescaped_positions(const std::string& text, char separator);
// `text` with each "\x" as "x"; a backslash at the end is kept.
std::string unescaped(const std::string& text);

// Checks a map's target against the targets before it: force, angle, rate, time or a column
// name with a unit suffix, and not named twice. Throws std::invalid_argument
// "--map target 'X' is not force, angle, rate, time or a column name with a unit suffix (e.g.
// inclinometer_angle_rad)", "--map names target 'X' twice".
void check_map_target(const std::string& target, const std::vector<std::string>& earlier);

}  // namespace doorbench
