#pragma once
// The one rule for every file doorbench writes (docs/output-files.md):
//
// 1. An existing output is refused unless the verb was given --overwrite; an output folder is
//    refused when it exists and is not empty (check_output_file, check_output_folder).
// 2. An output is never one of the verb's inputs, --overwrite or not (the same file by any
//    path: hard links, symbolic links, `./x` and `x` are caught by comparing the device
//    and inode).
// 3. A file is written whole or not at all: its bytes go to a temporary file beside it
//    ("NAME.partial-PID"), which is flushed, fsync()ed, closed and only then renamed onto
//    NAME (write_file_atomically). On any failure the temporary file is removed, whatever
//    was at NAME before is left as it was, and the OutputError names NAME and the system's
//    error ("run.csv: cannot write: No space left on device").
// 4. Inputs are checked before outputs are made (the verbs' order of work).
// 5. An output a verb writes only on some runs (a plot, a PDF) that this run does not write is
//    removed, so that an earlier run's file, left by --overwrite, never sits beside a report
//    that does not describe it (remove_output_not_written).
//
// Thread safety: free functions without shared state; two writers of one NAME at once in
// one process are not supported (the temporary file's name holds only the process id).
#include <filesystem>
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace doorbench {

// A refused or failed output; the message starts with the output's path.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// An output refused by the rule before anything was done (a usage error: exit status 2).
class OutputRefused : public OutputError {
 public:
  using OutputError::OutputError;
};

// Throws OutputRefused for `output` when it is one of `inputs` (the same file, however named), or
// when it exists and `overwrite` is false. Messages:
//   "OUT: is an input of this command (doorbench never writes onto its input)"
//   "OUT: exists (give --overwrite to replace it)"
//   "OUT: is a directory, not a file"
void check_output_file(const std::filesystem::path& output,
                       const std::vector<std::filesystem::path>& inputs, bool overwrite);

// The same for a session (HDF5): sessions are never replaced, so an existing one is refused
// ("OUT: exists (sessions are never overwritten)").
void check_output_session(const std::filesystem::path& output,
                          const std::vector<std::filesystem::path>& inputs);

// Throws OutputRefused for a folder of outputs that exists and is not empty when `overwrite` is
// false, that is not a folder, or that is (or holds) one of `inputs`. Does not create it. Messages:
//   "DIR: exists and is not empty (give --overwrite to write into it)"
//   "DIR: exists and is not a directory"
//   "DIR: holds an input of this command (IN) (doorbench never writes onto its input)"
void check_output_folder(const std::filesystem::path& folder,
                         const std::vector<std::filesystem::path>& inputs, bool overwrite);

// The temporary file write_file_atomically writes `path` through.
std::filesystem::path partial_path_for(const std::filesystem::path& path);

// Writes `path` through its temporary file (rule 3). `write` writes the contents to the
// stream; an exception from it removes the temporary file and is passed on. Throws
// OutputError "PATH: cannot write: SYSTEM ERROR" (also for cannot create, sync, rename).
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);
void write_text_file_atomically(const std::filesystem::path& path, std::string_view text);

// Rule 5: removes `path` when it exists (a file, or a link, not what it points to); nothing when
// it does not. Throws OutputError "PATH: cannot remove: SYSTEM ERROR".
void remove_output_not_written(const std::filesystem::path& path);

// Rule 5 for outputs named by their content (a plot per attribute, a file per variant): removes
// each entry of `folder` whose name `is_such_output` accepts and that is not in `written`;
// other files are left alone. Nothing when `folder` does not exist. Throws OutputError as
// remove_output_not_written, and when the folder cannot be read.
void remove_outputs_not_written(const std::filesystem::path& folder,
                                const std::function<bool(const std::string&)>& is_such_output,
                                const std::vector<std::string>& written);

// Removes `folder` and everything in it, for a verb that owns the whole folder (the demo's
// campaign, made again on each run); nothing when it does not exist. Throws OutputError
// "FOLDER: cannot remove: SYSTEM ERROR".
void remove_output_folder(const std::filesystem::path& folder);

// Renames a complete temporary file onto `path` and syncs the folder; on failure removes
// the temporary file and throws OutputError naming `path`. For writers that make their
// own temporary file (HDF5 sessions: SessionWriter on partial_path_for(path)).
void commit_partial_file(const std::filesystem::path& partial, const std::filesystem::path& path);

}  // namespace doorbench
