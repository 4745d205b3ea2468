// doorbench: record, model, fit and play back the feel of a product mechanism.
// Exit status: 0 success, 1 failure, 2 bad usage, 128 + N when signal N stopped a verb
// that writes what it finished, marked interrupted (app/stop_signals.h). Errors go to stderr
// on one line; a usage error points at the verb's own help (`doorbench VERB --help`, also
// `doorbench help VERB`).
#include <fcntl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <streambuf>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "acquisition/session/printable.h"
#include "app/commands.h"
#include "app/stop_signals.h"
#include "core/stop_request.h"

namespace {

// CLI11 reports a mistyped verb only as "a subcommand is required"; name the word instead.
std::string unknown_verb_message(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";
    const auto subcommands = level->get_subcommands([](const CLI::App*) { return true; });
    const CLI::App* next = nullptr;
    std::string expected;
    for (const CLI::App* sub : subcommands) {
      if (sub->get_name() == word) next = sub;
      expected += (expected.empty() ? "" : ", ") + sub->get_name();
    }
    if (next == nullptr) {
      if (subcommands.empty()) return "";
      return "unknown verb '" + path + word + "' (expected " + expected + ")";
    }
    path += word + " ";
    level = next;
  }
  return "";
}

// The verb the command line names, as "fit" or "hapticmaster check" (words that name a
// subcommand at each level, options and their values skipped); "" when none.
std::string named_verb(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') continue;
    const CLI::App* next = nullptr;
    for (const CLI::App* sub : level->get_subcommands([](const CLI::App*) { return true; })) {
      if (sub->get_name() == word) next = sub;
    }
    if (next == nullptr) continue;
    path += (path.empty() ? "" : " ") + word;
    level = next;
  }
  return path;
}

// Where to read about a usage error: the verb's own help when a verb was named.
std::string help_hint(const CLI::App& app, int argc, char** argv) {
  const std::string verb = named_verb(app, argc, argv);
  return " (see doorbench " + (verb.empty() ? std::string() : verb + " ") + "--help)";
}

// `doorbench help [VERB...]` is `doorbench [VERB...] --help`: the words are checked here
// (an unknown one is a usage error, exit 2, with the expected verbs) and `args` becomes the
// command line with --help. Returns false after printing the error.
bool help_command_line(const CLI::App& app, int argc, char** argv, std::vector<std::string>& args) {
  const CLI::App* level = &app;
  std::string path;
  args = {argv[0]};
  for (int i = 2; i < argc; ++i) {
    const std::string word = argv[i];
    const CLI::App* next = nullptr;
    std::string expected;
    for (const CLI::App* sub : level->get_subcommands([](const CLI::App*) { return true; })) {
      if (sub->get_name() == word) next = sub;
      expected += (expected.empty() ? "" : ", ") + sub->get_name();
    }
    if (next == nullptr) {
      std::cerr << "doorbench: help: unknown verb '" << doorbench::printable(path + word) << "'"
                << (expected.empty() ? "" : " (expected " + expected + ")")
                << " (see doorbench --help)\n";
      return false;
    }
    path += word + " ";
    args.push_back(word);
    level = next;
  }
  args.push_back("--help");
  return true;
}

// --quiet: stderr's progress, stage and warning lines are dropped while the verb runs;
// its error (printed by main after the verb returns) and stdout are kept.
// Lines written with stdio (fprintf(stderr, ...): record's live status) go too: file
// descriptor 2 points at /dev/null meanwhile, so -q silences record's status lines too.
class QuietStderr {
 public:
  explicit QuietStderr(bool quiet) : saved_(quiet ? std::cerr.rdbuf(&null_) : nullptr) {
    if (!quiet) return;
    std::fflush(stderr);
    saved_fd_ = ::dup(2);
    const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_fd_ >= 0 && null_fd >= 0) ::dup2(null_fd, 2);
    if (null_fd >= 0) ::close(null_fd);
  }
  ~QuietStderr() { restore(); }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;
  void restore() {
    if (saved_ != nullptr) std::cerr.rdbuf(saved_);
    saved_ = nullptr;
    if (saved_fd_ >= 0) {
      std::fflush(stderr);
      ::dup2(saved_fd_, 2);
      ::close(saved_fd_);
      saved_fd_ = -1;
    }
  }

 private:
  struct NullBuffer : std::streambuf {
    int overflow(int c) override { return traits_type::not_eof(c); }
  } null_;
  std::streambuf* saved_;
  int saved_fd_ = -1;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "doorbench: measure a door's feel on the bench, fit models to it and play it back.\n"
      "Run `doorbench help VERB` (or `doorbench VERB --help`) for each verb."};
  app.set_version_flag("-V,--version", std::string("doorbench ") + DOORBENCH_VERSION);
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet,
               "No progress, stage or warning lines on stderr (errors still); before or after "
               "the verb");
  app.fallthrough(true);  // every verb takes --quiet too
  doorbench::app::Action action;
  doorbench::app::add_all_verbs(app, action);

  // `doorbench help VERB`: parsed as `doorbench VERB --help`.
  std::vector<std::string> help_args;
  std::vector<char*> help_argv;
  if (argc >= 2 && std::string(argv[1]) == "help") {
    if (!help_command_line(app, argc, argv, help_args)) return 2;
    for (std::string& arg : help_args) help_argv.push_back(arg.data());
    argc = int(help_argv.size());
    argv = help_argv.data();
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    // `doorbench NOSUCHVERB --help`: the word is a mistake, not a request for help.
    if (const std::string message = unknown_verb_message(app, argc, argv); !message.empty()) {
      std::cerr << "doorbench: " << doorbench::printable(message) << " (see doorbench --help)\n";
      return 2;
    }
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForVersion& version) {
    return app.exit(version);
  } catch (const CLI::ParseError& error) {
    std::string message = unknown_verb_message(app, argc, argv);
    if (message.empty()) message = error.what();
    std::cerr << "doorbench: " << doorbench::printable(doorbench::shortened(message))
              << help_hint(app, argc, argv) << "\n";
    return 2;
  }

  QuietStderr quiet_stderr(quiet);
  try {
    if (action) action();
    return 0;
  } catch (const doorbench::app::UsageError& error) {
    quiet_stderr.restore();
    std::cerr << "doorbench: " << doorbench::printable(doorbench::shortened(error.what()))
              << help_hint(app, argc, argv) << "\n";
    return 2;
  } catch (const doorbench::app::Interrupted& error) {  // its marked result is written
    quiet_stderr.restore();
    std::cerr << "doorbench: " << doorbench::printable(error.what()) << "\n";
    return error.exit_status();
  } catch (const doorbench::StopRequested& stop) {  // a verb that did not say what it kept
    quiet_stderr.restore();
    std::cerr << "doorbench: " << stop.what() << "\n";
    return 1;
  } catch (const doorbench::OutputRefused& error) {  // an existing output, or an input
    quiet_stderr.restore();
    std::cerr << "doorbench: " << doorbench::printable(doorbench::shortened(error.what())) << "\n";
    return 2;
  } catch (const std::exception& error) {
    quiet_stderr.restore();
    // Messages quote files' text: control characters are shown escaped.
    std::cerr << "doorbench: " << doorbench::printable(doorbench::shortened(error.what())) << "\n";
    return 1;
  }
}
