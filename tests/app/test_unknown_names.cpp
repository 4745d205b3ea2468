// Unknown names are usage errors (`play --device bogus`, an unknown name in `fit --free`,
// `spec --fixed` and `--costs`, fit's before the data is read): exit 2, the message naming the
// option, the name and the valid choices, before any input is read or any output made.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;

const std::string kSensoryParameters =
    "J, k, k_inf, k_lock, theta0, theta1, theta2, theta3, c, d1, d2, s, theta4, beta, beta_f, "
    "k_stop, c_stop";
const std::string kPhysicalParameters =
    "m_d, l_c, J_d, k_s, L0, F0, A_x, A_y, B_u, B_v, T_h, b_h, w_f, mu_g, r_l, k_l, F_l0, h, "
    "alpha_o, alpha_c, mu_l, e, k_seal, theta_seal, k_stop, c_stop";

}  // namespace

TEST_CASE("Unknown names: fit --free and --fixed name the model's parameters, exit 2",
          "[cli][usage]") {
  const TempDir dir("unknown_fit_names");
  const auto out = dir / "out";
  // The data file does not exist: the names are checked before it is read.
  const std::string data = std::string("'").append((dir / "missing.csv").string()).append("'");
  const DoorbenchRun free =
      run_doorbench_shell("fit " + data + " --free J,bogus --out '" + out.string() + "'", dir);
  CHECK(free.status == 2);
  CHECK(free.err ==
        "doorbench: --free: the sensory model has no parameter 'bogus' (its "
        "parameters: " +
            kSensoryParameters + ") (see doorbench fit --help)\n");
  // With an effect, its parameters are names too.
  const DoorbenchRun fixed = run_doorbench_shell(
      "fit " + data + " --effects stribeck --fixed stribeck.d_s,stribeck.bogus --out '" +
          out.string() + "'",
      dir);
  CHECK(fixed.status == 2);
  CHECK(fixed.err ==
        "doorbench: --fixed: the sensory model has no parameter 'stribeck.bogus' "
        "(its parameters: " +
            kSensoryParameters + ", stribeck.d_s, stribeck.w_s) (see doorbench fit --help)\n");
  const DoorbenchRun loop = run_doorbench_shell(
      "fit " + data + " --model physical --free J --out '" + out.string() + "'", dir);
  CHECK(loop.status == 2);
  CHECK(loop.err ==
        "doorbench: --free: the physical model has no parameter 'J' (its "
        "parameters: " +
            kPhysicalParameters + ") (see doorbench fit --help)\n");
  CHECK_FALSE(std::filesystem::exists(out));
}

TEST_CASE(
    "Unknown names: spec --fixed and --costs name the physical model's parameters, "
    "exit 2",
    "[cli][usage]") {
  const TempDir dir("unknown_spec_names");
  const auto out = dir / "out";
  const std::string asis = std::string(DOORBENCH_SOURCE_DIR) + "/analysis/data/reference-door.json";
  // The TO-BE recording is not one: the names are checked before it is read.
  const std::string tobe = dir.write("tobe.csv", "not a recording\n").string();
  const std::string common =
      "spec '" + tobe + "' --asis '" + asis + "' --out '" + out.string() + "'";
  const DoorbenchRun fixed = run_doorbench_shell(common + " --fixed F0,bogus", dir);
  CHECK(fixed.status == 2);
  CHECK(fixed.err ==
        "doorbench: --fixed: the physical model has no parameter 'bogus' (its "
        "parameters: " +
            kPhysicalParameters + ") (see doorbench spec --help)\n");
  const DoorbenchRun costs = run_doorbench_shell(common + " --costs F0=1,k_x=5", dir);
  CHECK(costs.status == 2);
  CHECK(costs.err ==
        "doorbench: --costs: the physical model has no parameter 'k_x' (its "
        "parameters: " +
            kPhysicalParameters + ") (see doorbench spec --help)\n");
  CHECK_FALSE(std::filesystem::exists(out));
}

TEST_CASE("Unknown names: play --device names the devices there are, exit 2", "[cli][usage]") {
  const TempDir dir("unknown_device");
  const auto out = dir / "x.h5";
  const DoorbenchRun bogus =
      run_doorbench_shell("play --device bogus --out '" + out.string() + "'", dir);
  CHECK(bogus.status == 2);
  CHECK(bogus.err ==
        "doorbench: --device 'bogus': not a device (use sim, sim:hapticmaster, "
        "sim:rotary or hapticmaster://HOST[:PORT]) (see doorbench play --help)\n");
  const DoorbenchRun no_host =
      run_doorbench_shell("play --device hapticmaster:// --out '" + out.string() + "'", dir);
  CHECK(no_host.status == 2);
  CHECK(no_host.err ==
        "doorbench: --device 'hapticmaster://': no host "
        "(hapticmaster://HOST[:PORT]) (see doorbench play --help)\n");
  CHECK_FALSE(std::filesystem::exists(out));
}
