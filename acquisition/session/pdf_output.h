#pragma once
// HTML reports to PDF with an external renderer (weasyprint, from Debian), under the output
// rule (output_file.h): the renderer writes the PDF's temporary file, which is renamed onto
// the PDF only when the renderer succeeded; its output goes to "PDF.log", removed on success
// and kept (and named) on failure. Both reports (spec.pdf, report.pdf) are rendered here.
//
// The renderer runs as a child process that the caller's stop hook can end: asked every
// 20 ms while the renderer runs, a stop kills it (SIGTERM) and throws StopRequested("the PDF
// rendering"), leaving no PDF. (std::system would not do: it ignores SIGINT in the caller
// while the child runs, so a Ctrl-C would be lost.)
//
// Thread safety: free functions without shared state.
#include <filesystem>
#include <string>

#include "core/stop_request.h"

namespace doorbench {

// The renderer's path when `name` is an executable on PATH (or a path to one), else "".
std::string find_executable(const std::string& name);

// Renders `html` to `pdf` with `renderer` (empty: weasyprint from PATH). An earlier file at
// `pdf` is removed first (output rule 5), so that after a failure or a stop there is no PDF
// rather than another run's. Returns "" when the PDF was written, else why not: "weasyprint is not
// installed (scripts/install-deps.sh installs it)", "weasyprint failed (see PDF.log)". Throws
// StopRequested when `stop` asked, OutputError when the earlier PDF cannot be removed.
std::string render_pdf(const std::filesystem::path& html, const std::filesystem::path& pdf,
                       const std::string& renderer = "", const StopHook& stop = {});

}  // namespace doorbench
