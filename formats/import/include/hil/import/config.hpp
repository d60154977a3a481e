#pragma once
/// \file The mapping config of `hil import` (docs/import.md): which columns of a marker-plus-force-plate
/// CSV hold what, in which units and frames, and which markers form which rigid body.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace hil::import {

enum class TimeFormat { seconds, datetime };
enum class NonIncreasingTime { drop, error };

struct TimeSpec {
  std::string column;
  TimeFormat format = TimeFormat::seconds;
  /// seconds: multiplier to s (unit s, ms, us or ns).
  double s_per_unit = 1.0;
  /// seconds: the absolute time of t = 0 of the file's clock (UTC ISO 8601); empty = unknown.
  std::string start_time_utc;
  /// datetime: strptime-like pattern using %Y %m %d %H %M %S %f and literal characters.
  std::string pattern = "%Y-%m-%d %H:%M:%S.%f";
  /// datetime: the clock's offset from UTC in hours (local = UTC + offset). Absent: the clock is
  /// taken as UTC and run.yaml's notes say so.
  std::optional<double> utc_offset_h;
  NonIncreasingTime non_increasing = NonIncreasingTime::drop;
  /// A step longer than gap_factor * median step is reported as a gap (and kept).
  double gap_factor = 1.5;
};

struct MarkerSpec {
  std::string name;
  std::array<std::string, 3> columns;  ///< x, y, z in the motion-capture world frame
};

enum class BodyOrigin { marker_centroid, world };

struct BodySpec {
  std::string name;
  std::vector<MarkerSpec> markers;
  /// Reference (body-frame) marker positions: either given (m) ...
  std::vector<Eigen::Vector3d> reference_body_m;  ///< same order as `markers`; empty = from rows
  /// ... or the mean world positions over the first `reference_rows` rows where every marker is seen,
  /// with the body frame's axes along the world's and its origin at `origin`.
  std::size_t reference_rows = 100;
  BodyOrigin origin = BodyOrigin::marker_centroid;
  std::size_t min_markers = 3;  ///< >= 3; rows with fewer seen markers have no pose for this body
  double max_residual_m = 0.0;  ///< > 0: rows whose fit residual RMS is larger have no pose; 0 = no limit
};

struct WrenchSpec {
  std::array<std::string, 3> force_columns;
  std::array<std::string, 3> moment_columns;
  double n_per_unit = 1.0;        ///< force unit to N
  double nm_per_unit = 1.0;       ///< moment unit to N·m
  bool measured_on_body = false;  ///< true: the data is the reaction (wrench on the body); signs flipped
  /// R_fp_data: rotation from the data's axes to the force-plate frame (from `plate_axes`).
  Eigen::Matrix3d R_fp_data = Eigen::Matrix3d::Identity();
  /// The point (force-plate frame, m) about which the data's moment is taken; moved to the plate origin.
  Eigen::Vector3d moment_point_fp_m = Eigen::Vector3d::Zero();
};

struct ExtraColumnSpec {
  std::string column;  ///< in the data
  std::string name;    ///< in samples.csv
  double scale = 1.0;  ///< multiplier
};

struct ImportConfig {
  std::string file;  ///< the config's own path, for messages and notes
  std::string rig;   ///< run.yaml `rig`
  std::string source_name = "import";
  std::string notes;

  char delimiter = ',';
  bool header = true;
  std::vector<std::string> columns;  ///< names when header is false (`NAME_xyz` expanded)

  double marker_m_per_unit = 1.0;
  bool zero_marker_is_missing = true;  ///< a marker at exactly (0, 0, 0) was not seen

  TimeSpec time;
  std::vector<BodySpec> bodies;
  std::string ee_body;  ///< the body whose pose and twist are the run's `ee`
  WrenchSpec wrench;
  std::vector<std::string> joint_columns;  ///< j1..jN in this order
  double joint_si_per_unit = 1.0;          ///< deg -> rad when unit is deg
  std::vector<ExtraColumnSpec> extras;
  double twist_window_s = 0.05;  ///< width of the centred local-line fit that differentiates the poses
};

/// Parses a mapping config. \throws error::FormatError naming file, line, column and field.
ImportConfig parse_import_config(const std::string& yaml_text, const std::string& display_name);
ImportConfig load_import_config(const std::string& path);
/// What an import config makes: "run" (this config) or "calibration_run" (calibration_import.hpp),
/// from its `kind` key (default run). \throws FormatError.
std::string import_config_kind(const std::string& path);

/// `base1_xyz` -> base1_x, base1_y, base1_z; other names unchanged.
std::vector<std::string> expand_columns(const std::vector<std::string>& names);

}  // namespace hil::import
