// One output rule for every verb (acquisition/session/output_file.h, docs/output-files.md): an
// existing output is refused unless --overwrite, an output is never an input, every file is written
// whole or not at all, a failure names the path and the system's error, and fit/loop check their
// input before creating --out.
//
// A full disk is a real one where the machine permits it: a 64 KiB tmpfs mounted in a
// private mount namespace of the command (`unshare -m`, so it vanishes with it); and always
// a file size limit (`ulimit -f`), which makes write() fail the same way (EFBIG).
#include <sys/stat.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "acquisition/session/pdf_output.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/run_doorbench.h"

using doorbench::testing::read_file;

namespace {

using doorbench::testing::DoorbenchRun;
using doorbench::testing::run_doorbench_shell;
using doorbench::testing::TempDir;
namespace fs = std::filesystem;

// A 2 s session of the built-in bench (about 100 KB of CSV when exported).
fs::path small_session(const TempDir& dir) {
  const fs::path path = dir / "s.h5";
  doorbench::testing::record_built_in_session(path, 2.0, 3, "sensory");
  return path;
}

std::string files_in(const fs::path& folder) {
  std::string names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    names += entry.path().filename().string() + " ";
  }
  return names;
}

// The names of the files in `folder`, sorted.
std::vector<std::string> files_in_order(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Runs a shell script (`doorbench` stands for the executable); stdout and stderr captured.
DoorbenchRun run_script(const std::string& text, const TempDir& dir,
                        const std::string& shell = "sh") {
  const fs::path script = dir / "script.sh";
  std::ofstream(script) << "doorbench() { '" DOORBENCH_EXECUTABLE "' \"$@\"; }\n" << text << "\n";
  const fs::path out = dir / "script.out";
  const fs::path err = dir / "script.err";
  const std::string command =
      shell + " '" + script.string() + "' > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  DoorbenchRun run;
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = read_file(out);
  run.err = read_file(err);
  return run;
}

// Runs `doorbench ARGS` in a private mount namespace with a 64 KiB tmpfs at `mount_point`,
// after `setup` (shell commands run there first); `after` (shell) runs before the mount goes
// and its output is appended to stdout. False when mounting is not permitted here.
bool run_on_full_tmpfs(const fs::path& mount_point, const std::string& setup,
                       const std::string& args, const std::string& after, const TempDir& dir,
                       DoorbenchRun& run) {
  fs::create_directories(mount_point);
  const std::string mount = "mount -t tmpfs -o size=64k tmpfs '" + mount_point.string() + "'";
  const std::string probe = "unshare -m sh -c \"" + mount + "\" 2>/dev/null";
  if (std::system(probe.c_str()) != 0) return false;
  run = run_script(
      mount + "\n" + setup + "\ndoorbench " + args + "\nstatus=$?\n" + after + "\nexit $status",
      dir, "unshare -m sh");
  return true;
}

}  // namespace

TEST_CASE("Outputs: export never writes onto its input or an existing file", "[outputs][cli]") {
  const TempDir dir("output_export");
  const fs::path session = small_session(dir);
  const std::string before = read_file(session);

  const DoorbenchRun onto = run_doorbench_shell(
      "export " + session.string() + " --csv " + session.string() + " --overwrite", dir);
  CHECK(onto.status == 2);
  CHECK(onto.err == "doorbench: " + session.string() +
                        ": is an input of this command (doorbench never writes onto its input)\n");
  CHECK(read_file(session) == before);
  // The same file by another name.
  const fs::path link = dir / "link.csv";
  fs::create_symlink(session, link);
  CHECK(run_doorbench_shell("export " + session.string() + " --csv " + link.string(), dir).status ==
        2);
  CHECK(read_file(session) == before);

  const fs::path csv = dir / "s.csv";
  std::ofstream(csv) << "old\n";
  const DoorbenchRun again =
      run_doorbench_shell("export " + session.string() + " --csv " + csv.string(), dir);
  CHECK(again.status == 2);
  CHECK(again.err == "doorbench: " + csv.string() + ": exists (give --overwrite to replace it)\n");
  CHECK(read_file(csv) == "old\n");
  const DoorbenchRun forced = run_doorbench_shell(
      "export " + session.string() + " --csv " + csv.string() + " --overwrite", dir);
  INFO(forced.err);
  CHECK(forced.status == 0);
  CHECK(read_file(csv).find("\ntime_s,force_N,") != std::string::npos);
  CHECK(files_in(dir.path).find(".partial") == std::string::npos);
  // A pipe (as a device like /dev/null) is never replaced, --overwrite or not.
  const std::filesystem::path pipe = dir.path / "pipe.csv";
  REQUIRE(::mkfifo(pipe.c_str(), 0600) == 0);
  const DoorbenchRun onto_pipe = run_doorbench_shell(
      "export " + session.string() + " --csv " + pipe.string() + " --overwrite", dir);
  CHECK(onto_pipe.status == 2);
  CHECK(onto_pipe.err == "doorbench: " + pipe.string() +
                             ": is not a regular file (a device, pipe or socket): doorbench "
                             "writes through a temporary file renamed onto the name, which "
                             "would replace it\n");
  CHECK(std::filesystem::is_fifo(pipe));
}

