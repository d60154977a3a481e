#pragma once
/// \file The calibration run (docs/formats.md, "The calibration run"): static postures of a robot,
/// each with its joint values by joint name, a measured point (optionally a full pose) in the frame
/// of the station that measured it, its standard deviation, flags, measured tilts of named links
/// and the load. What a laser tracker, a total station or a motion-capture system gives, in one
/// table. Bad input throws hil::error::FormatError naming the file, line and column.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include <hil/format/rig.hpp>

namespace hil::format {

/// A measured tilt of a named link: rotation about one of the link frame's axes (rad), as an
/// inclinometer on that link reports it. Column `tilt_<link>_<axis>` with axis rx or ry.
struct TiltColumn {
  std::string column;
  std::string link;
  int axis = 0;  ///< 0: about x, 1: about y
};

struct CalibrationPosture {
  std::string id;       ///< `posture` column
  std::string station;  ///< `station` column; "1" when the file has none
  std::size_t line = 0;
  Eigen::VectorXd q;                              ///< joint values in the robot's joint order (rad or m)
  Eigen::Vector3d p_measured_m;                   ///< the measured point in the station's frame
  std::optional<Eigen::Vector3d> r_measured_rad;  ///< rotation vector of the measured frame, when the run has one
  double sigma_m = 0.0;                           ///< standard deviation of each point coordinate; 0: not given (estimated)
  double sigma_rad = 0.0;                         ///< same for the rotation vector
  std::vector<bool> flags;                        ///< one per CalibrationRun::flag_names
  std::vector<double> tilts_rad;                  ///< one per CalibrationRun::tilts
  double payload_kg = 0.0;                        ///< carried at payload_com_m (tool frame)
  Eigen::Vector3d payload_com_m = Eigen::Vector3d::Zero();
  std::optional<Eigen::Matrix<double, 6, 1>> wrench;  ///< external [f (N); m (N·m)] at the tool point, world frame
};

struct CalibrationRun {
  std::string file;
  std::vector<std::string> joint_names;  ///< the robot's, in its order
  std::vector<std::string> stations;     ///< distinct, in order of first appearance
  std::vector<std::string> flag_names;   ///< from `flag_<name>` columns
  std::vector<TiltColumn> tilts;
  bool has_orientation = false, has_sigma = false, has_payload = false, has_wrench = false;
  std::vector<CalibrationPosture> postures;
};

/// Reads a calibration run for `robot` (its joint names and limits; for a URDF robot its links, which
/// tilt columns may name). \throws error::FormatError.
CalibrationRun read_calibration_run(const std::string& path, const RobotSpec& robot);
CalibrationRun parse_calibration_run(const std::string& text, const std::string& display_name, const RobotSpec& robot);

/// True when a CSV header names a calibration run (it has `posture`, `px`, `py`, `pz`): how `hil
/// validate` tells it from samples.csv.
bool looks_like_calibration_run(const std::vector<std::string>& header);

}  // namespace hil::format
