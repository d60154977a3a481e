#pragma once
/// \file `hil import`: a marker-plus-force-plate table -> a run (run.yaml + samples.csv).
/// Pure steps (read the table, turn it into samples) with the file I/O at the edges.
#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/format/samples.hpp>
#include <hil/import/config.hpp>

namespace hil::import {

/// The options of the one CSV reader (format::parse_csv) for a data file: the config's delimiter,
/// its header line or its column names, a byte-order mark and blank lines skipped, and every
/// column kept as text (import_table reads the numbers, an empty or NaN cell being missing).
format::CsvOptions data_options(char delimiter, bool header, const std::vector<std::string>& names, const std::string& display_name = "");
/// format::read_csv with data_options. \throws error::FormatError naming file, line and column.
format::CsvTable read_delimited(const std::string& path, char delimiter, bool header, const std::vector<std::string>& names);

struct Gap {
  double t_s = 0;   ///< time of the sample after the gap
  double dt_s = 0;  ///< the step
  std::size_t line = 0;
};
struct DropCount {
  std::string reason;
  std::size_t count = 0;
  std::size_t first_line = 0;
};
struct BodyStats {
  std::string name;
  bool is_ee = false;
  std::size_t markers = 0;
  std::size_t reference_rows_used = 0;  ///< 0 when the reference was given
  std::size_t fitted = 0;               ///< rows (of those written) with a pose
  std::size_t reduced = 0;              ///< of those, fitted with some markers unseen
  std::size_t no_pose = 0;              ///< rows written without a pose of this body (not the ee)
  double rms_mean_m = 0, rms_median_m = 0, rms_max_m = 0;
  Eigen::Vector3d p_range_m = Eigen::Vector3d::Zero();      ///< max - min of p_world_body per axis
  Eigen::Vector3d rot_range_rad = Eigen::Vector3d::Zero();  ///< max - min of the rotation vector of R0^T R, per axis
  double max_displacement_m = 0;                            ///< max |p - p(first row)|
  double max_rotation_rad = 0;                              ///< max angle of R(first row)^T R
};
struct ImportReport {
  std::string data_file, config_file;
  std::size_t rows_read = 0, rows_written = 0;
  std::vector<DropCount> dropped;
  double duration_s = 0, median_dt_s = 0, min_dt_s = 0, max_dt_s = 0;
  std::vector<Gap> gaps;  ///< steps longer than gap_factor * median step (kept)
  std::vector<BodyStats> bodies;
  std::string start_time_utc;
  bool clock_taken_as_utc = false;
  Eigen::Vector3d f_min_n = Eigen::Vector3d::Zero(), f_max_n = Eigen::Vector3d::Zero();
  std::size_t extra_missing = 0;  ///< extra cells that were empty or NaN (written as nan)
};

struct ImportedRun {
  format::RunInfo info;
  format::SampleTable table;             ///< samples, joints, and the source line of each
  std::vector<std::string> extra_names;  ///< extra samples.csv columns, after the joints
  Eigen::MatrixXd extra_values;          ///< rows = samples; NaN where unknown
  ImportReport report;
};

/// Turns the table (read with data_options: every column text) into a run following the config. `rig_name` overrides the config's `rig`.
/// \throws error::FormatError naming the data file (line, column) or the config.
ImportedRun import_table(const format::CsvTable& data, const ImportConfig& config, const std::string& rig_name = "");

/// Writes run.yaml and samples.csv (required columns, j1..jN, then the extra columns) into `dir`
/// (created if needed). Numbers are written in the shortest form that reads back exactly.
void write_imported_run(const std::string& dir, const ImportedRun& run);

/// A few lines for people: rows, time, gaps, fit residuals, motion range, wrench range.
std::string report_text(const ImportReport& report);

}  // namespace hil::import
