#pragma once
/// \file `hil import`: a marker-plus-force-plate table -> a run (run.yaml + samples.csv).
/// Pure steps (read the table, turn it into samples) with the file I/O at the edges.
#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "hil/format/run.hpp"
#include "hil/format/samples.hpp"
#include "hil/import/config.hpp"

namespace hil::import {

/// A delimited text table, cells kept as text.
struct RawTable {
  std::string file;
  std::vector<std::string> names;  ///< column names (from the header or the config)
  std::size_t header_line = 0;     ///< 0 when the file has no header
  std::vector<std::vector<std::string>> rows;
  std::vector<std::size_t> line;  ///< 1-based file line of each row
};

/// Splits `text` into rows. With `header`, the first non-comment line names the columns; without,
/// `names` do. Lines starting with '#' and blank lines are skipped; ragged rows and a truncated last
/// line are errors. \throws format::FormatError.
RawTable parse_delimited(std::string_view text, const std::string& display_name, char delimiter, bool header,
                         const std::vector<std::string>& names);
RawTable read_delimited(const std::string& path, char delimiter, bool header, const std::vector<std::string>& names);

/// A cell read as a number: ok, missing (empty or NaN), or not a number.
enum class CellKind { number, missing, bad };
CellKind parse_cell(std::string_view cell, double& value);

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
  Eigen::Vector3d p_range_m = Eigen::Vector3d::Zero();     ///< max - min of p_world_body per axis
  Eigen::Vector3d rot_range_rad = Eigen::Vector3d::Zero();  ///< max - min of the rotation vector of R0^T R, per axis
  double max_displacement_m = 0;  ///< max |p - p(first row)|
  double max_rotation_rad = 0;    ///< max angle of R(first row)^T R
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
  format::SampleTable table;            ///< samples, joints, and the source line of each
  std::vector<std::string> extra_names;  ///< extra samples.csv columns, after the joints
  Eigen::MatrixXd extra_values;          ///< rows = samples; NaN where unknown
  ImportReport report;
};

/// Turns the table into a run following the config. `rig_name` overrides the config's `rig`.
/// \throws format::FormatError naming the data file (line, column) or the config.
ImportedRun import_table(const RawTable& data, const ImportConfig& config, const std::string& rig_name = "");

/// Writes run.yaml and samples.csv (required columns, j1..jN, then the extra columns) into `dir`
/// (created if needed). Numbers are written in the shortest form that reads back exactly.
void write_imported_run(const std::string& dir, const ImportedRun& run);

/// A few lines for people: rows, time, gaps, fit residuals, motion range, wrench range.
std::string report_text(const ImportReport& report);

}  // namespace hil::import
