#include <hil/diagnose/stiffness_family.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hil::diagnose {

namespace {

/// Link directions kept: singular value >= this fraction of the largest (columns at unit norm, then
/// the joints' part projected out), at most kMaxLinkDirections of them. Weaker directions are
/// beyond what a table of this size can tell from its noise; the PNR test judges the rest.
constexpr double kLinkDirectionFloor = 1e-2;
constexpr int kMaxLinkDirections = 12;

}  // namespace

const std::vector<std::string>& stiffness_extensions() {
  static const std::vector<std::string> names{"link_compliance", "sensor_bias", "sensor_gain", "load_offset"};
  return names;
}

StiffnessData make_stiffness_data(const calibration::VjmModel& model, const std::vector<calibration::Measurement>& rows) {
  const std::size_t n = rows.size();
  const int dof = model.dof();
  if (n < 10) throw std::runtime_error("too few rows to diagnose a stiffness table (" + std::to_string(n) + " < 10)");
  StiffnessData d;
  d.obs.component = {"dx", "dy", "dz", "rx", "ry", "rz"};
  d.obs.unit = {"m", "m", "m", "rad", "rad", "rad"};
  d.obs.y.resize(static_cast<Eigen::Index>(n), 6);
  d.joint_ops.resize(n);
  d.link_ops.resize(n);
  for (int j = 1; j <= dof; ++j) d.joint_names.push_back(model.springs()[static_cast<std::size_t>(model.joint_spring(j))].name);
  // Every symmetric entry of every link spring: M_p = J_s E_p J_sᵀ.
  std::vector<std::vector<Matrix6d>> raw(n);
  calibration::VjmWorkspace ws;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& m = rows[k];
    const std::string where = "row " + std::to_string(k + 1) + " (config " + std::to_string(m.config) + ")";
    if (m.kind != calibration::MeasurementKind::pose6 || m.displacement.size() != 6)
      throw std::runtime_error(where + ": the diagnosis needs the 6-D tool displacement (dx dy dz rx ry rz)");
    if (m.q_rad.size() != dof)
      throw std::runtime_error(where + ": " + std::to_string(m.q_rad.size()) + " joint values for a " + std::to_string(dof) +
                               "-joint robot");
    if (!m.displacement.allFinite() || !m.w_world.allFinite() || !m.q_rad.allFinite())
      throw std::runtime_error(where + ": non-finite value");
    d.obs.t_s.push_back(static_cast<double>(k));
    d.obs.y.row(static_cast<Eigen::Index>(k)) = m.displacement.transpose();
    d.load.push_back(m.w_world);
    d.config.push_back(m.config);
    model.jacobians(m.q_rad, ws);
    for (int j = 1; j <= dof; ++j) {
      const Vector6d c = ws.J[static_cast<std::size_t>(model.joint_spring(j))].col(0);
      d.joint_ops[k].push_back(c * c.transpose());
    }
    for (int l = 0; l <= dof; ++l) {
      const Matrix6d& J = ws.J[static_cast<std::size_t>(model.link_spring(l))];
      for (int r = 0; r < 6; ++r)
        for (int c = r; c < 6; ++c) {
          Matrix6d M = J.col(r) * J.col(c).transpose();
          if (r != c) M += J.col(c) * J.col(r).transpose();
          raw[k].push_back(M);
        }
    }
  }
  // Weights: translations by their largest excursion, rotations likewise (relative errors).
  const double ts = std::max(d.obs.y.leftCols(3).cwiseAbs().maxCoeff(), 1e-12);
  const double rs = std::max(d.obs.y.rightCols(3).cwiseAbs().maxCoeff(), 1e-12);
  d.obs.weight << 1 / ts, 1 / ts, 1 / ts, 1 / rs, 1 / rs, 1 / rs;
  Vector6d rms = Vector6d::Zero();
  for (const auto& w : d.load) rms += w.cwiseAbs2();
  rms.head<3>().maxCoeff(&d.gain_reference);  // the force component with the most load

  // The link directions this table identifies beside the joints: weighted observation columns at
  // the measured loads, the joints' span projected out, columns at unit norm, then the SVD.
  const auto rowsN = static_cast<Eigen::Index>(6 * n);
  const auto P = static_cast<Eigen::Index>(raw.empty() ? 0 : raw[0].size());
  Eigen::MatrixXd Jc(rowsN, dof), Lc(rowsN, P);
  for (std::size_t k = 0; k < n; ++k) {
    const auto r0 = static_cast<Eigen::Index>(6 * k);
    for (int j = 0; j < dof; ++j)
      Jc.block(r0, j, 6, 1) = (d.joint_ops[k][static_cast<std::size_t>(j)] * d.load[k]).cwiseProduct(d.obs.weight);
    for (Eigen::Index p = 0; p < P; ++p)
      Lc.block(r0, p, 6, 1) = (raw[k][static_cast<std::size_t>(p)] * d.load[k]).cwiseProduct(d.obs.weight);
  }
  // Unit columns before the projection: an entry the joints already explain keeps a (near) zero
  // column instead of having its rounding noise blown up.
  Eigen::VectorXd colscale(P);
  for (Eigen::Index p = 0; p < P; ++p) {
    const double nrm = Lc.col(p).norm();
    colscale(p) = nrm > 0 ? 1.0 / nrm : 0.0;
  }
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Jc);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(rowsN, dof);
  Lc -= Q * (Q.transpose() * Lc);
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(Lc * colscale.asDiagonal(), Eigen::ComputeThinV);
  const auto& s = svd.singularValues();
  for (Eigen::Index r = 0; r < s.size() && r < kMaxLinkDirections; ++r) {
    if (!(s(r) >= kLinkDirectionFloor * s(0)) || s(r) <= 0) break;
    const Eigen::VectorXd v = colscale.asDiagonal() * svd.matrixV().col(r);
    // Scaled so that a unit parameter moves the weighted prediction by about one unit.
    const double unit = 1.0 / s(r);
    for (std::size_t k = 0; k < n; ++k) {
      Matrix6d M = Matrix6d::Zero();
      for (Eigen::Index p = 0; p < P; ++p) M += v(p) * raw[k][static_cast<std::size_t>(p)];
      d.link_ops[k].push_back(unit * M);
    }
  }
  return d;
}

