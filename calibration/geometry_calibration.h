#pragma once
// Geometry: the handle radius (load cell to hinge axis) and the load cell's mounting
// angle. A force tangent to the handle's arc, on a cell turned by α from the tangent,
// reads F · cos α, so the tangential force is the reading / cos α. Both are measured
// (repeated readings of a tape or calliper, a protractor) or, for the angle, estimated
// from reference forces applied tangentially. The record (sensor_kind "geometry", input
// and unit N) maps the cell's reading to the tangential force: coefficients {0, 1/cos α}.
#include <string>
#include <utility>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

struct GeometryInputs {
  std::vector<double> handle_radius_m;     // repeated measurements, at least one
  std::vector<double> mounting_angle_deg;  // measured directly (may be empty) …
  // … or estimated: {reference force applied tangentially (N), calibrated reading (N)}.
  std::vector<std::pair<double, double>> tangential_checks_N;
};

struct GeometryCalibrationOptions {
  double length_resolution_m = 0.5e-3;  // of the tape or calliper (uniform: u = res/√12)
  double angle_resolution_deg = 0.5;    // of the protractor
  std::string validate() const;
};

struct GeometryCalibration {
  CalibrationRecord record;
  double handle_radius_m = 0.0, handle_radius_std_m = 0.0;
  double mounting_angle_deg = 0.0, mounting_angle_std_deg = 0.0;
  double cos_factor = 1.0;  // cos α: the reading per tangential force
  std::string brief_report() const;
};

// `header.sensor_serial` names the bench (or the load cell's mounting). Throws
// CalibrationError without a radius, with a radius that is not > 0, or without any angle
// information.
GeometryCalibration calibrate_geometry(const GeometryInputs& inputs,
                                       const GeometryCalibrationOptions& options,
                                       const RecordHeader& header);

}  // namespace doorbench::calibration
