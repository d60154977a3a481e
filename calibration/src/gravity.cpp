#include <hil/calibration/gravity.hpp>

#include <stdexcept>

namespace hil::calibration {

Eigen::VectorXd gravity_torques(const SerialRobot& robot, const ChainPoses& poses, const Eigen::Vector3d& g_world, double payload_kg,
                                const Eigen::Vector3d& payload_com_ee_m) {
  const int n = robot.dof();
  if (robot.inertials.size() != static_cast<std::size_t>(n) + 1)
    throw std::invalid_argument("gravity torques: the robot has no inertials (a URDF with <inertial> elements gives them)");
  // Walk from the tip: the weight beyond joint i is a force F and its moment about the world
  // origin M; joint i holds the moment about its axis through its origin.
  Eigen::Vector3d F = payload_kg * g_world;
  Eigen::Vector3d M = (poses.T_world_ee * payload_com_ee_m).cross(F);
  Eigen::VectorXd G(n);
  for (int i = n; i >= 1; --i) {
    const auto& in = robot.inertials[static_cast<std::size_t>(i)];
    const Eigen::Vector3d f = in.mass_kg * g_world;
    F += f;
    M += (poses.T_world_body[static_cast<std::size_t>(i)] * in.com_m).cross(f);
    const auto j = static_cast<std::size_t>(i - 1);
    const Eigen::Vector3d& z = poses.joint_axis_world[j];
    // Holding torque = −(gravity's moment about the axis through the joint's origin).
    G[i - 1] = robot.joints[j].kind == JointKind::revolute ? -z.dot(M - poses.p_world_joint_m[j].cross(F)) : -z.dot(F);
  }
  return G;
}

double moving_mass_kg(const SerialRobot& robot) {
  double m = 0.0;
  for (std::size_t b = 1; b < robot.inertials.size(); ++b) m += robot.inertials[b].mass_kg;
  return m;
}

}  // namespace hil::calibration