TEST_CASE("Outputs: simulate, model torque and import follow the same rule", "[outputs][cli]") {
  const TempDir dir("output_verbs");
  const fs::path run = dir / "run.csv";
  std::ofstream(run) << "old\n";
  const std::string simulate =
      "simulate --model sensory --hand open-close --duration-s 1 --out " + run.string();
  const DoorbenchRun refused = run_doorbench_shell(simulate, dir);
  CHECK(refused.status == 2);
  CHECK(refused.err ==
        "doorbench: " + run.string() + ": exists (give --overwrite to replace it)\n");
  CHECK(read_file(run) == "old\n");
  const DoorbenchRun replaced = run_doorbench_shell(simulate + " --overwrite", dir);
  INFO(replaced.err);
  CHECK(replaced.status == 0);
  CHECK(read_file(run) != "old\n");

  const fs::path grid = dir.write("grid.csv", "theta_rad,omega_rad_s\n0.1,0\n0.2,0.5\n");
  const DoorbenchRun onto_grid = run_doorbench_shell(
      "model torque --in " + grid.string() + " --out " + grid.string() + " --overwrite", dir);
  CHECK(onto_grid.status == 2);
  CHECK(onto_grid.err ==
        "doorbench: " + grid.string() +
            ": is an input of this command (doorbench never writes onto its input)\n");

  const fs::path session = dir / "imported.h5";
  const DoorbenchRun imported =
      run_doorbench_shell("import " + run.string() + " --out " + session.string(), dir);
  INFO(imported.err);
  CHECK(imported.status == 0);
  const DoorbenchRun twice =
      run_doorbench_shell("import " + run.string() + " --out " + session.string(), dir);
  CHECK(twice.status == 2);
  CHECK(twice.err ==
        "doorbench: " + session.string() + ": exists (sessions are never overwritten)\n");
  const DoorbenchRun onto_csv =
      run_doorbench_shell("import " + run.string() + " --out " + run.string(), dir);
  CHECK(onto_csv.status == 2);
  CHECK(onto_csv.err ==
        "doorbench: " + run.string() +
            ": is an input of this command (doorbench never writes onto its input)\n");
}

TEST_CASE("Outputs: fit and loop check their input before creating --out", "[outputs][cli]") {
  const TempDir dir("output_fit");
  const fs::path bad = dir.write("random.csv", "time_s,force_N\n0,1\n");
  for (const std::string verb : {"fit", "loop"}) {
    const fs::path out = dir / (verb + "-out");
    const DoorbenchRun run =
        run_doorbench_shell(verb + " " + bad.string() + " --out " + out.string(), dir);
    INFO(run.err);
    CHECK(run.status == 1);
    CHECK(!fs::exists(out));
  }
  // An --out folder that is not empty is refused before any work; so is one that holds DATA.
  const fs::path used = dir / "used";
  fs::create_directories(used);
  std::ofstream(used / "result.json") << "{}\n";
  const DoorbenchRun refused =
      run_doorbench_shell("fit " + bad.string() + " --out " + used.string(), dir);
  CHECK(refused.status == 2);
  CHECK(refused.err == "doorbench: " + used.string() +
                           ": exists and is not empty (give --overwrite to write into it)\n");
  CHECK(read_file(used / "result.json") == "{}\n");
  const DoorbenchRun holds = run_doorbench_shell(
      "fit " + bad.string() + " --out " + dir.path.string() + " --overwrite", dir);
  CHECK(holds.status == 2);
  CHECK(holds.err == "doorbench: " + dir.path.string() + ": holds an input of this command (" +
                         bad.string() + ") (doorbench never writes onto its input)\n");
  // A link in the folder to the input: --overwrite must not replace the link.
  const fs::path linked = dir / "linked";
  fs::create_directories(linked);
  fs::create_symlink(bad, linked / "result.json");
  const DoorbenchRun link = run_doorbench_shell(
      "fit " + bad.string() + " --out " + linked.string() + " --overwrite", dir);
  CHECK(link.status == 2);
  CHECK(link.err == "doorbench: " + (linked / "result.json").string() +
                        ": is an input of this command (" + bad.string() +
                        ") (doorbench never writes onto its input)\n");
  CHECK(fs::is_symlink(linked / "result.json"));
}

