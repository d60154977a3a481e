#pragma once
/// \file Forward kinematics of a DH chain, for controllers that report only joint angles.
#include <Eigen/Geometry>
#include <vector>

namespace hil::drivers {

struct DhJoint {
  double a_m = 0.0;
  double alpha_rad = 0.0;
  double d_m = 0.0;
  double theta_offset_rad = 0.0;
  bool prismatic = false;  ///< q is added to d instead of θ
};

/// Standard DH (T = Rz(θ) Tz(d) Tx(a) Rx(α)) or modified/Craig (T = Rx(α) Tx(a) Rz(θ) Tz(d)).
struct DhChain {
  bool modified = false;
  std::vector<DhJoint> joints;
  Eigen::Isometry3d T_flange_tool = Eigen::Isometry3d::Identity();  ///< tool (ee) in the last DH frame
};

/// T_base_tool for joint values q (rad or m). \pre q holds chain.joints.size() values. Allocation-free.
Eigen::Isometry3d forward_kinematics(const DhChain& chain, const double* q) noexcept;

}  // namespace hil::drivers
