#pragma once
/// \file The virtual joint method (VJM) stiffness model of a serial robot.
///
/// Springs, in chain order from the base: link 0 (the base), joint 1, link 1, joint 2, ..., joint N,
/// link N: N+1 six-dimensional link springs and N one-dimensional joint springs (7 + 6 = 13 springs
/// and 7·36 + 6 = 258 compliance entries for a 6R robot).
///
/// * Joint spring i sits on joint i's axis (at its DH origin) and deflects about that axis (revolute,
///   rad/(N·m)) or along it (prismatic, m/N).
/// * Link spring i is a 6-D spring at the link's distal end: at joint i+1's DH origin for i < N, at
///   the tool point for i = N. Link 0 (the base) ends at joint 1's origin. Its frame S_i is fixed in
///   body i: x along the link's long axis (from its proximal joint's origin — the robot base origin
///   for link 0 — to its distal point), z along the distal joint's axis made orthogonal to x (the tool
///   z axis for link N); when those are parallel the proximal joint's axis, then body axes, are used.
///   A link of zero length takes x along its distal joint's axis. The spring's deflection
///   δ_S = [δp; δθ] (m, rad, in S_i, rotation about S_i's origin) answers the wrench acting on the
///   distal part, [f; m] (N, N·m, in S_i, moment about S_i's origin): δ_S = k_i w_S, so k_i is the
///   compliance of the link's end relative to its root, the beam template of the paper's eq. 12.
///
/// The tool displacement under a tool-point wrench w (world, [f; m]) is t = Σ_s J_s k_s J_sᵀ w, where
/// J_s (6 x dim_s) maps the spring's deflection to the tool displacement [δp_ee; δθ] (world).
#include <string>
#include <vector>

#include <hil/calibration/robot.hpp>

namespace hil::calibration {

enum class SpringKind { link, joint };

struct Spring {
  SpringKind kind = SpringKind::link;
  int index = 0;                                                    ///< link 0..N or joint 1..N
  int dim = 6;                                                      ///< 6 for links, 1 for joints
  int body = 0;                                                     ///< body whose frame the spring frame is fixed in (link i: body i)
  Eigen::Isometry3d T_body_spring = Eigen::Isometry3d::Identity();  ///< link springs: frame S_i in body i
  double length_m = 0.0;  ///< link springs: distance from the proximal joint origin to the distal point
  std::string name;       ///< "L0".."LN", "J1".."JN"
};

/// Spring Jacobians at one configuration (workspace reused across configurations).
struct VjmWorkspace {
  ChainPoses poses;
  std::vector<Matrix6d> J;  ///< per spring; joint springs use column 0 only
};

/// Compliance of every spring: 6x6 for links (SI: m/N, m/(N·m), rad/N, rad/(N·m)), 1x1 for joints.
using ComplianceSet = std::vector<Eigen::MatrixXd>;

class VjmModel {
 public:
  explicit VjmModel(SerialRobot robot);

  const SerialRobot& robot() const { return robot_; }
  const std::vector<Spring>& springs() const { return springs_; }
  int dof() const { return robot_.dof(); }
  /// Index of link spring i / joint spring i in springs().
  int link_spring(int link) const { return 2 * link; }
  int joint_spring(int joint) const { return 2 * joint - 1; }
  /// Index of a spring by name ("L2", "J3"); -1 if none.
  int find(const std::string& name) const;

  /// Fills ws.poses and ws.J for configuration q (no allocation once ws is sized).
  void jacobians(const Eigen::Ref<const Eigen::VectorXd>& q, VjmWorkspace& ws) const;

  /// World pose of spring s's frame at the configuration held in ws.poses (joint springs: a frame
  /// with z along the joint axis).
  Eigen::Isometry3d spring_pose(int s, const ChainPoses& poses) const;

  /// Forward model: tool displacement [δp (m); δθ (rad)] (world) under the tool-point wrench w_world.
  Vector6d deflection(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q, const Vector6d& w_world) const;
  Vector6d deflection(const ComplianceSet& k, const VjmWorkspace& ws, const Vector6d& w_world) const;

  /// The Cartesian compliance matrix Σ_s J_s k_s J_sᵀ (6x6) at q.
  Matrix6d cartesian_compliance(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q) const;

  /// Compliance error compensation in joint space: joint values q_c such that the deflected tool
  /// pose under w_world, pose(q_c) ⊕ t(q_c), equals the nominal pose at q_target. Newton iterations
  /// q ← q − J⁺ (pose(q) ⊕ t(q) ⊖ target) with the pseudo-inverse of the rigid Jacobian.
  /// `residual` (optional) receives the norm of the remaining 6-D pose error (m and rad mixed).
  Eigen::VectorXd compensate(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q_target, const Vector6d& w_world,
                             int iterations = 8, double* residual = nullptr) const;

  /// A compliance set of the right shapes, all zero.
  ComplianceSet zero_compliance() const;

 private:
  SerialRobot robot_;
  std::vector<Spring> springs_;
};

/// Checks a compliance set's shapes against the model. \throws std::invalid_argument.
void check_shapes(const VjmModel& model, const ComplianceSet& k);

/// Physical plausibility of one spring's compliance matrix.
struct SpdCheck {
  std::string spring;
  double asymmetry = 0.0;       ///< max |k - kᵀ| / max |k|
  double min_eigenvalue = 0.0;  ///< of the symmetric part
  double max_eigenvalue = 0.0;
  bool symmetric = false;
  bool positive_definite = false;
};
std::vector<SpdCheck> check_spd(const VjmModel& model, const ComplianceSet& k, double symmetry_tolerance = 1e-9);

}  // namespace hil::calibration