StiffnessFamily::StiffnessFamily(const StiffnessData& d, std::set<std::string> extensions) : d_(d), ext_(std::move(extensions)) {
  const auto& all = stiffness_extensions();
  for (const auto& e : ext_)
    if (std::find(all.begin(), all.end(), e) == all.end())
      throw std::invalid_argument("'" + e +
                                  "' does not apply to a stiffness table (candidates: link_compliance, sensor_bias, "
                                  "sensor_gain, load_offset)");
  for (const auto& j : d.joint_names) linear_.push_back({j, "rad/(N m)", 1e-6, false});
  links_ = ext_.count("link_compliance") > 0;
  if (links_) {
    const std::size_t r = d.link_ops.empty() ? 0 : d.link_ops[0].size();
    for (std::size_t i = 0; i < r; ++i) linear_.push_back({"link_direction_" + std::to_string(i + 1), "", 1.0, true});
  }
  if (ext_.count("sensor_bias")) {
    j_bias_ = static_cast<int>(linear_.size());
    for (int c = 0; c < 6; ++c)
      linear_.push_back({"bias_" + d.obs.component[static_cast<std::size_t>(c)], d.obs.unit[static_cast<std::size_t>(c)], 1e-5, true});
  }
  static const char* wn[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  if (ext_.count("sensor_gain")) {
    i_gain_ = static_cast<int>(nonlinear_.size());
    for (int c = 0; c < 6; ++c)
      if (c != d.gain_reference) nonlinear_.push_back({std::string("gain_") + wn[c], "", 1e-2, true, -0.5, 0.5});
  }
  if (ext_.count("load_offset")) {
    i_offset_ = static_cast<int>(nonlinear_.size());
    Vector6d rms = Vector6d::Zero();
    for (const auto& w : d.load) rms += w.cwiseAbs2();
    rms = (rms / static_cast<double>(std::max<std::size_t>(1, d.load.size()))).cwiseSqrt();
    for (int c = 0; c < 6; ++c)
      nonlinear_.push_back({std::string("load_offset_") + wn[c], c < 3 ? "N" : "N m", std::max(1e-3, 0.01 * rms(c)), true});
  }
}

std::string StiffnessFamily::name() const {
  if (ext_.empty()) return "nominal (joint compliances)";
  std::string s;
  for (const auto& e : stiffness_extensions())
    if (ext_.count(e)) s += (s.empty() ? "" : "+") + e;
  return s;
}

void StiffnessFamily::design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const {
  const std::size_t n = d_.obs.size();
  A.setZero(static_cast<Eigen::Index>(6 * n), static_cast<Eigen::Index>(linear_.size()));
  Vector6d gain = Vector6d::Ones(), offset = Vector6d::Zero();
  if (i_gain_ >= 0) {
    Eigen::Index g = i_gain_;
    for (int c = 0; c < 6; ++c)
      if (c != d_.gain_reference) gain(c) += phi(g++);
  }
  if (i_offset_ >= 0) offset = phi.segment(i_offset_, 6);
  const auto nj = static_cast<Eigen::Index>(d_.joint_names.size());
  for (std::size_t k = 0; k < n; ++k) {
    const auto r0 = static_cast<Eigen::Index>(6 * k);
    const Vector6d w = gain.cwiseProduct(d_.load[k]) + offset;  // the load the robot really carried
    for (Eigen::Index j = 0; j < nj; ++j) A.block(r0, j, 6, 1) = d_.joint_ops[k][static_cast<std::size_t>(j)] * w;
    if (links_)
      for (std::size_t i = 0; i < d_.link_ops[k].size(); ++i) A.block(r0, nj + static_cast<Eigen::Index>(i), 6, 1) = d_.link_ops[k][i] * w;
    if (j_bias_ >= 0)
      for (int c = 0; c < 6; ++c) A(r0 + c, j_bias_ + c) = 1.0;
  }
}

std::string StiffnessFamily::check(const Fit& f) const {
  for (std::size_t j = 0; j < d_.joint_names.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    const double sd = std::sqrt(std::max(0.0, f.cov(i, i)));
    if (f.theta(i) < -2.0 * sd)
      return d_.joint_names[j] + " compliance " + std::to_string(f.theta(i)) + " rad/(N m) is negative: the joint would push back";
  }
  return "";
}

}  // namespace hil::diagnose
