#pragma once
/// \file Rigid-body pose from markers (Kabsch/Horn by SVD) and twist from filtered differences.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace hil::import {

/// T_world_body fitted to markers: minimises sum |R_world_body * b_i + p_world_body - w_i|^2.
struct RigidFit {
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_body_m = Eigen::Vector3d::Zero();
  double residual_rms_m = 0.0;  ///< RMS over the used markers of |fitted - measured|
  std::size_t markers_used = 0;
};

/// Why a fit could not be made.
struct FitFailure {
  std::string reason;
};

/// Fits the pose of a body from the markers flagged in `seen` (columns of the 3xN matrices).
/// Needs >= `min_markers` (>= 3) seen markers whose reference positions are not (nearly) collinear.
std::optional<RigidFit> fit_rigid_body(const Eigen::Matrix3Xd& markers_body_m, const Eigen::Matrix3Xd& markers_world_m,
                                       const std::vector<bool>& seen, std::size_t min_markers, FitFailure* failure = nullptr);

/// Spread of points across their best line, relative to their spread along it (0 = collinear).
double planarity_ratio(const Eigen::Matrix3Xd& points);

/// A pose over time and its twist.
struct PoseTrack {
  std::vector<double> t_s;  ///< strictly increasing
  std::vector<Eigen::Vector3d> p_world_body_m;
  std::vector<Eigen::Quaterniond> q_world_body;
};
struct Twist {
  std::vector<Eigen::Vector3d> v_world_m_per_s;    ///< of the body origin
  std::vector<Eigen::Vector3d> w_world_rad_per_s;  ///< angular velocity in world
};

/// Velocities as the slope of a least-squares line through the samples within +-window_s/2 of each
/// sample (a first-order Savitzky-Golay derivative that accepts uneven steps and gaps). Rotations
/// enter as rotation vectors of R_j * R_i^T (world frame), so the slope is the world angular velocity.
/// A window holding only the sample itself widens to its nearest neighbours.
Twist twist_from_poses(const PoseTrack& track, double window_s);

}  // namespace hil::import
