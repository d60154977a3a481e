#pragma once
/// \file samples.csv: one row per synchronized sample, SI units, frames in the column names.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace hil::format {

/// One synchronized sample (a row of samples.csv).
struct Sample {
  double t_s = 0.0;  ///< seconds since run start
  Eigen::Vector3d p_world_ee_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_ee = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_world_ee_m_per_s = Eigen::Vector3d::Zero();  ///< at the ee origin
  Eigen::Vector3d w_world_ee_rad_per_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d f_fp_n = Eigen::Vector3d::Zero();   ///< force on the plate, force-plate frame
  Eigen::Vector3d m_fp_nm = Eigen::Vector3d::Zero();  ///< moment about the plate origin, force-plate frame
};

/// The required columns, in the order the writer emits them.
const std::vector<std::string>& sample_columns();

/// A whole samples.csv.
struct SampleTable {
  std::string file;
  std::vector<Sample> samples;
  Eigen::MatrixXd joints_rad;              ///< rows = samples, cols = joints (0 cols if none)
  std::vector<std::string> extra_columns;  ///< unknown columns, kept in the table but ignored
  std::vector<std::size_t> line;           ///< source line of each sample (for messages)

  std::size_t size() const { return samples.size(); }
  std::size_t joint_count() const { return static_cast<std::size_t>(joints_rad.cols()); }
};

/// Reads and checks samples.csv: required columns, finite numbers, unit quaternions, strictly
/// increasing time, joints j1..jN numbered without gaps. \throws error::FormatError naming file, line, column.
SampleTable read_samples(const std::string& path);
SampleTable parse_samples(const std::string& text, const std::string& display_name);

/// Append-only writer. Rows are kept in memory and handed to the kernel whole by flush() (one
/// write(2) of complete lines), so a process killed at any moment leaves a file that ends at a
/// row boundary and loses only what came since the last flush.
class SamplesWriter {
 public:
  /// Creates (truncates) `path` and writes the header: the sample columns, j1..jN, then
  /// `extra_columns` (numbers the reader keeps and ignores, e.g. the recorder's `quality`).
  /// \throws std::runtime_error on I/O failure.
  SamplesWriter(const std::string& path, std::size_t joint_count, std::vector<std::string> extra_columns = {});
  ~SamplesWriter();
  SamplesWriter(const SamplesWriter&) = delete;
  SamplesWriter& operator=(const SamplesWriter&) = delete;

  /// \pre joints_rad has joint_count entries (or is null when joint_count is 0).
  /// \pre extras has extra_columns.size() entries (or is null when there are none).
  void append(const Sample& s, const double* joints_rad = nullptr, const double* extras = nullptr);
  std::size_t buffered_bytes() const { return buf_.size(); }
  void flush();
  void close();
  std::size_t rows() const { return rows_; }

 private:
  void write_all(const std::string& bytes);
  int fd_ = -1;
  std::string path_;
  std::size_t joints_ = 0;
  std::size_t extras_ = 0;
  std::size_t rows_ = 0;
  std::string buf_;
};

/// Writes a whole table (convenience for generators and importers).
void write_samples(const std::string& path, const SampleTable& table);

}  // namespace hil::format
