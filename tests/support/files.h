#pragma once
// Reading a whole file in a test. Throws std::runtime_error naming the file when it cannot
// be opened, so that a test never compares against the empty text of a missing file.
#include <filesystem>
#include <string>

namespace doorbench::testing {

// The file's bytes, unchanged (binary mode).
std::string read_file(const std::filesystem::path& path);

}  // namespace doorbench::testing
