// Linear estimation of θ = (K, K μ) at given geometry: solve_theta, the running least squares, the
// global and the instantaneous estimates.
#include <hil/contact_id/identification.hpp>
#include "identification_detail.hpp"

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hil::contact_id {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

namespace detail {

Eigen::VectorXd row_variances(const Eigen::VectorXd& e, int p) {
  const Eigen::Index n = e.size();
  double sf = 0.0, sm = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) (i % 6 < 3 ? sf : sm) += e[i] * e[i];
  const double dof = std::max(1.0, static_cast<double>(n - p)) / static_cast<double>(n);
  const double half = static_cast<double>(n) / 2.0;
  const double vf = sf / (half * dof), vm = sm / (half * dof);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = i % 6 < 3 ? vf : vm;
  return v;
}

}  // namespace detail

using detail::row_variances;

LinearEstimate solve_theta(const Eigen::MatrixX2d& A, const Eigen::VectorXd& b) {
  LinearEstimate e;
  e.rows = A.rows();
  const double n0 = A.col(0).norm(), n1 = A.col(1).norm();
  if (!(n0 > 0.0)) throw std::runtime_error("the regressor is zero: no interference in the samples used");
  if (n1 <= 1e-12 * n0) {
    // All contacts stick: only K is identifiable.
    const double K = A.col(0).dot(b) / (n0 * n0);
    e.theta = {K, kNaN};
    e.rank = 1;
    e.condition = std::numeric_limits<double>::infinity();
    const Eigen::VectorXd r = b - A.col(0) * K;
    const double dof = std::max<double>(1.0, static_cast<double>(A.rows()) - 1.0);
    e.sigma2 = r.squaredNorm() / dof;
    e.cov.setZero();
    e.cov(0, 0) = A.col(0).cwiseAbs2().dot(row_variances(r, 1)) / (n0 * n0 * n0 * n0);
    e.cov(1, 1) = kNaN;
    e.K = K;
    e.K_std = std::sqrt(e.cov(0, 0));
    e.mu = kNaN;
    e.mu_std = kNaN;
    e.mu_identifiable = false;
    e.relative_force_error = std::sqrt(r.squaredNorm() / static_cast<double>(A.rows()));
    e.note = "rank-deficient regressor: every contact sticks (tangential speed below v_t,m) in the samples used, so "
             "the friction column of Φ is zero; only K is identifiable, μ is not";
    return e;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& s = svd.singularValues();
  e.rank = s[1] > 1e-12 * s[0] ? 2 : 1;
  e.condition = e.rank == 2 ? s[0] / s[1] : std::numeric_limits<double>::infinity();
  svd.setThreshold(1e-12);
  e.theta = svd.solve(b);
  const Eigen::VectorXd r = b - A * e.theta;
  const double dof = std::max<double>(1.0, static_cast<double>(A.rows()) - 2.0);
  e.sigma2 = r.squaredNorm() / dof;
  e.relative_force_error = std::sqrt(r.squaredNorm() / static_cast<double>(A.rows()));
  if (e.rank == 2) {
    // cov = A^+ diag(σ_row²) A^+T with A^+ = V S^-1 U^T (per-group residual variances).
    const Eigen::MatrixXd B = svd.matrixU() * s.cwiseInverse().asDiagonal() * svd.matrixV().transpose();
    e.cov = B.transpose() * row_variances(r, 2).asDiagonal() * B;
  } else {
    e.cov.setConstant(kNaN);
    e.note = "rank-deficient regressor: the stiffness and friction columns are collinear; θ is the minimum-norm solution";
  }
  e.K = e.theta[0];
  e.K_std = std::sqrt(e.cov(0, 0));
  e.mu_identifiable = e.rank == 2;
  e.mu = e.theta[1] / e.theta[0];
  const Eigen::Vector2d g(-e.theta[1] / (e.theta[0] * e.theta[0]), 1.0 / e.theta[0]);
  e.mu_std = std::sqrt(std::max(0.0, g.dot(e.cov * g)));
  if (!(e.K > 0.0))
    e.note += (e.note.empty() ? "" : "; ") + std::string("the identified K is not positive: the data do not fit the contact model");
  return e;
}

void RunningLeastSquares::add(const Regressor& A, const Vector6d& b) {
  Eigen::Matrix<double, 8, 2> M;
  Eigen::Matrix<double, 8, 1> y;
  M << R_, A;
  y << z_, b;
  Eigen::HouseholderQR<Eigen::Matrix<double, 8, 2>> qr(M);
  const Eigen::Matrix<double, 8, 1> qy = qr.householderQ().transpose() * y;
  R_ = qr.matrixQR().topRows<2>().triangularView<Eigen::Upper>();
  z_ = qy.head<2>();
  rss_ += qy.tail<6>().squaredNorm();
  ++n_;
}

LinearEstimate RunningLeastSquares::estimate() const {
  LinearEstimate e;
  e.rows = static_cast<Eigen::Index>(6 * n_);
  if (n_ == 0 || !(std::abs(R_(0, 0)) > 0.0)) {
    e.note = "no contact yet";
    return e;
  }
  const double dof = std::max(1.0, static_cast<double>(e.rows) - 2.0);
  e.sigma2 = rss_ / dof;
  e.relative_force_error = std::sqrt(rss_ / static_cast<double>(e.rows));
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(R_);
  const auto s = svd.singularValues();
  e.rank = s[1] > 1e-12 * s[0] ? 2 : 1;
  e.condition = e.rank == 2 ? s[0] / s[1] : std::numeric_limits<double>::infinity();
  if (e.rank == 2) {
    e.theta = R_.triangularView<Eigen::Upper>().solve(z_);
    const Eigen::Matrix2d Ri = R_.triangularView<Eigen::Upper>().solve(Eigen::Matrix2d::Identity());
    e.cov = e.sigma2 * Ri * Ri.transpose();
    e.mu_identifiable = true;
    e.K = e.theta[0];
    e.mu = e.theta[1] / e.theta[0];
    const Eigen::Vector2d g(-e.theta[1] / (e.theta[0] * e.theta[0]), 1.0 / e.theta[0]);
    e.mu_std = std::sqrt(std::max(0.0, g.dot(e.cov * g)));
  } else {
    // Only the stiffness column carries information (all contacts stuck so far).
    e.K = z_[0] / R_(0, 0);
    e.theta = {e.K, kNaN};
    e.cov.setConstant(kNaN);
    e.cov(0, 0) = e.sigma2 / (R_(0, 0) * R_(0, 0));
    e.mu = kNaN;
    e.mu_std = kNaN;
    e.note = "every contact has stuck so far: only K is identifiable";
  }
  e.K_std = std::sqrt(e.cov(0, 0));
  return e;
}

LinearEstimate global_estimate(const ContactProblem& p, const Eigen::VectorXd& x) {
  Eigen::MatrixX2d A;
  p.regressor(x, A);
  return solve_theta(A, p.y());
}

std::vector<InstantEstimate> instantaneous(const ContactProblem& p, const Eigen::VectorXd& x, int window) {
  Eigen::MatrixX2d A;
  std::vector<int> n;
  p.regressor(x, A, &n);
  const auto L = static_cast<Eigen::Index>(p.used().size());
  const Eigen::Index half = std::max(0, window - 1) / 2;
  std::vector<InstantEstimate> out(static_cast<std::size_t>(L));
  for (Eigen::Index a = 0; a < L; ++a) {
    auto& e = out[static_cast<std::size_t>(a)];
    e.t_s = p.data()[static_cast<std::size_t>(p.used()[static_cast<std::size_t>(a)])].t_s;
    e.contacts = n[static_cast<std::size_t>(a)];
    const Eigen::Index lo = std::max<Eigen::Index>(0, a - half), hi = std::min<Eigen::Index>(L - 1, a + half);
    const auto Ab = A.middleRows(6 * lo, 6 * (hi - lo + 1));
    const auto bb = p.y().segment(6 * lo, 6 * (hi - lo + 1));
    if (!(Ab.col(0).norm() > 0.0)) continue;
    const auto est = solve_theta(Ab, bb);
    e.valid = true;
    e.K = est.K;
    e.mu_valid = est.mu_identifiable;
    e.mu = est.mu_identifiable ? est.mu : kNaN;
  }
  return out;
}

}  // namespace hil::contact_id
