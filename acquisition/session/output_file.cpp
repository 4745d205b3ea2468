#include "acquisition/session/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <streambuf>
#include <system_error>

namespace doorbench {
namespace fs = std::filesystem;

namespace {

std::string system_error(int error) {
  return std::strerror(error);
}

// The same file: device and inode (so hard links, symbolic links and other spellings of
// one path are caught). False when either does not exist.
bool same_file(const fs::path& a, const fs::path& b) {
  struct stat sa {};
  struct stat sb {};
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

// A stream buffer on a file descriptor that remembers the first write error (errno).
class FdBuffer : public std::streambuf {
 public:
  explicit FdBuffer(int fd) : fd_(fd) { setp(buffer_, buffer_ + sizeof buffer_); }
  int error() const { return error_; }
  bool drain() {
    const char* data = pbase();
    std::size_t left = static_cast<std::size_t>(pptr() - pbase());
    while (left > 0 && error_ == 0) {
      const ssize_t written = ::write(fd_, data, left);
      if (written < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        break;
      }
      data += written;
      left -= static_cast<std::size_t>(written);
    }
    setp(buffer_, buffer_ + sizeof buffer_);
    return error_ == 0;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  int fd_;
  int error_ = 0;
  char buffer_[1 << 16];
};

void sync_folder(const fs::path& path) {
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // the rename is done; a folder that cannot be synced is no failure
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void check_output_file(const fs::path& output, const std::vector<fs::path>& inputs,
                       bool overwrite) {
  const std::string where = output.string() + ": ";
  for (const fs::path& input : inputs) {
    if (same_file(output, input)) {
      throw OutputRefused(where +
                          "is an input of this command (doorbench never writes onto its input)");
    }
  }
  std::error_code error;
  const fs::file_status status = fs::symlink_status(output, error);
  if (!fs::exists(status)) return;
  if (fs::is_directory(fs::status(output, error))) {
    throw OutputRefused(where + "is a directory, not a file");
  }
  // A device, pipe or socket (e.g. --csv /dev/null as root): the temporary file renamed onto
  // it would replace the node itself, so it is refused even with --overwrite.
  const fs::file_status target = fs::status(output, error);
  if (fs::exists(target) && !fs::is_regular_file(target)) {
    throw OutputRefused(where +
                        "is not a regular file (a device, pipe or socket): doorbench writes "
                        "through a temporary file renamed onto the name, which would replace it");
  }
  if (!overwrite) throw OutputRefused(where + "exists (give --overwrite to replace it)");
}

void check_output_session(const fs::path& output, const std::vector<fs::path>& inputs) {
  check_output_file(output, inputs, true);
  std::error_code error;
  if (fs::exists(fs::symlink_status(output, error))) {
    throw OutputRefused(output.string() + ": exists (sessions are never overwritten)");
  }
}

void check_output_folder(const fs::path& folder, const std::vector<fs::path>& inputs,
                         bool overwrite) {
  const std::string where = folder.string() + ": ";
  std::error_code error;
  if (!fs::exists(folder, error)) return;
  if (!fs::is_directory(folder, error))
    throw OutputRefused(where + "exists and is not a directory");
  for (const fs::path& input : inputs) {
    // The input itself, or a file in the folder (its parent is the folder).
    const fs::path parent = input.parent_path().empty() ? fs::path(".") : input.parent_path();
    if (same_file(folder, input) || same_file(folder, parent)) {
      throw OutputRefused(where + "holds an input of this command (" + input.string() +
                          ") (doorbench never writes onto its input)");
    }
  }
  if (!overwrite && !fs::is_empty(folder, error)) {
    throw OutputRefused(where + "exists and is not empty (give --overwrite to write into it)");
  }
  // A file in it that is an input under another name (a link to it): --overwrite would
  // replace that name.
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error)) {
    for (const fs::path& input : inputs) {
      if (same_file(entry.path(), input)) {
        throw OutputRefused(entry.path().string() + ": is an input of this command (" +
                            input.string() + ") (doorbench never writes onto its input)");
      }
    }
  }
}

fs::path partial_path_for(const fs::path& path) {
  fs::path partial = path;
  partial += ".partial-" + std::to_string(::getpid());
  return partial;
}

void commit_partial_file(const fs::path& partial, const fs::path& path) {
  if (::rename(partial.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(partial.c_str());
    throw OutputError(path.string() + ": cannot write: cannot rename " + partial.string() +
                      " onto it: " + system_error(error));
  }
  sync_folder(path);
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  const fs::path partial = partial_path_for(path);
  const std::string where = path.string() + ": cannot write: ";
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw OutputError(where + system_error(errno));
  int error = 0;
  {
    FdBuffer buffer(fd);
    try {
      std::ostream out(&buffer);
      write(out);
      out.flush();
      error = buffer.error();
      if (error == 0 && !out) error = EIO;  // the writer set the stream's failbit itself
    } catch (...) {
      ::close(fd);
      ::unlink(partial.c_str());
      // A writer that stops at the stream's failure: the system's error is the cause.
      if (buffer.error() != 0) throw OutputError(where + system_error(buffer.error()));
      throw;
    }
  }
  if (error == 0 && ::fsync(fd) != 0) error = errno;
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) {
    ::unlink(partial.c_str());
    throw OutputError(where + system_error(error));
  }
  commit_partial_file(partial, path);
}

void write_text_file_atomically(const fs::path& path, std::string_view text) {
  write_file_atomically(path, [text](std::ostream& out) { out << text; });
}

void remove_output_not_written(const fs::path& path) {
  std::error_code error;
  fs::remove(path, error);
  if (error) throw OutputError(path.string() + ": cannot remove: " + error.message());
}

void remove_output_folder(const fs::path& folder) {
  std::error_code error;
  fs::remove_all(folder, error);
  if (error) throw OutputError(folder.string() + ": cannot remove: " + error.message());
}

void remove_outputs_not_written(const fs::path& folder,
                                const std::function<bool(const std::string&)>& is_such_output,
                                const std::vector<std::string>& written) {
  std::error_code error;
  if (!fs::exists(folder, error)) return;
  std::vector<fs::path> stale;
  for (fs::directory_iterator entry(folder, error), end; !error && entry != end;
       entry.increment(error)) {
    const std::string name = entry->path().filename().string();
    if (is_such_output(name) && std::find(written.begin(), written.end(), name) == written.end())
      stale.push_back(entry->path());
  }
  if (error) throw OutputError(folder.string() + ": cannot read: " + error.message());
  for (const fs::path& path : stale) remove_output_not_written(path);
}

}  // namespace doorbench
