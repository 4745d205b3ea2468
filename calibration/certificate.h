#pragma once
// The calibration certificate: one self-contained HTML page per record (print it to PDF
// from a browser): who, what, when and how; the coefficients; the results with their
// uncertainties; the reference points with their residuals and a residual plot (SVG);
// and the uncertainty statement.
#include <filesystem>
#include <string>

#include "acquisition/rig/calibration_record.h"

namespace doorbench::calibration {

std::string certificate_html(const CalibrationRecord& record);
// Writes the certificate whole or not at all (acquisition/session/output_file.h); throws
// OutputError "PATH: cannot write: SYSTEM ERROR". The commands refuse an existing file first.
void write_certificate(const std::filesystem::path& path, const CalibrationRecord& record);

}  // namespace doorbench::calibration
