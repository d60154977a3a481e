#pragma once
/// \file A serial manipulator described by a Denavit-Hartenberg table: forward kinematics and the
/// geometric Jacobian of the tool point. Pure numerics (Eigen only); the `hil` tools build it from the
/// rig file (hil::format::RobotSpec).
///
/// Frames: `world` (W), robot base (frame 0 of the DH table, placed by T_world_base), DH frames
/// 1..N, flange = frame N, tool/end-effector `ee` placed by T_flange_ee. A 6-D small displacement
/// or twist is ordered [translation (m); rotation (rad)] and, unless named otherwise, expressed in
/// the world frame at the tool point.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include <hil/so3/so3.hpp>

namespace hil::calibration {

using hil::Matrix6d;
using hil::Vector6d;

enum class DhConvention {
  standard,  ///< Denavit-Hartenberg 1955: T_{i-1,i} = Rz(θ) Tz(d) Tx(a) Rx(α); joint i moves about z_{i-1}
  modified,  ///< Craig: T_{i-1,i} = Rx(α) Tx(a) Rz(θ) Tz(d); joint i moves about z_i
  urdf       ///< URDF joints: T_{i-1,i} = T_parent_joint · Rot(axis, θ) (or · Trans(axis, d)); joint i moves about its axis
};
enum class JointKind { revolute, prismatic };

/// One joint: a DH row, or (DhConvention::urdf) a URDF joint's origin and axis.
/// θ = q + theta_offset_rad (revolute) or d = q + d_m (prismatic) in every convention; a_m and
/// alpha_rad are unused in the URDF form, T_parent_joint and axis only there.
struct DhRow {
  std::string name;
  JointKind kind = JointKind::revolute;
  double a_m = 0.0;
  double alpha_rad = 0.0;
  double d_m = 0.0;
  double theta_offset_rad = 0.0;
  double lower = -3.141592653589793;  ///< joint limit (rad or m), used to plan experiments
  double upper = 3.141592653589793;
  Eigen::Isometry3d T_parent_joint = Eigen::Isometry3d::Identity();  ///< URDF form: the joint frame in the previous body
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();                   ///< URDF form: unit axis in the joint frame
  /// A URDF mimic joint: a physical joint (own axis, body, spring, offset) whose value is
  /// mimic_multiplier · q[mimic_master] + mimic_offset where hil makes joint values itself
  /// (fill_mimic_joints); -1 for an independent joint.
  int mimic_master = -1;
  double mimic_multiplier = 1.0;
  double mimic_offset = 0.0;
};

/// Mass properties of one body of the chain (URDF inertials, fixed links lumped in), in the body's
/// frame: mass, centre of mass, rotational inertia about the centre of mass.
struct BodyInertial {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_kgm2 = Eigen::Matrix3d::Zero();
};

struct SerialRobot {
  std::string name = "robot";
  DhConvention convention = DhConvention::standard;
  std::vector<DhRow> joints;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_flange_ee = Eigen::Isometry3d::Identity();
  /// Bodies 0..N (empty when the description has none, as a DH table): what gravity loads.
  std::vector<BodyInertial> inertials;
  /// Names of bodies 0..N (URDF links) when known, for messages and parameter names; may be empty.
  std::vector<std::string> body_links;

  int dof() const { return static_cast<int>(joints.size()); }
};

/// Poses of every body of the chain at one configuration. Body 0 is the base (fixed in the world),
/// body i (1..N) is the link moved by joints 1..i; its frame is DH frame i.
struct ChainPoses {
  std::vector<Eigen::Isometry3d> T_world_body;    ///< N+1 entries
  std::vector<Eigen::Vector3d> joint_axis_world;  ///< unit axis of joint i (index i-1)
  std::vector<Eigen::Vector3d> p_world_joint_m;   ///< a point on joint i's axis (its DH origin), index i-1
  Eigen::Isometry3d T_world_ee = Eigen::Isometry3d::Identity();
};

/// Sets every mimic joint's entry of q from its master's (q holds one value per joint, dof() of
/// them; independent entries are left as they are).
void fill_mimic_joints(const SerialRobot& robot, Eigen::Ref<Eigen::VectorXd> q);

/// The DH transform of one row at joint value q (rad or m).
Eigen::Isometry3d dh_transform(DhConvention convention, const DhRow& row, double q);

/// Forward kinematics of every body. \pre q.size() == robot.dof().
void forward(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q, ChainPoses& out);
ChainPoses forward(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q);

/// T_world_ee at q.
Eigen::Isometry3d tool_pose(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q);
/// The tool in the robot's base frame (T_world_base left out) for joint values `q` (rad or m, dof()
/// of them). Allocation-free: the driver of a controller that reports only joints calls it per poll.
Eigen::Isometry3d tool_in_base(const SerialRobot& robot, const double* q) noexcept;

/// Geometric Jacobian (6 x N) of the tool point: [v_W; ω_W] = J q̇ with v the velocity of the
/// tool-frame origin, both in the world frame.
Eigen::MatrixXd tool_jacobian(const SerialRobot& robot, const Eigen::Ref<const Eigen::VectorXd>& q);
Eigen::MatrixXd tool_jacobian(const SerialRobot& robot, const ChainPoses& poses);

/// Skew-symmetric matrix [v]x such that [v]x u = v x u.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

/// The small-displacement difference of two poses, [p_b - p_a; log(R_b R_a^T)] (world frame),
/// used by the finite-difference checks and the compensation.
Vector6d pose_difference(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b);

/// Reference geometry close to a KUKA KR-270 R2700 (standard DH, metres), used for the Table I
/// comparison and the benchmark: a1 0.350, d1 0.675, a2 1.150, a3 0.041, d4 1.200, d6 0.215 and a
/// 0.2 m tool along the flange z axis. See docs/calibration.md.
SerialRobot kr270_like();

}  // namespace hil::calibration
