#pragma once
/// \file Static gravity loads of a serial robot from its bodies' inertials (URDF robots): the joint
/// torques that hold the arm still, the load that joint springs and gears carry.
#include <Eigen/Core>

#include <hil/calibration/robot.hpp>

namespace hil::calibration {

/// Standard gravity, m/s², pointing down the world z axis.
inline const Eigen::Vector3d kGravityWorld(0.0, 0.0, -9.80665);

/// The holding torques G(q) (N·m for revolute joints, N for prismatic ones): what joint i must
/// apply so that the bodies beyond it stay still under gravity g_world (m/s², world frame), plus a
/// payload of `payload_kg` at `payload_com_ee_m` in the tool frame. The same G as Orocos KDL's
/// ChainDynParam::JntToGravity (tested against it). A joint spring of compliance c (rad/(N·m))
/// carrying it turns by Δq = −c·G. \pre robot.inertials has dof()+1 entries (body 0 unused).
/// \throws std::invalid_argument when the robot has no inertials.
Eigen::VectorXd gravity_torques(const SerialRobot& robot, const ChainPoses& poses, const Eigen::Vector3d& g_world = kGravityWorld,
                                double payload_kg = 0.0, const Eigen::Vector3d& payload_com_ee_m = Eigen::Vector3d::Zero());

/// Total mass of the bodies moved by the joints (bodies 1..N), kg; 0 without inertials.
double moving_mass_kg(const SerialRobot& robot);

}  // namespace hil::calibration