TEST_CASE("Outputs: spec refuses a folder that is not empty before any work", "[outputs][cli]") {
  const TempDir dir("output_spec");
  const fs::path out = dir / "spec";
  fs::create_directories(out);
  std::ofstream(out / "spec.json") << "{}\n";
  // Inputs that would fail if read: the refusal comes first.
  const fs::path tobe = dir.write("tobe.csv", "not a recording\n");
  const fs::path asis = dir.write("asis.json", "not a door\n");
  const DoorbenchRun run = run_doorbench_shell(
      "spec " + tobe.string() + " --asis " + asis.string() + " --out " + out.string(), dir);
  CHECK(run.status == 2);
  CHECK(run.err == "doorbench: " + out.string() +
                       ": exists and is not empty (give --overwrite to write into it)\n");
  CHECK(read_file(out / "spec.json") == "{}\n");
}

TEST_CASE("Outputs: calibration certificates follow the rule", "[outputs][cli]") {
  const TempDir dir("output_certificate");
  const fs::path session = small_session(dir);
  const fs::path certificate = dir / "cert.html";
  std::ofstream(certificate) << "old\n";
  const DoorbenchRun existing = run_doorbench_shell(
      "calibrate gyro --from " + session.string() + " --certificate " + certificate.string(), dir);
  CHECK(existing.status == 2);
  CHECK(existing.err ==
        "doorbench: " + certificate.string() + ": exists (give --overwrite to replace it)\n");
  CHECK(read_file(certificate) == "old\n");
  const DoorbenchRun onto =
      run_doorbench_shell("calibrate gyro --from " + session.string() + " --certificate " +
                              session.string() + " --overwrite",
                          dir);
  CHECK(onto.status == 2);
  CHECK(onto.err == "doorbench: " + session.string() +
                        ": is an input of this command (doorbench never writes onto its input)\n");
  const DoorbenchRun store =
      run_doorbench_shell("calibration certificate some-id --out " + certificate.string(), dir);
  CHECK(store.status == 2);
  CHECK(store.err ==
        "doorbench: " + certificate.string() + ": exists (give --overwrite to replace it)\n");
}

TEST_CASE("Outputs: a full disk leaves the old file or nothing, and the message names the path",
          "[outputs][cli]") {
  const TempDir dir("output_full");
  const fs::path session = small_session(dir);

  SECTION("a file size limit (write fails with EFBIG)") {
    const fs::path csv = dir / "limited.csv";
    // 64 blocks of 512 bytes: 32 KiB, far less than the export.
    const std::string limit = "trap '' XFSZ\nulimit -f 64\n";  // SIGXFSZ ignored: write() fails
    const DoorbenchRun run =
        run_script(limit + "doorbench export " + session.string() + " --csv " + csv.string(), dir);
    CHECK(run.status == 1);
    CHECK(run.err == "doorbench: " + csv.string() + ": cannot write: File too large\n");
    CHECK(!fs::exists(csv));
    CHECK(files_in(dir.path).find(".partial") == std::string::npos);
    // The old file stays as it was.
    std::ofstream(csv) << "old\n";
    const DoorbenchRun over = run_script(
        limit + "doorbench export " + session.string() + " --csv " + csv.string() + " --overwrite",
        dir);
    CHECK(over.status == 1);
    CHECK(read_file(csv) == "old\n");
  }
  SECTION("a full tmpfs") {
    const fs::path mount_point = dir / "full";
    const fs::path csv = mount_point / "s.csv";
    DoorbenchRun run;
    if (!run_on_full_tmpfs(mount_point, "echo old > '" + csv.string() + "'",
                           "export " + session.string() + " --csv " + csv.string() + " --overwrite",
                           "ls -A '" + mount_point.string() + "'; cat '" + csv.string() + "'", dir,
                           run)) {
      WARN("mounting a tmpfs is not permitted here: the file size limit above stands in");
      return;
    }
    CHECK(run.status == 1);
    CHECK(run.err == "doorbench: " + csv.string() + ": cannot write: No space left on device\n");
    CHECK(run.out == "s.csv\nold\n");  // the old file, and no partial file beside it

    const fs::path csv_source = dir / "s-source.csv";
    REQUIRE(run_doorbench_shell("export " + session.string() + " --csv " + csv_source.string(), dir)
                .status == 0);
    const fs::path imported = mount_point / "i.h5";
    DoorbenchRun import;
    REQUIRE(run_on_full_tmpfs(mount_point, "",
                              "import " + csv_source.string() + " --out " + imported.string(),
                              "ls -A '" + mount_point.string() + "'", dir, import));
    CHECK(import.status == 1);
    CHECK(import.err.rfind("doorbench: " + imported.string() + ": cannot write: ", 0) == 0);
    CHECK(import.out.empty());  // nothing left under the session's name, no partial file

    const fs::path run_csv = mount_point / "run.csv";
    DoorbenchRun simulate;
    REQUIRE(run_on_full_tmpfs(
        mount_point, "",
        "simulate --model sensory --hand open-close --duration-s 2 --out " + run_csv.string(),
        "ls -A '" + mount_point.string() + "'", dir, simulate));
    CHECK(simulate.status == 1);
    CHECK(simulate.err ==
          "doorbench: " + run_csv.string() + ": cannot write: No space left on device\n");
    CHECK(simulate.out.empty());
  }
}

