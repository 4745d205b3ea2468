#include <catch2/catch.hpp>

#include "study/trials_table.h"

using doorbench::study::csv_row;
using doorbench::study::parse_trials_table;
using doorbench::study::TrialsTableError;

namespace {
const char* kHeader = "participant,block,trial,question,first,second,answer";
}

TEST_CASE("a trials table keeps every column by name and reads quoted fields", "[study]") {
  const std::string text = std::string(kHeader) + ",notes\r\n" +
                           "P01,pair,1,preference-2ac,A,B,same,\"said \"\"hm\"\", then same\"\n"
                           "\n"
                           "P01,rating,2,rating:heavy:7,A,B,3 5,\"two\nlines\"\n";
  const auto table = parse_trials_table(text, "t.csv");
  REQUIRE(table.rows.size() == 2);
  CHECK(table.value(0, "answer") == "same");
  CHECK(table.value(0, "notes") == "said \"hm\", then same");
  CHECK(table.value(1, "answer") == "3 5");
  CHECK(table.value(1, "notes") == "two\nlines");
  CHECK(table.line_numbers == std::vector<int>{2, 4});
}

TEST_CASE("a written row reads back as the same fields", "[study]") {
  const std::vector<std::string> fields{"P02", "pair", "3", "preference", "a,b", "\"q\"", " x"};
  const auto table = parse_trials_table(std::string(kHeader) + "\n" + csv_row(fields), "t.csv");
  REQUIRE(table.rows.size() == 1);
  CHECK(table.rows[0] == fields);
}

TEST_CASE("a trials table that breaks the format is refused with its line", "[study]") {
  const std::string header(kHeader);
  CHECK_THROWS_WITH(parse_trials_table("participant,block,trial\n", "t.csv"),
                    "t.csv:1: no column 'question' (the header has: participant,block,trial)");
  CHECK_THROWS_WITH(parse_trials_table(header + ",trial\n", "t.csv"),
                    "t.csv:1: column 'trial' is named twice");
  CHECK_THROWS_WITH(parse_trials_table(header + "\nP1,pair,1,preference,A,B\n", "t.csv"),
                    "t.csv:2: 6 fields, the header has 7");
  CHECK_THROWS_WITH(parse_trials_table(header + "\nP1,pair,1,preference,A,B,\"1\n", "t.csv"),
                    "t.csv:2: a quoted field is not closed");
  CHECK_THROWS_WITH(parse_trials_table(header + "\nP1,pa\"ir,1,preference,A,B,1\n", "t.csv"),
                    "t.csv:2: a double quote inside an unquoted field (quote the whole field)");
  CHECK_THROWS_WITH(parse_trials_table("", "t.csv"),
                    "t.csv: no header row (the file holds no text)");
}
