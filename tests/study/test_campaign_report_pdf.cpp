// report.pdf read as a reader would: a campaign of 6 variants and 300 participants (every
// section but tuning at that size, six tuned doors beside) analysed by `doorbench campaign
// analyze`, its report.pdf turned back into text (pdftotext -layout) and into pixels
// (pdftoppm). Every table row's numbers and names must come out on one line, each cell
// whole (no number or name broken across lines), and nothing may run into the page's right
// margin. Needs weasyprint and poppler-utils (scripts/install-deps.sh); warns without them.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "tests/study/simulated_panel.h"
#include "tests/support/files.h"
#include "tests/support/pgm_image.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::append_row;
using doorbench::testing::PanelRandom;
using doorbench::testing::read_file;
using doorbench::testing::TempDir;

namespace {

const std::vector<std::string> kVariants{"reference", "heavier-door",   "softer_latch",
                                         "Barcelona", "snappier-close", "smooth_friction"};

std::string participant_id(int p) {
  return std::string("P").append(std::to_string(1000 + p));
}

// Identify-real (the real door against Barcelona, 4 trials each, Pc 0.55), ratings of
// heaviness (3 pairs), a jnd block of J_d (6 levels twice) for every participant; six tuned
// doors.
void append_other_blocks(std::string& text, const TempDir& dir, PanelRandom& random) {
  auto door = nlohmann::json::parse(doorbench::reference_door_json());
  const double reference_j = door["sensory"]["J"]["value"].get<double>();
  for (int p = 0; p < 300; ++p) {
    const std::string id = participant_id(p);
    for (int t = 0; t < 4; ++t) {
      const bool real_first = t % 2 == 0, correct = random.uniform() < 0.55;
      append_row(text, {id, "ir", std::to_string(t + 1), "identify-real",
                        real_first ? "real" : "Barcelona", real_first ? "Barcelona" : "real",
                        real_first == correct ? "1" : "2"});
    }
    for (int r = 0; r < 3; ++r) {
      const int a = 2 + int(4 * random.uniform()),
                b = std::clamp(a + int(4 * random.uniform()) - 1, 1, 7);
      append_row(text, {id, "rating", std::to_string(r + 1), "rating:heavy:7", kVariants[0],
                        kVariants[std::size_t(r + 1)],
                        std::to_string(a).append(" ").append(std::to_string(b))});
    }
    int trial = 0;
    for (int rep = 0; rep < 2; ++rep) {
      for (const char* level :
           {"J_d*0.80", "J_d*0.90", "J_d*0.95", "J_d*1.05", "J_d*1.10", "J_d*1.20"}) {
        const double factor = std::stod(std::string(level).substr(4));
        const double p_stronger = 0.5 * std::erfc(-std::log(factor) / 0.12 / std::sqrt(2.0));
        const bool stronger = random.uniform() < p_stronger, comparison_first = ++trial % 2 == 1;
        append_row(text,
                   {id, "jnd", std::to_string(trial), "stronger:J_d",
                    comparison_first ? level : "J_d*1.00", comparison_first ? "J_d*1.00" : level,
                    stronger == comparison_first ? "1" : "2"});
      }
    }
    if (p < 6) {
      door["sensory"]["J"]["value"] = reference_j * (1.0 + 0.03 * p);
      dir.write("campaign/tuned/" + id + ".json", door.dump());
      append_row(text, {id, "tune", "1", "tune", "", "", "tuned/" + id + ".json"});
    }
  }
}

std::string decode(std::string text) {
  text = std::regex_replace(text, std::regex("<[^>]*>"), "");
  const std::pair<const char*, const char*> entities[] = {
      {"&ndash;", "\u2013"},  {"&minus;", "\u2212"}, {"&infin;", "\u221e"},
      {"&plusmn;", "\u00b1"}, {"&nbsp;", " "},       {"&lt;", "<"},
      {"&gt;", ">"},          {"&quot;", "\""},      {"&amp;", "&"}};
  for (const auto& [entity, character] : entities)
    text = std::regex_replace(text, std::regex(entity), character);
  return std::regex_replace(text, std::regex("\\s+"), " ");
}

// Each table row's cells that must not wrap (all but class="text"), decoded.
std::vector<std::vector<std::string>> unbreakable_rows(const std::string& html) {
  std::vector<std::vector<std::string>> rows;
  const std::regex row("<tr>(.*?)</tr>"), cell("<td( class=\"text\")?>(.*?)</td>");
  for (auto r = std::sregex_iterator(html.begin(), html.end(), row); r != std::sregex_iterator();
       ++r) {
    const std::string inside = (*r)[1];
    std::vector<std::string> cells;
    for (auto c = std::sregex_iterator(inside.begin(), inside.end(), cell);
         c != std::sregex_iterator(); ++c) {
      if ((*c)[1].matched) continue;
      const std::string text = decode((*c)[2]);
      if (!text.empty() && text != " ") cells.push_back(text);
    }
    if (!cells.empty()) rows.push_back(cells);
  }
  return rows;
}

// Whether one line holds every cell, in order, each whole.
bool on_one_line(const std::vector<std::string>& lines, const std::vector<std::string>& cells) {
  for (const std::string& line : lines) {
    std::size_t at = 0;
    bool all = true;
    for (const std::string& c : cells) {
      at = line.find(c, at);
      if (at == std::string::npos) {
        all = false;
        break;
      }
      at += c.size();
    }
    if (all) return true;
  }
  return false;
}

}  // namespace

