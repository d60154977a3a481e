#pragma once
// What `hil calibrate RUN --rig RIG` does, as library calls: a calibration run (measured points of
// static postures) against the rig's robot: what the postures determine, the rigid model with its
// nuisance frames fitted, every candidate extension by held-out error, the named cause and its
// parameters. Files in (hil::format's calibration run and rig), text and JSON out; the numerics are
// hil::calibration's (point_calibration.hpp).
#include <nlohmann/json.hpp>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/calibration_run.hpp>

namespace hil::services::point_calibration {

struct Options {
  std::vector<calibration::PointCandidate> candidates = calibration::point_candidates();
  int folds = 0;  ///< one station: postures left out in this many folds (0: one at a time)
  Eigen::Vector3d tool_point_start_ee_m = Eigen::Vector3d::Zero();
  /// URDF links that may bend (link_bending); empty: every link spanning 0.2 m or more.
  std::vector<std::string> bending_links;
  /// Fit the run's measured orientations too (rx ry rz columns), weighted by sigma_m / sigma_rad
  /// where the run states both.
  bool orientation = false;
};

struct Report {
  std::string run_path, rig_path, robot_name;
  std::vector<std::string> robot_links;  ///< the chain's bodies 0..N by URDF link (empty for a DH robot)
  std::vector<std::string> joint_units;  ///< per joint: rad or m
  format::CalibrationRun run;
  std::vector<calibration::PointObservation> observations;
  std::vector<calibration::PointFit> determined;  ///< per model (rigid, then each candidate), before estimation
  calibration::PointFit rigid;
  calibration::PointComparison comparison;
  std::optional<calibration::PointFit> cause;  ///< the named cause's fit (with the second cause when there is one)
  std::vector<std::string> skipped;            ///< candidates left out, with why
  bool orientation = false;                    ///< the measured orientations were fitted
};

/// \throws error::FormatError for bad files, std::invalid_argument for data that cannot be fitted.
Report run(const std::string& run_path, const std::string& rig_path, const Options& options);
void print(std::ostream& os, const Report& r);
/// hil.point_calibration (docs/schemas/hil.point_calibration.schema.json).
nlohmann::json to_json(const Report& r);
/// The HTML report in `dir` (index.html, figures/): the verdict, what the postures determine, the
/// candidates, the residual vectors per posture before and after, the cause's parameters.
/// \throws std::runtime_error if it cannot be written.
void write_report(const Report& r, const std::string& dir);

}  // namespace hil::services::point_calibration
