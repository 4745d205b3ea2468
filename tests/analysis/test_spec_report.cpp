// The specification report: spec.json's fields, spec.html's tables and plots, spec.pdf when
// weasyprint is installed. The inverse design result is made by hand here (a known TO-BE
// door), so that the report is tested without the inverse fit.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "analysis/design/spec_report.h"
#include "analysis/model/parameter_file.h"
#include "analysis/simulation/fit_synthetic.h"
#include "fixtures/temp_dir.h"
#include "tests/support/pgm_image.h"

using Catch::Matchers::Contains;
using doorbench::DesignParameter;
using doorbench::DesignSolution;
using doorbench::DoorModel;
using doorbench::InverseDesignResult;
using doorbench::ModelKind;
using doorbench::PreparedData;

namespace {

DoorModel scaled(const DoorModel& model, const char* name, double factor) {
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  values.at(static_cast<std::size_t>(*model.find_parameter(name))) *= factor;
  return model.with_parameter_values(values);
}

DesignSolution solution_of(const DoorModel& asis, const DoorModel& tobe) {
  DesignSolution solution{.model = tobe,
                          .parameters = {},
                          .fit = {},
                          .held_at_as_is = {},
                          .at_bound = {},
                          .summary = {}};
  for (int i = 0; i < tobe.parameter_count(); ++i) {
    DesignParameter p;
    p.name = tobe.parameter_name(i);
    p.unit = std::string(tobe.parameter_unit(i));
    p.free = p.name != "m_d";
    p.as_is = asis.parameter_values()[i];
    p.to_be = tobe.parameter_values()[i];
    p.change = p.to_be - p.as_is;
    p.relative_change = p.change / std::abs(p.as_is);
    p.uncertainty = p.free ? 0.01 * std::abs(p.to_be) : NAN;
    p.weight = 1.0;
    p.bounds = tobe.parameter_bounds()[i];
    p.changed = p.free && p.change != 0.0;
    solution.parts_changed += p.changed ? 1 : 0;
    solution.parameters.push_back(p);
  }
  return solution;
}

// A known design (the reference door with a softer catch and more preload), its evaluation
// against synthetic recordings of that door, and an alternative.
struct KnownReport {
  DoorModel asis;
  InverseDesignResult design;
  doorbench::SpecEvaluation evaluation;
};

KnownReport known_report() {
  const DoorModel asis = doorbench::reference_model(ModelKind::kPhysical);
  const DoorModel tobe = scaled(scaled(asis, "F_l0", 0.7), "F0", 1.04);
  const DoorModel alternative = scaled(asis, "k_l", 0.8);
  doorbench::SyntheticStrokeOptions synthetic;
  synthetic.runs = {{1.0, 4.0}, {1.3, 5.0}};
  std::vector<PreparedData> recordings = {doorbench::synthetic_strokes(tobe, synthetic)};
  recordings[0].source = "tobe <1>.h5";  // escaped in the HTML

  InverseDesignResult design;
  design.solutions.push_back(solution_of(asis, tobe));
  design.solutions.front().held_at_as_is = {"k_s", "L0"};  // a fewest-changes design
  design.solutions.front().parts_changed_cost = 2.0;       // F0 and F_l0
  design.solutions.push_back(solution_of(asis, alternative));
  design.commanded_torque = true;
  design.rate_noise_rad_s = 0.001;
  design.notes = {"made by hand for the test"};

  doorbench::SpecEvaluationOptions options;
  options.felt.hand.duration_s = 6.0;
  options.monte_carlo.samples = 8;
  options.monte_carlo.threads = 2;
  doorbench::SpecEvaluation evaluation =
      doorbench::evaluate_spec(asis, design, recordings, options);
  evaluation.command = "doorbench spec test";
  evaluation.asis_source = "reference door";
  return {asis, design, evaluation};
}

}  // namespace