TEST_CASE(
    "report.pdf of 6 variants and 300 participants: no number or name broken, nothing "
    "off the page",
    "[study][campaign][pdf]") {
  if (std::system("command -v weasyprint > /dev/null 2>&1") != 0 ||
      std::system("command -v pdftotext > /dev/null 2>&1") != 0 ||
      std::system("command -v pdftoppm > /dev/null 2>&1") != 0) {
    WARN("weasyprint or pdftotext/pdftoppm (poppler-utils) not installed: scripts/install-deps.sh");
    return;
  }
  TempDir dir("campaign_report_pdf");
  doorbench::testing::PairPanel panel;
  panel.variants = kVariants;
  panel.worths = {0.0, -0.4, 0.3, 0.8, -1.0, 0.1};
  panel.nu = 0.5;
  panel.delta = 0.1;
  panel.heterogeneity_sd = 0.3;
  panel.participants = 300;
  panel.repetitions = 1;
  std::string text = doorbench::testing::kTrialsHeader;
  // The pair block's participants are S1 ... S300: named as the others' P1000 ... P1299.
  std::istringstream pairs(doorbench::testing::simulate_pairs(panel, 44));
  for (std::string line; std::getline(pairs, line);) {
    const std::size_t comma = line.find(',');
    text += participant_id(std::stoi(line.substr(1, comma - 1)) - 1) + line.substr(comma) + "\n";
  }
  PanelRandom random(45);
  append_other_blocks(text, dir, random);
  dir.write("campaign/trials.csv", text);

  const auto run = doorbench::testing::run_doorbench_shell(
      "campaign analyze '" + (dir / "campaign").string() + "' --bootstrap 200 --out '" +
          (dir / "analysis").string() + "'",
      dir);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const std::filesystem::path pdf = dir / "analysis" / "report.pdf";
  REQUIRE(std::filesystem::exists(pdf));
  const std::string html = read_file(dir / "analysis" / "report.html");
  // p-values as statisticians write them: never "p = 0.00" (nor "p = 0").
  const std::regex zero_p("p = 0(\\.0*)?[^.0-9]");
  CHECK_FALSE(std::regex_search(decode(html), zero_p));
  CHECK_FALSE(std::regex_search(run.out, zero_p));
  CHECK(html.find("fewer than") == std::string::npos);  // 300 participants: bootstrapped

  // Every row's unbreakable cells on one line of the PDF's text, whole.
  REQUIRE(std::system(
              ("pdftotext -layout '" + pdf.string() + "' '" + (dir / "report.txt").string() + "'")
                  .c_str()) == 0);
  std::vector<std::string> lines;
  std::istringstream report_text(read_file(dir / "report.txt"));
  for (std::string line; std::getline(report_text, line);)
    lines.push_back(std::regex_replace(line, std::regex("\\s+"), " "));
  const auto rows = unbreakable_rows(html);
  CHECK(rows.size() > 600);  // 300 identify-real and 300 jnd rows, and the rest
  int broken = 0;
  for (const auto& cells : rows) {
    if (on_one_line(lines, cells)) continue;
    if (++broken <= 10) {
      std::string joined;
      for (const std::string& c : cells) joined += "[" + c + "] ";
      UNSCOPED_INFO("a row not whole on one line of report.pdf: " << joined);
    }
  }
  CHECK(broken == 0);

  // Nothing in the outer 10 mm of the right margin (12 mm) of any A4 page.
  constexpr int kDpi = 40;
  REQUIRE(std::system(("pdftoppm -r " + std::to_string(kDpi) + " -gray '" + pdf.string() + "' '" +
                       (dir / "page").string() + "'")
                          .c_str()) == 0);
  int pages = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path)) {
    if (entry.path().extension() != ".pgm") continue;
    ++pages;
    const auto page = doorbench::testing::read_pgm(entry.path());
    INFO(entry.path().filename().string());
    CHECK(std::abs(page.width - 210.0 / 25.4 * kDpi) <= 2);
    CHECK(doorbench::testing::ink_in_right_margin(page, int(10.0 / 25.4 * kDpi)) == 0);
  }
  CHECK(pages >= 3);
}