TEST_CASE("Outputs: write_file_atomically keeps the old file when the writer fails", "[outputs]") {
  const TempDir dir("output_atomic");
  const fs::path file = dir / "a.txt";
  doorbench::write_text_file_atomically(file, "first\n");
  CHECK(read_file(file) == "first\n");
  CHECK_THROWS_WITH(doorbench::write_file_atomically(file,
                                                     [](std::ostream& out) {
                                                       out << "half";
                                                       throw std::runtime_error("stopped");
                                                     }),
                    "stopped");
  CHECK(read_file(file) == "first\n");
  CHECK(files_in(dir.path) == "a.txt ");
  const fs::path missing = dir / "no-such-folder" / "b.txt";
  CHECK_THROWS_WITH(doorbench::write_text_file_atomically(missing, "x"),
                    missing.string() + ": cannot write: No such file or directory");
}

TEST_CASE("Outputs: remove_output_not_written removes a file or a link, never a link's target",
          "[outputs]") {
  const TempDir dir("output_remove");
  const fs::path file = dir.write("plot.svg", "earlier\n");
  doorbench::remove_output_not_written(file);
  CHECK_FALSE(fs::exists(file));
  doorbench::remove_output_not_written(file);  // nothing there: nothing to do
  const fs::path target = dir.write("kept.txt", "kept\n");
  fs::create_symlink(target, dir / "link.svg");
  doorbench::remove_output_not_written(dir / "link.svg");
  CHECK_FALSE(fs::is_symlink(dir / "link.svg"));
  CHECK(read_file(target) == "kept\n");
  // What cannot be removed is named with the system's reason.
  fs::create_directories(dir / "full.svg");
  std::ofstream(dir / "full.svg" / "inside") << "x\n";
  CHECK_THROWS_WITH(doorbench::remove_output_not_written(dir / "full.svg"),
                    (dir / "full.svg").string() + ": cannot remove: Directory not empty");
}

TEST_CASE("Outputs: remove_output_folder removes a folder whole, or names what it cannot",
          "[outputs]") {
  const TempDir dir("output_remove_folder");
  fs::create_directories(dir / "campaign" / "answers");
  std::ofstream(dir / "campaign" / "answers" / "trials.csv") << "x\n";
  doorbench::remove_output_folder(dir / "campaign");
  CHECK_FALSE(fs::exists(dir / "campaign"));
  doorbench::remove_output_folder(dir / "campaign");  // nothing there: nothing to do
  const fs::path under_file = dir.write("a.txt", "kept\n") / "sub";
  CHECK_THROWS_WITH(doorbench::remove_output_folder(under_file),
                    under_file.string() + ": cannot remove: Not a directory");
  CHECK(read_file(dir / "a.txt") == "kept\n");
}