TEST_CASE("Spec report: spec.json, spec.html and spec.pdf of a known design", "[spec]") {
  KnownReport known = known_report();
  const DoorModel& asis = known.asis;
  const DoorModel tobe = known.design.solutions.front().model;
  InverseDesignResult& design = known.design;
  doorbench::SpecEvaluation& evaluation = known.evaluation;

  REQUIRE(evaluation.tolerances);
  CHECK(evaluation.tolerances->failed == 0);
  REQUIRE(evaluation.felt_alternatives.size() == 1);
  // The design is the door that made the recordings: its check is far better than AS-IS's.
  CHECK(evaluation.check_after.curve_rms_error_N < 0.5);
  CHECK(evaluation.check_before.curve_rms_error_N > 5 * evaluation.check_after.curve_rms_error_N);
  CHECK(evaluation.felt_after.peak_unlatch_force_N < evaluation.felt_before.peak_unlatch_force_N);

  doorbench::testing::TempDir dir("spec_report");
  const doorbench::SpecReportFiles files =
      doorbench::write_spec_report(dir / "out", design, evaluation);
  REQUIRE(std::filesystem::exists(files.json));
  REQUIRE(std::filesystem::exists(files.html));

  const auto json = nlohmann::json::parse(doorbench::read_text_file(files.json));
  CHECK(json["feasible"] == true);
  CHECK(json["requested"].empty());
  CHECK(json["tobe_sources"][0] == "tobe <1>.h5");
  REQUIRE(json["parameters"].size() == static_cast<std::size_t>(asis.parameter_count()));
  const auto& f_l0 = json["parameters"][doorbench::physical::kFl0];
  CHECK(f_l0["name"] == "F_l0");
  CHECK(f_l0["unit"] == "N");
  CHECK(f_l0["as_is"].get<double>() == 15.0);
  CHECK_THAT(f_l0["to_be"].get<double>(), Catch::Matchers::WithinRel(10.5, 1e-12));
  CHECK_THAT(f_l0["change"].get<double>(), Catch::Matchers::WithinRel(-4.5, 1e-12));
  CHECK(f_l0["uncertainty"].is_number());
  CHECK(json["parameters"][0]["uncertainty"].is_null());  // m_d fixed: NaN -> null
  for (const char* key : {"before", "after", "tobe_recorded"}) {
    INFO(key);
    CHECK(json["felt"][key]["peak_unlatch_force_N"].is_number());
    CHECK(json["felt"][key]["balance_force_N"].is_number());
  }
  CHECK(json["check"]["after"]["errors"].size() == doorbench::kFeltQuantities.size());
  CHECK(json["check"]["after"]["curve_rms_error_N"].get<double>() < 0.5);
  CHECK(json["tolerances"]["samples"] == 8);
  REQUIRE(json["tolerances"]["spreads"].size() == doorbench::kFeltQuantities.size());
  CHECK(json["tolerances"]["spreads"][0]["sd"].get<double>() > 0);
  CHECK(json["tolerances"]["spreads"][0]["explained_variance"].contains("F_l0"));
  CHECK(json["fit"]["commanded_torque"] == true);
  CHECK(json["fit"]["parts_changed_cost"].get<double>() == 2.0);
  CHECK(json["fit"]["held_at_as_is"] == nlohmann::json::array({"k_s", "L0"}));
  REQUIRE(json["alternatives"].size() == 1);
  CHECK(json["alternatives"][0]["held_at_as_is"].empty());
  CHECK(json["alternatives"][0]["changes"].size() == 1);
  CHECK(json["alternatives"][0]["changes"][0]["name"] == "k_l");

  const std::string html = doorbench::read_text_file(files.html);
  CHECK_THAT(html, Contains("<h2>Parameters</h2>"));
  CHECK_THAT(html, Contains("<tr class=\"changed\"><td>F_l0</td>"));
  CHECK_THAT(html, Contains("<svg"));
  CHECK_THAT(html, Contains("fitted to the torque they commanded"));
  // The first page says what to change, what stays, what it gives.
  CHECK_THAT(html, Contains("<p><b>Change:</b> F0 250 &rarr; 260 N (+4.0 %); F_l0 15 &rarr; "
                            "10.5 N (-30.0 %).</p>"));
  CHECK_THAT(html, Contains("<p><b>Keep</b> the other 24 parameters as they are (parts changed: "
                            "2, cost 2)."));
  CHECK_THAT(html, Contains("design, opening"));
  CHECK_THAT(html, Contains("spread of the peak force to unlatch"));
  // Felt quantities by their human labels with units, under stated conditions.
  CHECK_THAT(html, Contains("<td>peak force to unlatch (N)</td>"));
  CHECK(html.find("peak_unlatch_force_N") == std::string::npos);
  CHECK_THAT(html, Contains("The same quantities in the standard run (virtual hand, 0 to 80 deg "
                            "and back in 6 s"));
  // One definition: spec.json's felt quantities of a model are those of its check, read along
  // the same recordings (like with like), and the tables cannot disagree.
  for (std::size_t q = 0; q < doorbench::kFeltQuantities.size(); ++q) {
    const std::string name(doorbench::kFeltQuantities[q].name);
    INFO(name);
    CHECK(json["felt"]["after"][name] == json["check"]["after"]["errors"][q]["model"]);
    CHECK(json["felt"]["before"][name] == json["check"]["before"]["errors"][q]["model"]);
    CHECK(json["felt"]["tobe_recorded"][name] == json["check"]["after"]["errors"][q]["recorded"]);
  }
  CHECK(json["felt"]["conditions"] == "along the TO-BE recordings' motion");
  CHECK(json["felt"]["standard_run"]["after"]["peak_unlatch_force_N"].is_number());
  CHECK_THAT(html, Contains("tobe &lt;1&gt;.h5"));
  CHECK(html.find("<?xml") == std::string::npos);  // inline SVG, no XML declaration

  if (std::system("command -v weasyprint > /dev/null 2>&1") == 0) {
    INFO(files.pdf_note);
    REQUIRE(!files.pdf.empty());
    CHECK(doorbench::read_text_file(files.pdf).rfind("%PDF", 0) == 0);
  } else {
    WARN("weasyprint not installed: " << files.pdf_note);
    CHECK(files.pdf.empty());
  }
  // Asked for no PDF: none, and an earlier run's spec.pdf in the folder is removed.
  std::filesystem::create_directories(dir / "nopdf");
  std::ofstream(dir / "nopdf" / "spec.pdf") << "%PDF of an earlier run\n";
  const auto no_pdf = doorbench::write_spec_report(dir / "nopdf", design, evaluation, "none");
  CHECK(no_pdf.pdf.empty());
  CHECK(!std::filesystem::exists(dir / "nopdf" / "spec.pdf"));
}

