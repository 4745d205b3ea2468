#pragma once
// Checks the SVG doorbench wrote under some files or folders with tests/support/check_svg.py
// (Debian's /usr/bin/python3, standard library): every .svg file and every <svg> inside an
// .html file parses as XML, carries no stray text, and each legend entry has its key (a
// <line>) in the colour of its series' line. The tests of each verb that writes SVG (demo,
// fit, loop, spec, calibrate and calibration certificate) call it on their outputs.
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace doorbench::testing {

struct SvgCheck {
  int status = -1;         // the script's exit status: 0 when every SVG passed
  std::string output;      // one line per problem, then "checked N SVG, M legend entries"
  int svgs = 0;            // N
  int legend_entries = 0;  // M
};

inline SvgCheck check_svgs(const std::vector<std::filesystem::path>& paths) {
  std::string command = "/usr/bin/python3 '" DOORBENCH_SOURCE_DIR "/tests/support/check_svg.py'";
  for (const std::filesystem::path& path : paths) command += " '" + path.string() + "'";
  SvgCheck check;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return check;
  char chunk[4096];
  for (std::size_t n; (n = std::fread(chunk, 1, sizeof chunk, pipe)) > 0;)
    check.output.append(chunk, n);
  const int status = ::pclose(pipe);
  check.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const std::size_t last = check.output.rfind("checked ");
  if (last != std::string::npos) {
    std::sscanf(check.output.c_str() + last, "checked %d SVG, %d legend entries", &check.svgs,
                &check.legend_entries);
  }
  return check;
}

}  // namespace doorbench::testing
