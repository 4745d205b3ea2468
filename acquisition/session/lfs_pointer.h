#pragma once
// Git LFS pointers: the small text file a repository without Git LFS (or a clone made without
// it) holds in place of a large file, as the Git LFS specification writes it:
//
//   version https://git-lfs.github.com/spec/v1
//   oid sha256:4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393
//   size 12345
//
// A reader that meets one says so instead of reporting the text as a damaged file.
// Header-only; no state.
#include <algorithm>
#include <string>
#include <string_view>

#include "acquisition/session/printable.h"

namespace doorbench {

// "" unless `contents` (a whole file, or its first bytes) is a Git LFS pointer; else what it
// is: "this is a Git LFS pointer to a file of 12345 bytes (oid sha256:4d7a2146...), not the
// file itself: fetch it (git lfs pull) and import that".
inline std::string lfs_pointer_description(std::string_view contents) {
  constexpr std::string_view kVersions[] = {"version https://git-lfs.github.com/spec/",
                                            "version https://hawser.github.com/spec/"};
  bool pointer = false;
  for (std::string_view version : kVersions) {
    pointer = pointer || contents.substr(0, version.size()) == version;
  }
  if (!pointer) return "";
  // A line "KEY VALUE" of the pointer; "" when there is none.
  const auto value_of = [contents](std::string_view key) -> std::string {
    std::size_t at = 0;
    while (at < contents.size()) {
      const std::size_t end = std::min(contents.find('\n', at), contents.size());
      const std::string_view line = contents.substr(at, end - at);
      if (line.size() > key.size() && line.substr(0, key.size()) == key &&
          line[key.size()] == ' ') {
        return printable(line.substr(key.size() + 1, 80));
      }
      at = end + 1;
    }
    return "";
  };
  const std::string size = value_of("size");
  std::string oid = value_of("oid");
  if (oid.size() > 15) oid = oid.substr(0, 15) + "...";
  std::string what = "this is a Git LFS pointer";
  if (!size.empty()) what += " to a file of " + size + " bytes";
  if (!oid.empty()) what += " (oid " + oid + ")";
  return what + ", not the file itself: fetch it (git lfs pull) and import that";
}

}  // namespace doorbench
