// The contracts of core's shared helpers: JSON numbers, HTML escaping, percentiles, percents
// and seeded draws.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/html_escape.h"
#include "core/json_number.h"
#include "core/number_format.h"
#include "core/percentile.h"
#include "core/seeded_random.h"
#include "core/time_text.h"

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

TEST_CASE("json_number: a finite value is itself, NaN and infinities are null", "[core]") {
  CHECK(doorbench::json_number(0.25).dump() == "0.25");
  CHECK(doorbench::json_number(-3.0).dump() == "-3.0");
  CHECK(doorbench::json_number(std::nan("")).is_null());
  CHECK(doorbench::json_number(kInf).is_null());
  CHECK(doorbench::json_number(-kInf).is_null());
  CHECK(doorbench::json_number(std::optional<double>{}).is_null());
  CHECK(doorbench::json_number(std::optional<double>{1.5}).dump() == "1.5");
  const nlohmann::ordered_json ordered = {
      {"b", doorbench::json_number<nlohmann::ordered_json>(std::nan(""))},
      {"a", doorbench::json_number<nlohmann::ordered_json>(2.0)}};
  CHECK(ordered.dump() == R"({"b":null,"a":2.0})");
}

TEST_CASE("html_escape: & < > \" and ' are escaped, everything else is kept", "[core]") {
  CHECK(doorbench::html_escape("a & b") == "a &amp; b");
  CHECK(doorbench::html_escape("<tag>") == "&lt;tag&gt;");
  CHECK(doorbench::html_escape(R"(say "hi")") == "say &quot;hi&quot;");
  CHECK(doorbench::html_escape("d' > 0") == "d&#39; &gt; 0");
  CHECK(doorbench::html_escape("&amp;") == "&amp;amp;");
  CHECK(doorbench::html_escape("θ₁ = 5 °") == "θ₁ = 5 °");
  CHECK(doorbench::html_escape("").empty());
}

TEST_CASE("percentile: linear interpolation between order statistics, as R's type 7", "[core]") {
  const std::vector<double> values = {4.0, 1.0, 3.0, 2.0};
  CHECK(doorbench::percentile(values, 0.0) == 1.0);
  CHECK(doorbench::percentile(values, 1.0) == 4.0);
  CHECK(doorbench::percentile(values, 0.5) == Approx(2.5));
  // R: quantile(c(1, 2, 3, 4), 0.1) is 1.3.
  CHECK(doorbench::percentile(values, 0.1) == Approx(1.3));
  CHECK(doorbench::percentile({7.0}, 0.9) == 7.0);
  const std::vector<double> sorted = {1.0, 2.0, 3.0, 4.0};
  CHECK(doorbench::percentile_of_sorted(sorted, 0.75) == Approx(3.25));
}

TEST_CASE(
    "percentile: an empty sample or a NaN fraction gives NaN, a fraction outside [0, 1] "
    "is clamped",
    "[core]") {
  CHECK(std::isnan(doorbench::percentile({}, 0.5)));
  CHECK(std::isnan(doorbench::percentile_of_sorted({}, 0.0)));
  CHECK(std::isnan(doorbench::percentile({1.0, 2.0}, std::nan(""))));
  CHECK(doorbench::percentile({1.0, 2.0}, -0.5) == 1.0);
  CHECK(doorbench::percentile({1.0, 2.0}, 1.5) == 2.0);
}

TEST_CASE("median: the middle value, or the mean of the two middle ones, NaN when empty",
          "[core]") {
  CHECK(doorbench::median({3.0, 1.0, 2.0}) == 2.0);
  CHECK(doorbench::median({4.0, 1.0, 3.0, 2.0}) == 2.5);
  CHECK(doorbench::median({5.0}) == 5.0);
  CHECK(std::isnan(doorbench::median({})));
  const std::vector<double> values = {0.3, 9.1, -2.0, 4.4, 4.4, 7.0};
  CHECK(doorbench::median(values) == Approx(doorbench::percentile(values, 0.5)));
}

TEST_CASE("median_interval_s: the median step between consecutive times, NaN below two times",
          "[core]") {
  CHECK(doorbench::median_interval_s(std::vector<double>{0.0, 1.0, 3.0}) == 1.5);
  CHECK(doorbench::median_interval_s(std::vector<double>{0.0, 0.1, 0.2, 0.5}) == Approx(0.1));
  CHECK(doorbench::median_interval_s(std::vector<double>{0.0, 1.0, 3.0, 6.0, 10.0}) == 2.5);
  CHECK(std::isnan(doorbench::median_interval_s(std::vector<double>{1.0})));
  CHECK(std::isnan(doorbench::median_interval_s(std::vector<double>{})));
}

