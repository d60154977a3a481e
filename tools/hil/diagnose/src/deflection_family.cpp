#include "hil/diagnose/deflection_family.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hil::diagnose {

const std::vector<std::string>& deflection_extensions() {
  static const std::vector<std::string> names{"robot_compliance", "time_offset"};
  return names;
}

DeflectionData make_deflection_data(const std::vector<double>& t_s, const std::vector<contact_id::Kinematics>& kin,
                                    const std::vector<Eigen::Matrix<double, 6, 1>>& w_fp, const Eigen::Isometry3d& T_world_fp) {
  const std::size_t n = t_s.size();
  if (n < 20 || kin.size() != n || w_fp.size() != n) throw std::runtime_error("too few samples to diagnose a deflection");
  DeflectionData d;
  d.obs.t_s = t_s;
  d.obs.component = {"dx", "dy", "dz", "rx", "ry", "rz"};
  d.obs.unit = {"m", "m", "m", "rad", "rad", "rad"};
  d.obs.y.resize(static_cast<Eigen::Index>(n), 6);
  d.load.resize(static_cast<Eigen::Index>(n), 6);
  d.speed_m_per_s.resize(n);
  const Eigen::Vector3d p0 = kin[0].T_world_ee.translation();
  const Eigen::Matrix3d R0 = kin[0].T_world_ee.linear();
  for (std::size_t k = 0; k < n; ++k) {
    const auto& T = kin[k].T_world_ee;
    if (!T.matrix().allFinite() || !w_fp[k].allFinite()) throw std::runtime_error("sample " + std::to_string(k) + ": non-finite value");
    const Eigen::AngleAxisd aa(T.linear() * R0.transpose());
    const auto i = static_cast<Eigen::Index>(k);
    d.obs.y.row(i).head<3>() = (T.translation() - p0).transpose();
    d.obs.y.row(i).tail<3>() = (aa.angle() * aa.axis()).transpose();
    // The load that deflects a body standing on the plate is what it pushes onto its support:
    // in equilibrium the spring (suspension, wheels) passes it on to the plate, so the load is the
    // plate's wrench itself, moved to p_0 in world axes.
    const Eigen::Vector3d f = T_world_fp.linear() * w_fp[k].head<3>();
    const Eigen::Vector3d m = T_world_fp.linear() * w_fp[k].tail<3>() + (T_world_fp.translation() - p0).cross(f);
    d.load.row(i).head<3>() = f.transpose();
    d.load.row(i).tail<3>() = m.transpose();
    d.speed_m_per_s[k] = kin[k].v_world_ee.norm();
  }
  // Weights: translations by their largest excursion from the mean, rotations likewise.
  const Eigen::MatrixXd c = d.obs.y.rowwise() - d.obs.y.colwise().mean();
  const double ts = std::max(c.leftCols(3).cwiseAbs().maxCoeff(), 1e-9);
  const double rs = std::max(c.rightCols(3).cwiseAbs().maxCoeff(), 1e-9);
  d.obs.weight << 1 / ts, 1 / ts, 1 / ts, 1 / rs, 1 / rs, 1 / rs;
  return d;
}

DeflectionFamily::DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions)
    : d_(d), ext_(std::move(extensions)) {
  for (const auto& e : ext_)
    if (std::find(deflection_extensions().begin(), deflection_extensions().end(), e) == deflection_extensions().end())
      throw std::invalid_argument("'" + e + "' does not apply to a deflection diagnosis (no contact geometry)");
  for (std::size_t c = 0; c < 6; ++c) linear_.push_back({"rest_" + d.obs.component[c], d.obs.unit[c], 1e-3, false});
  compliance_ = ext_.count("robot_compliance") > 0;
  if (compliance_) {
    const char* ax[6] = {"x", "y", "z", "rx", "ry", "rz"};
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) {
        const std::string unit = (i < 3 && j < 3) ? "m/N" : (i >= 3 && j >= 3) ? "rad/(N m)" : "m/(N m)";
        linear_.push_back({std::string("C_") + ax[i] + "_" + ax[j], unit, 1e-6, true});
      }
  }
  if (ext_.count("time_offset")) {
    const double dt = (d.obs.t_s.back() - d.obs.t_s.front()) / static_cast<double>(d.obs.size() - 1);
    i_tau_ = 0;
    nonlinear_.push_back({"time_offset_s", "s", dt, true, -0.5, 0.5});
  }
}

std::string DeflectionFamily::check(const Fit& f) const {
  if (!compliance_) return "";
  // Balanced units (mm/N, mrad/(N m)): positive semi-definiteness is invariant under this congruence.
  const Eigen::Matrix<double, 6, 1> s = (Eigen::Matrix<double, 6, 1>() << 1e3, 1e3, 1e3, 1e3, 1e3, 1e3).finished();
  Eigen::Matrix<double, 6, 6> C, V;
  Eigen::Index col = 6;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j, ++col) {
      C(i, j) = C(j, i) = s(i) * s(j) * f.theta(col);
      V(i, j) = V(j, i) = s(i) * s(j) * std::sqrt(std::max(0.0, f.cov(col, col)));
    }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(C);
  const double lo = es.eigenvalues()(0);
  // Tolerance: two standard deviations of the entries (spectral norm bound by the Frobenius norm).
  if (lo < -2.0 * V.norm())
    return "the compliance is not positive semi-definite (smallest eigenvalue " + std::to_string(lo * 1e-6) +
           " in m/N-equivalent units): the motion it explains is not elastic";
  return "";
}

std::string DeflectionFamily::name() const {
  if (ext_.empty()) return "nominal (rigid)";
  std::string s;
  for (const auto& e : deflection_extensions())
    if (ext_.count(e)) s += (s.empty() ? "" : "+") + e;
  return s;
}

std::vector<Eigen::VectorXd> DeflectionFamily::starts() const {
  std::vector<Eigen::VectorXd> out{Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nonlinear_.size()))};
  if (i_tau_ >= 0)
    for (int i = -10; i <= 10; ++i)
      if (i != 0) out.push_back(Eigen::VectorXd::Constant(1, 0.05 * i));
  return out;
}

void DeflectionFamily::design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const {
  const std::size_t n = d_.obs.size();
  A.setZero(static_cast<Eigen::Index>(6 * n), static_cast<Eigen::Index>(linear_.size()));
  const double tau = i_tau_ >= 0 ? phi(i_tau_) : 0.0;
  const auto& t = d_.obs.t_s;
  for (std::size_t k = 0; k < n; ++k) {
    const auto r = static_cast<Eigen::Index>(6 * k);
    for (int c = 0; c < 6; ++c) A(r + c, c) = 1.0;
    if (!compliance_) continue;
    // The load at t - τ (linear interpolation, held at the ends).
    Eigen::Matrix<double, 1, 6> w;
    const double tq = t[k] - tau;
    const auto it = std::upper_bound(t.begin(), t.end(), tq);
    if (it == t.begin()) {
      w = d_.load.row(0);
    } else if (it == t.end()) {
      w = d_.load.row(static_cast<Eigen::Index>(n - 1));
    } else {
      const auto j1 = static_cast<Eigen::Index>(it - t.begin()), j0 = j1 - 1;
      const double a = (tq - t[static_cast<std::size_t>(j0)]) / (t[static_cast<std::size_t>(j1)] - t[static_cast<std::size_t>(j0)]);
      w = (1 - a) * d_.load.row(j0) + a * d_.load.row(j1);
    }
    Eigen::Index col = 6;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j, ++col) {
        A(r + i, col) += w(j);
        if (i != j) A(r + j, col) += w(i);
      }
  }
}

}  // namespace hil::diagnose
