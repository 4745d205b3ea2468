// The --map syntax of doorbench import (acquisition/session/map_syntax.h).
#include "acquisition/session/map_syntax.h"

#include <algorithm>
#include <stdexcept>

#include "acquisition/session/recording_csv.h"

namespace doorbench {

std::vector<std::size_t> unescaped_positions(const std::string& text, char separator) {
  std::vector<std::size_t> positions;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\\') {
      ++i;
    } else if (text[i] == separator) {
      positions.push_back(i);
    }
  }
  return positions;
}

std::string unescaped(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\\' && i + 1 < text.size()) ++i;
    out += text[i];
  }
  return out;
}

std::vector<MapItemText> split_map_items(const std::string& text) {
  std::vector<MapItemText> items;
  std::vector<std::size_t> commas = unescaped_positions(text, ',');
  commas.push_back(text.size());
  std::size_t start = 0;
  for (std::size_t comma : commas) {
    MapItemText item;
    item.item = text.substr(start, comma - start);
    const std::vector<std::size_t> equals_at = unescaped_positions(item.item, '=');
    if (!equals_at.empty() && equals_at.front() > 0) {
      item.target = item.item.substr(0, equals_at.front());
      item.text = item.item.substr(equals_at.front() + 1);
    }
    items.push_back(std::move(item));
    start = comma + 1;
  }
  return items;
}

void check_map_target(const std::string& target, const std::vector<std::string>& earlier) {
  if (target != "force" && target != "angle" && target != "rate" && target != "time" &&
      !has_unit_suffix(target)) {
    throw std::invalid_argument("--map target '" + target +
                                "' is not force, angle, rate, time or a column name with a "
                                "unit suffix (e.g. inclinometer_angle_rad)");
  }
  if (std::find(earlier.begin(), earlier.end(), target) != earlier.end()) {
    throw std::invalid_argument("--map names target '" + target + "' twice");
  }
}

}  // namespace doorbench