TEST_CASE("format_percent: a fraction as a percentage, '-' where there is no number", "[core]") {
  CHECK(doorbench::format_percent(0.123, 1) == "12.3%");
  CHECK(doorbench::format_percent(0.5, 2) == "50.00%");
  CHECK(doorbench::format_percent(std::nan(""), 1) == "-");
  CHECK(doorbench::format_percent(kInf, 1) == "-");
  CHECK(doorbench::format_signed_percent(0.123, 1) == "+12.3%");
  CHECK(doorbench::format_signed_percent(-0.005, 1) == "-0.5%");
  CHECK(doorbench::format_signed_percent(std::nan(""), 1) == "-");
  CHECK(doorbench::format_percent_at_most(0.123, 2, 10.0) == "12.30%");
  CHECK(doorbench::format_percent_at_most(10.0, 2, 10.0) == "1000.00%");
  CHECK(doorbench::format_percent_at_most(4.76e36, 2, 10.0) == "> 1000%");
  CHECK(doorbench::format_percent_at_most(kInf, 2, 10.0) == "-");
  CHECK(doorbench::format_percent_at_most(std::nan(""), 2, 10.0) == "-");
}

TEST_CASE(
    "format_readable writes a value or a limit as people write it, format_number "
    "exactly",
    "[core]") {
  CHECK(doorbench::format_readable(1e9) == "1000000000");
  CHECK(doorbench::format_readable(0.05) == "0.05");
  CHECK(doorbench::format_readable(200000) == "200000");
  CHECK(doorbench::format_readable(1.1 * 1.1) == "1.21");
  CHECK(doorbench::format_number(1.1 * 1.1) == "1.2100000000000002");
  CHECK(doorbench::format_number(1e9) == "1e+09");
}

TEST_CASE("seeded draws: the same seed gives the same numbers, in range", "[core]") {
  std::mt19937_64 a(42), b(42);
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t k = doorbench::uniform_below(a, 7);
    CHECK(k < 7);
    CHECK(k == doorbench::uniform_below(b, 7));
    const double u = doorbench::uniform_open01(a);
    CHECK(u > 0.0);
    CHECK(u < 1.0);
    CHECK(u == doorbench::uniform_open01(b));
  }
  // The first output of std::mt19937_64 seeded with 5489 is fixed by the standard, so the
  // first uniform_below of a bound far below 2^64 is that output modulo the bound.
  std::mt19937_64 standard(5489);
  CHECK(doorbench::uniform_below(standard, 1000) == 14514284786278117030ULL % 1000);
  CHECK(doorbench::mix64(0) == 0xE220A8397B1DCDAFULL);
}

TEST_CASE("seeded draws: standard_normal has mean 0 and variance 1, shuffle keeps the items",
          "[core]") {
  std::mt19937_64 random(7);
  double sum = 0.0, sum_squares = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double z = doorbench::standard_normal(random);
    sum += z;
    sum_squares += z * z;
  }
  // Four standard errors either side: the seed is fixed, so this never flickers.
  CHECK(std::abs(sum / n) < 4.0 / std::sqrt(n));
  CHECK(std::abs(sum_squares / n - 1.0) < 4.0 * std::sqrt(2.0 / n));
  std::vector<int> items = {1, 2, 3, 4, 5, 6, 7, 8};
  doorbench::shuffle_in_place(items, random);
  std::vector<int> sorted = items;
  std::sort(sorted.begin(), sorted.end());
  CHECK(sorted == std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8});
}

TEST_CASE("iso8601_utc_text: seconds since 1970 in UTC, with the fraction's leading zeros",
          "[core]") {
  using doorbench::iso8601_utc_text;
  CHECK(iso8601_utc_text(0) == "1970-01-01T00:00:00Z");
  CHECK(iso8601_utc_text(1700000000) == "2023-11-14T22:13:20Z");
  CHECK(iso8601_utc_text(1700000000, 123456789, 9) == "2023-11-14T22:13:20.123456789Z");
  CHECK(iso8601_utc_text(1700000000, 5, 6) == "2023-11-14T22:13:20.000005Z");
  CHECK_THROWS_WITH(iso8601_utc_text(0, 1000000, 6),
                    "iso8601_utc_text: fraction 1000000 is not from 0 to 10^6 - 1 with 0 to 9 "
                    "digits");
  CHECK_THROWS_WITH(iso8601_utc_text(0, -1, 3),
                    "iso8601_utc_text: fraction -1 is not from 0 to 10^3 - 1 with 0 to 9 digits");
  // The present moment is a valid UTC time as the command line takes it.
  CHECK(doorbench::iso8601_utc_problem(doorbench::utc_now_iso8601()).empty());
  CHECK(doorbench::utc_now_iso8601().size() == 20);
}

