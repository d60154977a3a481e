#include "hil/drivers/kinematics.hpp"

#include <cmath>

namespace hil::drivers {

Eigen::Isometry3d forward_kinematics(const DhChain& chain, const double* q) noexcept {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < chain.joints.size(); ++i) {
    const DhJoint& j = chain.joints[i];
    const double theta = j.theta_offset_rad + (j.prismatic ? 0.0 : q[i]);
    const double d = j.d_m + (j.prismatic ? q[i] : 0.0);
    const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(j.alpha_rad), sa = std::sin(j.alpha_rad);
    Eigen::Matrix4d A;
    if (!chain.modified) {
      A << ct, -st * ca, st * sa, j.a_m * ct,  //
          st, ct * ca, -ct * sa, j.a_m * st,   //
          0, sa, ca, d,                        //
          0, 0, 0, 1;
    } else {
      A << ct, -st, 0, j.a_m,                  //
          st * ca, ct * ca, -sa, -sa * d,      //
          st * sa, ct * sa, ca, ca * d,        //
          0, 0, 0, 1;
    }
    T = T * Eigen::Isometry3d(A);
  }
  return T * chain.T_flange_tool;
}

}  // namespace hil::drivers
