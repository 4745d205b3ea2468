#pragma once
// A recording read from its file and prepared into strokes (preprocessing.h): a session
// (HDF5, told by its signature) or a recording in the CSV exchange format, whose empty cells
// are missing samples. What `fit`, `loop` and the specification read.
//
// Errors: std::runtime_error naming the file ("PATH: not an HDF5 file ..."), and what the
// session and CSV readers and prepare() throw.
// Thread safety: pure functions of the files read.
#include <string>
#include <string_view>

#include "analysis/preprocessing/preprocessing.h"

namespace doorbench {

// Whether `path` is an HDF5 file (a session), by its signature. Throws std::runtime_error
// when it cannot be opened.
bool is_hdf5_file(const std::string& path);

// The start of the warning for a session's channel cut short ("a channel ends before the
// others: ..."), which report.md repeats.
inline constexpr std::string_view kCutShortWarning = "a channel ends before the others: ";

// The recording at `path`, prepared. A file named *.h5 or *.hdf5 that is not HDF5 is refused
// ("PATH: not an HDF5 file ..."). A handle radius the recording states gets its origin named
// for the file's kind (PreparedData::handle_radius_origin). A CSV whose columns are not the
// exchange format's is refused at its header's line with its columns and how to import it.
// Each of the recording's unit_doubts (acquisition/session/recording_csv.h) is a warning
// starting with kUnitDoubtWarning, before preprocessing's warnings.
PreparedData load_prepared_data(const std::string& path,
                                const PreprocessingOptions& preprocessing = {});

}  // namespace doorbench