TEST_CASE("Outputs: remove_outputs_not_written removes only such outputs not written",
          "[outputs]") {
  const TempDir dir("output_remove_named");
  dir.write("ratings-a.svg", "now\n");
  dir.write("ratings-b.svg", "earlier\n");
  dir.write("notes.txt", "the user's\n");
  const auto is_rating = [](const std::string& name) { return name.starts_with("ratings-"); };
  doorbench::remove_outputs_not_written(dir.path, is_rating, {"ratings-a.svg"});
  CHECK(fs::exists(dir / "ratings-a.svg"));
  CHECK_FALSE(fs::exists(dir / "ratings-b.svg"));
  CHECK(fs::exists(dir / "notes.txt"));
  doorbench::remove_outputs_not_written(dir / "absent", is_rating, {});  // no folder: nothing
  CHECK_FALSE(fs::exists(dir / "absent"));
}

// Rule 5 on the verb: a second fit with --overwrite into the same folder that adds no effect
// and ends with a fit that runs no global stage (--free auto's refit) leaves no
// fitted-effects.json or global-search.svg of the first.
TEST_CASE("Outputs: fit --overwrite removes the outputs of an earlier run it does not write",
          "[outputs][cli]") {
  const TempDir dir("output_fit_stale");
  const fs::path session = small_session(dir);
  const fs::path out = dir / "out";
  const std::string fit =
      "fit " + session.string() + " --folds 0 --out " + out.string() + " --overwrite";
  const DoorbenchRun first = run_doorbench_shell(fit + " --effects viscous_damping", dir);
  INFO(first.err);
  REQUIRE(first.status == 0);
  REQUIRE(fs::exists(out / "fitted-effects.json"));
  std::ofstream(out / "global-search.svg") << "<svg/>\n";  // as an earlier search drew it
  const DoorbenchRun second = run_doorbench_shell(fit + " --free auto", dir);
  INFO(second.err);
  REQUIRE(second.status == 0);
  CHECK_FALSE(fs::exists(out / "fitted-effects.json"));
  CHECK_FALSE(fs::exists(out / "global-search.svg"));
  CHECK(fs::exists(out / "result.json"));
  CHECK(read_file(out / "report.md").find("global-search.svg") == std::string::npos);
}

// Rule 5 between fit's two kinds of run: --init-only into a whole fit's folder leaves none of
// its files, and a whole fit into an --init-only folder leaves no start files; a file of the
// user's stays through both.
TEST_CASE("Outputs: fit --init-only and a whole fit each remove the other's earlier outputs",
          "[outputs][cli]") {
  const TempDir dir("output_fit_init_only");
  const fs::path session = small_session(dir);
  const fs::path out = dir / "out";
  const std::string fit =
      "fit " + session.string() + " --folds 0 --out " + out.string() + " --overwrite";
  const DoorbenchRun whole = run_doorbench_shell(fit, dir);
  INFO(whole.err);
  REQUIRE(whole.status == 0);
  std::ofstream(out / "global-search.svg") << "<svg/>\n";  // as an earlier search drew it
  std::ofstream(out / "notes.txt") << "the operator's notes\n";
  const DoorbenchRun init = run_doorbench_shell(fit + " --init-only", dir);
  INFO(init.err);
  REQUIRE(init.status == 0);
  CHECK(files_in_order(out) ==
        std::vector<std::string>{"notes.txt", "start-params.json", "start.md"});
  const DoorbenchRun again = run_doorbench_shell(fit, dir);
  INFO(again.err);
  REQUIRE(again.status == 0);
  CHECK_FALSE(fs::exists(out / "start-params.json"));
  CHECK_FALSE(fs::exists(out / "start.md"));
  CHECK(fs::exists(out / "result.json"));
  CHECK(read_file(out / "notes.txt") == "the operator's notes\n");
}

TEST_CASE("Outputs: a PDF not rendered leaves no earlier PDF behind", "[outputs]") {
  const TempDir dir("output_pdf_stale");
  const fs::path html = dir.write("report.html", "<html><body>now</body></html>\n");
  const fs::path pdf = dir.write("report.pdf", "%PDF of an earlier run\n");
  CHECK(doorbench::render_pdf(html, pdf, "/bin/false") ==
        "/bin/false failed (see " + pdf.string() + ".log)");
  CHECK_FALSE(fs::exists(pdf));
  dir.write("report.pdf", "%PDF of an earlier run\n");
  CHECK(doorbench::render_pdf(html, pdf, "no-such-renderer") ==
        "no-such-renderer is not installed");
  CHECK_FALSE(fs::exists(pdf));
}
