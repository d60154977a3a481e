#pragma once
// An independent generator of point-calibration data for the tests of point_calibration.cpp: the
// robot's kinematics and gravity come from Orocos KDL's own chain and solvers (built from the URDF
// file by kdl_parser, not from hil's joint rows), the effects are applied to KDL's joint values,
// and the station frame and noise are drawn here. It shares no code with the candidates that must
// find the effects (hil's dh_transform, gravity_torques, the fit).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace hil::test {

struct PointTruth {
  Eigen::VectorXd joint_offset_rad;                        ///< added to the commanded joint values
  Eigen::VectorXd joint_compliance;                        ///< rad/(N·m): each joint turns by −c·G under the holding torque G
  std::vector<Eigen::Isometry3d> T_station_base;           ///< per station
  Eigen::Vector3d tool_point_m = Eigen::Vector3d::Zero();  ///< in the tip link's frame
  double noise_m = 0.0;                                    ///< per coordinate
};

struct PointSample {
  Eigen::VectorXd q;  ///< commanded
  int station = 0;
  Eigen::Vector3d p_station_m;
};

/// `n` postures drawn uniformly per joint in `range_rad` (lower, upper per joint; when empty, a UR
/// arm's: [-3, 3] except the shoulder lift and elbow, which keep the arm above its base), spread
/// over the stations in turn, measured with noise.
std::vector<PointSample> generate_points(const std::string& urdf, const std::string& base, const std::string& tip, const PointTruth& truth,
                                         int n, std::mt19937& rng, const std::vector<std::pair<double, double>>& range_rad = {});

/// A random station frame: a rotation of up to `angle_rad` about a random axis, a translation of up
/// to `distance_m` per axis.
Eigen::Isometry3d random_station(std::mt19937& rng, double angle_rad, double distance_m);

}  // namespace hil::test