TEST_CASE("iso8601_utc_problem and parse_date_time take the same days of the calendar as timegm",
          "[core]") {
  // A day is in the calendar when timegm does not move it to another day.
  for (int year : {1900, 1999, 2000, 2023, 2024, 2100, 2400}) {
    for (int month = 1; month <= 12; ++month) {
      for (int day = 27; day <= 32; ++day) {
        std::tm civil{};
        civil.tm_year = year - 1900;
        civil.tm_mon = month - 1;
        civil.tm_mday = day;
        const std::time_t back = timegm(&civil);
        std::tm normal{};
        gmtime_r(&back, &normal);
        const bool in_calendar = normal.tm_mday == day && day <= 31;
        const std::string date = doorbench::printf_text("%04d-%02d-%02d", year, month, day);
        CAPTURE(date);
        CHECK(doorbench::iso8601_utc_problem(date).empty() == in_calendar);
        CHECK(static_cast<bool>(doorbench::parse_date_time(date + " 12:00")) == in_calendar);
      }
    }
  }
  CHECK(doorbench::iso8601_utc_problem("2100-02-29") == "2100-02-29 is not a day of the calendar");
}

TEST_CASE("parse_date_time: a logger's date and time as seconds since 1970, its zone if stated",
          "[core]") {
  using doorbench::parse_date_time;
  // Against timegm (the C library's own calendar) over dates either side of leap days and
  // centuries, at every month's first and last day.
  for (int year : {1970, 1999, 2000, 2024, 2025, 2100}) {
    for (int month = 1; month <= 12; ++month) {
      for (int day : {1, 28}) {
        std::tm civil{};
        civil.tm_year = year - 1900;
        civil.tm_mon = month - 1;
        civil.tm_mday = day;
        civil.tm_hour = 13;
        civil.tm_min = 7;
        civil.tm_sec = 59;
        char text[32];
        std::snprintf(text, sizeof text, "%04d-%02d-%02d 13:07:59", year, month, day);
        const auto parsed = parse_date_time(text);
        REQUIRE(parsed);
        CHECK(parsed->seconds == static_cast<std::int64_t>(timegm(&civil)));
        CHECK_FALSE(parsed->zone_known);
      }
    }
  }
  const auto utc = parse_date_time("2024-02-29T23:59:58.125Z");
  REQUIRE(utc);
  CHECK(utc->seconds == 1709251198);
  CHECK(utc->fraction_s == 0.125);
  CHECK(utc->zone_known);
  // An offset is taken off; seconds and the fraction are optional.
  CHECK(parse_date_time("2024-03-01 00:59:58.125+01:00")->seconds == 1709251198);
  CHECK(parse_date_time("2024-02-29 18:59:58-0500")->seconds == 1709251198);
  CHECK(parse_date_time(" 2024-02-29 23:59 ")->seconds == 1709251140);
  CHECK(parse_date_time("2024-02-29 23:59:58.000000000000000000001")->fraction_s == 0.0);
  for (const char* bad : {"2023-02-29 00:00:00", "2024-13-01 00:00", "2024-01-01", "12.5",
                          "2024-01-01 24:00:00", "2024-01-01 00:00:00.", "2024-01-01 00:00:00 PM",
                          "2024-01-01 00:00:00+1", "2024-01-01_00:00:00", ""}) {
    INFO(bad);
    CHECK_FALSE(parse_date_time(bad));
  }
  // A time of the day alone: seconds since its midnight, no date, no zone.
  const auto clock = parse_date_time(" 09:30:05.25 ");
  REQUIRE(clock);
  CHECK(clock->seconds == 9 * 3600 + 30 * 60 + 5);
  CHECK(clock->fraction_s == 0.25);
  CHECK_FALSE(clock->date_known);
  CHECK_FALSE(clock->zone_known);
  CHECK(parse_date_time("23:59")->seconds == 86340);
  CHECK(parse_date_time("2024-02-29 23:59")->date_known);
  for (const char* bad :
       {"24:00:00", "09:60", "09:30:60", "09:30:00Z", "09:30:00.", "9:30:00", "09:30 PM", "09:3"}) {
    INFO(bad);
    CHECK_FALSE(parse_date_time(bad));
  }
}
