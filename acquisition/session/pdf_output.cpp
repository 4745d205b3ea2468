#include "acquisition/session/pdf_output.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <system_error>
#include <thread>
#include <vector>

#include "acquisition/session/output_file.h"

extern char** environ;

namespace doorbench {
namespace {

bool is_executable_file(const std::filesystem::path& path) {
  struct stat status {};
  return ::stat(path.c_str(), &status) == 0 && S_ISREG(status.st_mode) &&
         ::access(path.c_str(), X_OK) == 0;
}

// Runs `argv` with stdout and stderr into `log`; its exit status (-1: it could not start or a
// signal ended it). Kills it and throws StopRequested when `stop` asks meanwhile.
int run_child(const std::vector<std::string>& argv, const std::filesystem::path& log,
              const StopHook& stop) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> args;
  std::vector<std::string> storage = argv;
  for (std::string& arg : storage) args.push_back(arg.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  for (;;) {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (done < 0 && errno != EINTR) return -1;
    if (stop_requested(stop)) {
      ::kill(pid, SIGTERM);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      throw StopRequested("the PDF rendering");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

std::string find_executable(const std::string& name) {
  if (name.find('/') != std::string::npos) return is_executable_file(name) ? name : "";
  const char* path = std::getenv("PATH");
  const std::string folders = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t begin = 0;
  while (begin <= folders.size()) {
    const std::size_t end = std::min(folders.find(':', begin), folders.size());
    const std::filesystem::path candidate =
        std::filesystem::path(end > begin ? folders.substr(begin, end - begin) : ".") / name;
    if (is_executable_file(candidate)) return candidate.string();
    begin = end + 1;
  }
  return "";
}

std::string render_pdf(const std::filesystem::path& html, const std::filesystem::path& pdf,
                       const std::string& renderer, const StopHook& stop) {
  remove_output_not_written(pdf);
  const std::string name = renderer.empty() ? "weasyprint" : renderer;
  const std::string program = find_executable(name);
  if (program.empty()) {
    return name + " is not installed" +
           (renderer.empty() ? " (scripts/install-deps.sh installs it)" : "");
  }
  const std::filesystem::path partial = partial_path_for(pdf);
  std::filesystem::path log = pdf;
  log += ".log";
  std::error_code ignored;
  int status = -1;
  try {
    status = run_child({program, html.string(), partial.string()}, log, stop);
  } catch (const StopRequested&) {
    std::filesystem::remove(partial, ignored);
    std::filesystem::remove(log, ignored);
    throw;
  }
  if (status != 0 || !std::filesystem::exists(partial)) {
    std::filesystem::remove(partial, ignored);
    return name + " failed (see " + log.string() + ")";
  }
  commit_partial_file(partial, pdf);
  std::filesystem::remove(log, ignored);
  return "";
}

}  // namespace doorbench
