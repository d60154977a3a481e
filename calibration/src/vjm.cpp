#include <hil/calibration/vjm.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

namespace hil::calibration {
namespace {

constexpr double kTinyLength_m = 1e-9;

/// The first candidate not parallel to x, made orthogonal to it (unit).
Eigen::Vector3d orthogonal_axis(const Eigen::Vector3d& x, const std::vector<Eigen::Vector3d>& candidates) {
  for (const auto& c : candidates) {
    const Eigen::Vector3d z = c - c.dot(x) * x;
    if (z.norm() > 1e-6 * c.norm()) return z.normalized();
  }
  // Unreachable with the body axes among the candidates, kept for safety.
  return x.unitOrthogonal();
}

}  // namespace

VjmModel::VjmModel(SerialRobot robot) : robot_(std::move(robot)) {
  const int n = robot_.dof();
  if (n < 1) throw std::invalid_argument("VJM model: the robot has no joints");
  const ChainPoses p0 = forward(robot_, Eigen::VectorXd::Zero(n));
  for (int i = 0; i <= n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (i >= 1) {
      Spring j;
      j.kind = SpringKind::joint;
      j.index = i;
      j.dim = 1;
      j.body = i - 1;
      j.name = "J" + std::to_string(i);
      springs_.push_back(j);
    }
    const Eigen::Isometry3d& T_wb = p0.T_world_body[ui];
    const Eigen::Vector3d proximal_W = i == 0 ? robot_.T_world_base.translation() : p0.p_world_joint_m[ui - 1];
    const Eigen::Vector3d distal_W = i < n ? p0.p_world_joint_m[ui] : p0.T_world_ee.translation();
    const Eigen::Vector3d distal_axis_W = i < n ? p0.joint_axis_world[ui] : p0.T_world_ee.linear().col(2);
    const Eigen::Vector3d proximal_axis_W = i == 0 ? robot_.T_world_base.linear().col(2) : p0.joint_axis_world[ui - 1];
    const Eigen::Vector3d along_W = distal_W - proximal_W;
    Eigen::Vector3d x, z;
    if (along_W.norm() > kTinyLength_m) {
      x = along_W.normalized();
      z = orthogonal_axis(x, {distal_axis_W, proximal_axis_W, T_wb.linear().col(2), T_wb.linear().col(0), T_wb.linear().col(1)});
    } else {
      x = distal_axis_W.normalized();
      z = orthogonal_axis(x, {proximal_axis_W, T_wb.linear().col(2), T_wb.linear().col(0), T_wb.linear().col(1)});
    }
    Eigen::Matrix3d R_WS;
    R_WS.col(0) = x;
    R_WS.col(1) = z.cross(x);
    R_WS.col(2) = z;
    Eigen::Isometry3d T_WS = Eigen::Isometry3d::Identity();
    T_WS.linear() = R_WS;
    T_WS.translation() = distal_W;
    Spring l;
    l.kind = SpringKind::link;
    l.index = i;
    l.dim = 6;
    l.body = i;
    l.T_body_spring = T_wb.inverse() * T_WS;
    l.length_m = along_W.norm();
    l.name = "L" + std::to_string(i);
    springs_.push_back(l);
  }
}

int VjmModel::find(const std::string& name) const {
  for (std::size_t s = 0; s < springs_.size(); ++s)
    if (springs_[s].name == name) return static_cast<int>(s);
  return -1;
}

Eigen::Isometry3d VjmModel::spring_pose(int s, const ChainPoses& poses) const {
  const Spring& sp = springs_[static_cast<std::size_t>(s)];
  if (sp.kind == SpringKind::link) return poses.T_world_body[static_cast<std::size_t>(sp.body)] * sp.T_body_spring;
  const auto j = static_cast<std::size_t>(sp.index - 1);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z = poses.joint_axis_world[j];
  T.linear().col(2) = z;
  T.linear().col(0) = z.unitOrthogonal();
  T.linear().col(1) = z.cross(T.linear().col(0));
  T.translation() = poses.p_world_joint_m[j];
  return T;
}

void VjmModel::jacobians(const Eigen::Ref<const Eigen::VectorXd>& q, VjmWorkspace& ws) const {
  forward(robot_, q, ws.poses);
  ws.J.resize(springs_.size());
  const Eigen::Vector3d p_ee = ws.poses.T_world_ee.translation();
  for (std::size_t s = 0; s < springs_.size(); ++s) {
    const Spring& sp = springs_[s];
    Matrix6d& J = ws.J[s];
    if (sp.kind == SpringKind::link) {
      const Eigen::Isometry3d T_WS = ws.poses.T_world_body[static_cast<std::size_t>(sp.body)] * sp.T_body_spring;
      const Eigen::Matrix3d R = T_WS.linear();
      J.topLeftCorner<3, 3>() = R;
      J.topRightCorner<3, 3>().noalias() = -skew(p_ee - T_WS.translation()) * R;
      J.bottomLeftCorner<3, 3>().setZero();
      J.bottomRightCorner<3, 3>() = R;
    } else {
      const auto j = static_cast<std::size_t>(sp.index - 1);
      const Eigen::Vector3d& z = ws.poses.joint_axis_world[j];
      J.setZero();
      if (robot_.joints[j].kind == JointKind::revolute) J.col(0) << z.cross(p_ee - ws.poses.p_world_joint_m[j]), z;
      else J.col(0) << z, Eigen::Vector3d::Zero();
    }
  }
}

Vector6d VjmModel::deflection(const ComplianceSet& k, const VjmWorkspace& ws, const Vector6d& w_world) const {
  Vector6d t = Vector6d::Zero();
  for (std::size_t s = 0; s < springs_.size(); ++s) {
    const int d = springs_[s].dim;
    const auto Js = ws.J[s].leftCols(d);
    const Eigen::VectorXd u = Js.transpose() * w_world;
    t.noalias() += Js * (k[s] * u);
  }
  return t;
}

Vector6d VjmModel::deflection(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q, const Vector6d& w_world) const {
  check_shapes(*this, k);
  VjmWorkspace ws;
  jacobians(q, ws);
  return deflection(k, ws, w_world);
}

Matrix6d VjmModel::cartesian_compliance(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  check_shapes(*this, k);
  VjmWorkspace ws;
  jacobians(q, ws);
  Matrix6d C = Matrix6d::Zero();
  for (std::size_t s = 0; s < springs_.size(); ++s) {
    const int d = springs_[s].dim;
    const auto Js = ws.J[s].leftCols(d);
    C.noalias() += Js * k[s] * Js.transpose();
  }
  return C;
}

Eigen::VectorXd VjmModel::compensate(const ComplianceSet& k, const Eigen::Ref<const Eigen::VectorXd>& q_target, const Vector6d& w_world,
                                     int iterations, double* residual) const {
  check_shapes(*this, k);
  const Eigen::Isometry3d target = tool_pose(robot_, q_target);
  Eigen::VectorXd q = q_target;
  VjmWorkspace ws;
  Vector6d err = Vector6d::Zero();
  for (int it = 0; it <= iterations; ++it) {
    jacobians(q, ws);
    const Vector6d rigid = pose_difference(target, ws.poses.T_world_ee);
    err = rigid + deflection(k, ws, w_world);
    if (it == iterations) break;
    // The rotation error is log(R(q) R_targetᵀ): a joint step turns R(q) by J_ω dq in the world
    // frame, which moves the log by Jl⁻¹(log) J_ω dq (so3::left_jacobian_inverse). The deflection's
    // own change with q is second order and left out.
    Eigen::MatrixXd J = tool_jacobian(robot_, ws.poses);
    J.bottomRows<3>() = so3::left_jacobian_inverse(rigid.tail<3>()) * J.bottomRows<3>();
    q -= J.completeOrthogonalDecomposition().solve(err);
  }
  if (residual) *residual = err.norm();
  return q;
}

ComplianceSet VjmModel::zero_compliance() const {
  ComplianceSet k;
  for (const auto& s : springs_) k.push_back(Eigen::MatrixXd::Zero(s.dim, s.dim));
  return k;
}

void check_shapes(const VjmModel& model, const ComplianceSet& k) {
  if (k.size() != model.springs().size())
    throw std::invalid_argument("compliance set has " + std::to_string(k.size()) + " springs, the model " +
                                std::to_string(model.springs().size()));
  for (std::size_t s = 0; s < k.size(); ++s) {
    const int d = model.springs()[s].dim;
    if (k[s].rows() != d || k[s].cols() != d)
      throw std::invalid_argument("compliance of " + model.springs()[s].name + " must be " + std::to_string(d) + "x" + std::to_string(d));
  }
}

std::vector<SpdCheck> check_spd(const VjmModel& model, const ComplianceSet& k, double symmetry_tolerance) {
  check_shapes(model, k);
  std::vector<SpdCheck> out;
  for (std::size_t s = 0; s < k.size(); ++s) {
    SpdCheck c;
    c.spring = model.springs()[s].name;
    const double scale = k[s].cwiseAbs().maxCoeff();
    c.asymmetry = scale > 0.0 ? (k[s] - k[s].transpose()).cwiseAbs().maxCoeff() / scale : 0.0;
    c.symmetric = c.asymmetry <= symmetry_tolerance;
    const Eigen::MatrixXd sym = 0.5 * (k[s] + k[s].transpose());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(sym, Eigen::EigenvaluesOnly);
    c.min_eigenvalue = es.eigenvalues().minCoeff();
    c.max_eigenvalue = es.eigenvalues().maxCoeff();
    c.positive_definite = c.symmetric && c.min_eigenvalue > 0.0;
    out.push_back(c);
  }
  return out;
}

}  // namespace hil::calibration