TEST_CASE("Spec report: a design without solutions is refused", "[spec]") {
  const DoorModel asis = doorbench::reference_model(ModelKind::kPhysical);
  const InverseDesignResult empty;
  const std::vector<PreparedData> none;
  CHECK_THROWS_WITH(doorbench::evaluate_spec(asis, empty, none),
                    "spec: the inverse design has no solution");
}

// spec.pdf must print on A4 portrait: every page rendered to pixels (pdftoppm, poppler-utils)
// has nothing in its right margin, where a table or plot too wide for the page would run.
TEST_CASE("Spec report: spec.pdf fits A4 portrait, nothing at the right margin", "[spec][pdf]") {
  if (std::system("command -v weasyprint > /dev/null 2>&1") != 0 ||
      std::system("command -v pdftoppm > /dev/null 2>&1") != 0) {
    WARN("weasyprint or pdftoppm (poppler-utils) not installed: scripts/install-deps.sh");
    return;
  }
  KnownReport known = known_report();
  // What ran off the page before: a long command line and long notes.
  for (int i = 0; i < 8; ++i) known.evaluation.command += " /some/long/folder/tobe-recording.h5";
  known.design.notes.push_back(std::string(300, 'x'));
  // The sparse search's table, with candidates the data cannot tell apart.
  doorbench::SparseStep as_is_row, step;
  as_is_row.data_cost = 8.12849e7;
  step.added = "F_l0";
  step.data_cost = 14391.8;
  step.reduced_data_cost = 1.392;
  step.tried = {{"F_l0", 14391.8}, {"k_l", 14400.1}, {"theta_seal", 14410.9}, {"alpha_o", 14420.5}};
  step.equivalent = {"F_l0", "k_l", "theta_seal", "alpha_o"};
  known.design.sparse_steps = {as_is_row, step};
  known.design.sparse_stop = "stopped at 1 part(s): " + std::string(200, 'y');
  // The panel's section (spec --campaign): long sources and criteria, the proposal's table.
  REQUIRE(known.evaluation.tolerances);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  doorbench::PerceptualSpec panel;
  panel.campaign = "/some/long/folder/campaign-analysis-of-the-panel/analysis.json";
  panel.tobe_source = "the panel's favourite variant " + std::string(150, 'z');
  panel.notes = {
      "no jnd section in /some/long/folder/campaign-analysis-of-the-panel/"
      "analysis.json: typical published JNDs used (stiffness 15%, friction 20%)"};
  panel.preference = {{"a_variant_with_a_long_name", 0.8, 0.3, 1.3}, {"A", 0.0, nan, nan}};
  panel.thresholds = {{"k_l", "k_l*1.00", "panel", "psychometric fit, pooled",
                       "75.0% of the lapse-free cumulative normal above its PSE", 0.17, 0.14, nan}};
  for (const auto& info : doorbench::kFeltQuantities) {
    doorbench::FeltJnd jnd = doorbench::typical_felt_jnd(info.name);
    jnd.source = "measured: free_movement_friction (panel, psychometric fit, pooled)";
    panel.jnds.push_back(jnd);
  }
  panel.rows = doorbench::perceptual_shares(*known.evaluation.tolerances, panel.jnds);
  panel.proposal.felt_share = 0.05;
  panel.proposal.factor = 0.5;
  panel.proposal.reached = true;
  panel.proposal.rows = panel.rows;
  panel.proposal.tolerances = known.evaluation.tolerances->tolerances;
  panel.proposal.summary =
      "every tolerance × 0.5 keeps each felt quantity's share " + std::string(100, 'w');
  known.evaluation.perceptual = panel;
  doorbench::testing::TempDir dir("spec_pdf");
  const doorbench::SpecReportFiles files =
      doorbench::write_spec_report(dir / "out", known.design, known.evaluation);
  INFO(files.pdf_note);
  CHECK_THAT(doorbench::read_text_file(files.html),
             Contains("<h2>Tolerances judged by the panel's perception</h2>"));
  CHECK_THAT(doorbench::read_text_file(files.html),
             Contains("<h2>How the parts were chosen</h2>") &&
                 Contains("<td>k_l (14400.1), theta_seal (14410.9), alpha_o (14420.5)</td>"));
  REQUIRE(!files.pdf.empty());
  constexpr int kDpi = 40;
  const std::string command = "pdftoppm -r " + std::to_string(kDpi) + " -gray '" +
                              files.pdf.string() + "' '" + (dir / "page").string() + "'";
  REQUIRE(std::system(command.c_str()) == 0);
  int pages = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path)) {
    if (entry.path().extension() != ".pgm") continue;
    ++pages;
    const doorbench::testing::GrayImage page = doorbench::testing::read_pgm(entry.path());
    INFO(entry.path().filename().string() << ": " << page.width << " x " << page.height);
    // A4 portrait: 210 x 297 mm.
    CHECK(std::abs(page.width - 210.0 / 25.4 * kDpi) <= 2);
    CHECK(std::abs(page.height - 297.0 / 25.4 * kDpi) <= 2);
    // The right margin is 12 mm: its outer 10 mm must stay white on every row.
    const int margin_px = static_cast<int>(10.0 / 25.4 * kDpi);
    CHECK(doorbench::testing::ink_in_right_margin(page, margin_px) == 0);
  }
  CHECK(pages >= 2);
}
