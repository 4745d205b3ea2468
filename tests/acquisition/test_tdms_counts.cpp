// The TDMS reader checks the counts a file claims against the bytes left before believing
// them (4294967295 properties claimed are refused as such, not read as "type unknown type
// 0x14"), and calls a 0-byte file empty rather than "no channel a/b (the file has none)".
#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "acquisition/session/tdms.h"
#include "fixtures/temp_dir.h"
#include "tests/support/tdms_error.h"
#include "tests/support/tdms_writer.h"

namespace doorbench {
namespace {

using namespace testing::tdms;

// One segment with the file object "/" (no raw data, no properties): the object count at
// byte 28, the path at 32 (5 bytes), the raw index at 37, the property count at 41.
std::vector<std::uint8_t> file_object_segment() {
  std::vector<std::uint8_t> bytes;
  const auto put = [&bytes](std::uint64_t value, int size) {
    for (int i = 0; i < size; ++i) bytes.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  };
  for (const char c : {'T', 'D', 'S', 'm'}) bytes.push_back(static_cast<std::uint8_t>(c));
  put(kTocMetaData | kTocNewObjList, 4);
  put(4713, 4);
  put(17, 8);  // the next segment: after the 17 bytes of metadata
  put(17, 8);  // no raw data
  put(1, 4);   // one object
  put(1, 4);   // its path "/"
  bytes.push_back('/');
  put(0xFFFFFFFFu, 4);  // no raw data index
  put(0, 4);            // no properties
  return bytes;
}

void put32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t value) {
  std::memcpy(bytes.data() + at, &value, 4);
}

}  // namespace

TEST_CASE("TDMS: counts a file claims are checked against the bytes left", "[tdms]") {
  std::vector<std::uint8_t> bytes = file_object_segment();
  REQUIRE(bytes.size() == 45);
  CHECK(error_of(bytes) == "(no error)");
  put32(bytes, 41, 0xFFFFFFFFu);
  CHECK(error_of(bytes) ==
        "mem.tdms: segment 1 (byte 41): claims 4294967295 properties, but only 0 bytes are left "
        "(each takes at least 9)");
  bytes = file_object_segment();
  put32(bytes, 28, 0xFFFFFFFFu);
  CHECK(error_of(bytes) ==
        "mem.tdms: segment 1 (byte 28): claims 4294967295 objects, but only 13 bytes are left "
        "(each takes at least 12)");
}

TEST_CASE("TDMS: a 0-byte file is called empty", "[tdms]") {
  const testing::TempDir dir("tdms-empty");
  const auto path = dir.write("empty.tdms", "");
  CHECK_THROWS_WITH(read_tdms(path), path.string() + ": the file is empty (0 bytes)");
}

}  // namespace doorbench
