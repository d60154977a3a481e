#include <hil/calibration/robot.hpp>
#include <hil/so3/so3.hpp>

#include <cmath>
#include <stdexcept>

namespace hil::calibration {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

Eigen::Isometry3d dh_transform(DhConvention convention, const DhRow& row, double q) {
  const double theta = row.kind == JointKind::revolute ? q + row.theta_offset_rad : row.theta_offset_rad;
  const double d = row.kind == JointKind::prismatic ? q + row.d_m : row.d_m;
  if (convention == DhConvention::urdf) {
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    if (row.kind == JointKind::revolute) motion.linear() = Eigen::AngleAxisd(theta, row.axis).toRotationMatrix();
    else motion.translation() = d * row.axis;
    return row.T_parent_joint * motion;
  }
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(row.alpha_rad), sa = std::sin(row.alpha_rad);
  Eigen::Matrix4d M;
  if (convention == DhConvention::standard) {
    // Rz(θ) Tz(d) Tx(a) Rx(α)
    M << ct, -st * ca, st * sa, row.a_m * ct,  //
        st, ct * ca, -ct * sa, row.a_m * st,   //
        0.0, sa, ca, d,                        //
        0.0, 0.0, 0.0, 1.0;
  } else {
    // Rx(α) Tx(a) Rz(θ) Tz(d)
    M << ct, -st, 0.0, row.a_m,          //
        st * ca, ct * ca, -sa, -sa * d,  //
        st * sa, ct * sa, ca, ca * d,    //
        0.0, 0.0, 0.0, 1.0;
  }
  Eigen::Isometry3d T;
  T.matrix() = M;
  return T;
}

void forward(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q, ChainPoses& out) {
  const int n = robot.dof();
  if (q.size() != n) throw std::invalid_argument("forward: expected " + std::to_string(n) + " joint values");
  out.T_world_body.resize(static_cast<std::size_t>(n) + 1);
  out.joint_axis_world.resize(static_cast<std::size_t>(n));
  out.p_world_joint_m.resize(static_cast<std::size_t>(n));
  out.T_world_body[0] = robot.T_world_base;
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const Eigen::Isometry3d& T_prev = out.T_world_body[ui];
    out.T_world_body[ui + 1] = T_prev * dh_transform(robot.convention, robot.joints[ui], q[i]);
    // Standard: joint i+1 moves about z of the previous frame through its origin;
    // modified: about z of its own frame (the new frame's z, through its origin);
    // URDF: about its axis through the joint frame's origin (the axis is unchanged by the motion).
    if (robot.convention == DhConvention::urdf) {
      const DhRow& row = robot.joints[ui];
      out.joint_axis_world[ui] = T_prev.linear() * (row.T_parent_joint.linear() * row.axis);
      out.p_world_joint_m[ui] = T_prev * row.T_parent_joint.translation();
      continue;
    }
    const Eigen::Isometry3d& T_axis = robot.convention == DhConvention::standard ? T_prev : out.T_world_body[ui + 1];
    out.joint_axis_world[ui] = T_axis.linear().col(2);
    out.p_world_joint_m[ui] = T_axis.translation();
  }
  out.T_world_ee = out.T_world_body.back() * robot.T_flange_ee;
}

ChainPoses forward(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q) {
  ChainPoses p;
  forward(robot, q, p);
  return p;
}

Eigen::Isometry3d tool_pose(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q) { return forward(robot, q).T_world_ee; }

void fill_mimic_joints(const SerialRobot& robot, Eigen::Ref<Eigen::VectorXd> q) {
  for (std::size_t i = 0; i < robot.joints.size(); ++i) {
    const auto& row = robot.joints[i];
    // Masters are independent joints (the URDF reader resolves chains of mimics), so one pass does.
    if (row.mimic_master >= 0) q[static_cast<Eigen::Index>(i)] = row.mimic_multiplier * q[row.mimic_master] + row.mimic_offset;
  }
}

Eigen::Isometry3d tool_in_base(const SerialRobot& robot, const double* q) noexcept {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < robot.joints.size(); ++i) T = T * dh_transform(robot.convention, robot.joints[i], q[i]);
  return T * robot.T_flange_ee;
}

Eigen::MatrixXd tool_jacobian(const SerialRobot& robot, const ChainPoses& poses) {
  const int n = robot.dof();
  Eigen::MatrixXd J(6, n);
  const Eigen::Vector3d p_ee = poses.T_world_ee.translation();
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const Eigen::Vector3d& z = poses.joint_axis_world[ui];
    if (robot.joints[ui].kind == JointKind::revolute) {
      J.col(i) << z.cross(p_ee - poses.p_world_joint_m[ui]), z;
    } else {
      J.col(i) << z, Eigen::Vector3d::Zero();
    }
  }
  return J;
}

Eigen::MatrixXd tool_jacobian(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q) {
  return tool_jacobian(robot, forward(robot, q));
}

Vector6d pose_difference(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b) {
  Vector6d d;
  d << T_b.translation() - T_a.translation(), so3::log(Eigen::Matrix3d(T_b.linear() * T_a.linear().transpose()));
  return d;
}

SerialRobot kr270_like() {
  constexpr double kHalfPi = 1.5707963267948966;
  SerialRobot r;
  r.name = "kr270_like";
  r.convention = DhConvention::standard;
  r.joints = {
      {"a1", JointKind::revolute, 0.350, -kHalfPi, 0.675, 0.0, -3.2, 3.2}, {"a2", JointKind::revolute, 1.150, 0.0, 0.0, 0.0, -2.44, -0.09},
      {"a3", JointKind::revolute, 0.041, -kHalfPi, 0.0, 0.0, -2.1, 2.7},   {"a4", JointKind::revolute, 0.0, kHalfPi, 1.200, 0.0, -6.1, 6.1},
      {"a5", JointKind::revolute, 0.0, -kHalfPi, 0.0, 0.0, -2.1, 2.1},     {"a6", JointKind::revolute, 0.0, 0.0, 0.215, 0.0, -6.1, 6.1},
  };
  r.T_flange_ee = Eigen::Isometry3d::Identity();
  r.T_flange_ee.translation() = Eigen::Vector3d(0.0, 0.0, 0.2);
  return r;
}

}  // namespace hil::calibration
