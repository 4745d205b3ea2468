#include "tests/support/files.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace doorbench::testing {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot be opened for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace doorbench::testing
