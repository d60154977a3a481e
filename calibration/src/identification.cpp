#include <hil/calibration/identification.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hil::calibration {

CompressedSystem compress(const Eigen::Ref<const Eigen::MatrixXd>& A_w, const Eigen::Ref<const Eigen::VectorXd>& t_w) {
  if (A_w.rows() != t_w.size()) throw std::invalid_argument("compress: A and t differ in rows");
  CompressedSystem out;
  out.rows = A_w.rows();
  const Eigen::Index k = std::min(A_w.rows(), A_w.cols());
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(A_w);
  out.R = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
  Eigen::VectorXd qt = t_w;
  qt.applyOnTheLeft(qr.householderQ().adjoint());
  out.z = qt.head(k);
  out.rss_outside = qt.tail(qt.size() - k).squaredNorm();
  return out;
}

Eigen::MatrixXd scaled_columns(const CompressedSystem& sys, const std::vector<int>& cols, Eigen::VectorXd* scale) {
  Eigen::MatrixXd M(sys.R.rows(), static_cast<Eigen::Index>(cols.size()));
  Eigen::VectorXd s(static_cast<Eigen::Index>(cols.size()));
  double largest = 0.0;
  for (int c : cols) largest = std::max(largest, sys.R.col(c).norm());
  for (std::size_t i = 0; i < cols.size(); ++i) {
    const auto c = static_cast<Eigen::Index>(i);
    M.col(c) = sys.R.col(cols[i]);
    const double nrm = M.col(c).norm();
    if (nrm <= kZeroColumn * largest) {
      // Rounding noise, not information: scaling it to unit norm would invent a direction.
      M.col(c).setZero();
      s[c] = 1.0;
    } else {
      s[c] = 1.0 / nrm;
      M.col(c) *= s[c];
    }
  }
  if (scale) *scale = s;
  return M;
}

namespace {
int count_rank(const Eigen::VectorXd& sv, double tolerance) {
  if (sv.size() == 0 || sv[0] <= 0.0) return 0;
  int r = 0;
  for (Eigen::Index i = 0; i < sv.size(); ++i)
    if (sv[i] > tolerance * sv[0]) ++r;
  return r;
}
}  // namespace

int rank_of(const CompressedSystem& sys, const std::vector<int>& cols, const RankOptions& options, Eigen::VectorXd* singular_values) {
  if (cols.empty()) {
    if (singular_values) singular_values->resize(0);
    return 0;
  }
  const Eigen::MatrixXd M = scaled_columns(sys, cols);
  Eigen::BDCSVD<Eigen::MatrixXd> svd(M);
  if (singular_values) *singular_values = svd.singularValues();
  return count_rank(svd.singularValues(), options.tolerance);
}

LsqSolution solve(const CompressedSystem& sys, const std::vector<int>& free_cols, const std::vector<int>& fixed_cols,
                  const Eigen::Ref<const Eigen::VectorXd>& fixed_values, const RankOptions& options) {
  if (fixed_values.size() != static_cast<Eigen::Index>(fixed_cols.size())) throw std::invalid_argument("solve: one value per fixed column");
  LsqSolution out;
  const auto n = static_cast<Eigen::Index>(free_cols.size());
  Eigen::VectorXd rhs = sys.z;
  for (std::size_t i = 0; i < fixed_cols.size(); ++i)
    rhs.noalias() -= sys.R.col(fixed_cols[i]) * fixed_values[static_cast<Eigen::Index>(i)];
  if (n == 0) {
    out.rss = sys.rss_outside + rhs.squaredNorm();
    out.dof = sys.rows;
    out.full_rank = true;
    out.sigma0_sq = out.dof > 0 ? out.rss / static_cast<double>(out.dof) : 0.0;
    return out;
  }
  Eigen::VectorXd scale;
  const Eigen::MatrixXd M = scaled_columns(sys, free_cols, &scale);
  Eigen::BDCSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  out.singular_values = sv;
  out.rank = count_rank(sv, options.tolerance);
  out.full_rank = out.rank == n;
  const Eigen::Index r = out.rank;
  const Eigen::MatrixXd& U = svd.matrixU();
  const Eigen::MatrixXd& V = svd.matrixV();
  Eigen::VectorXd coeff = (U.leftCols(r).transpose() * rhs).cwiseQuotient(sv.head(r));
  const Eigen::VectorXd x_scaled = V.leftCols(r) * coeff;
  out.value = scale.cwiseProduct(x_scaled);
  out.rss = sys.rss_outside + (rhs - M * x_scaled).squaredNorm();
  out.dof = sys.rows - r;
  out.sigma0_sq = out.dof > 0 ? out.rss / static_cast<double>(out.dof) : std::numeric_limits<double>::quiet_NaN();
  out.condition = out.full_rank ? sv[0] / sv[n - 1] : std::numeric_limits<double>::infinity();
  if (out.full_rank) {
    // cov = D V Σ^-2 Vᵀ D
    const Eigen::MatrixXd W = scale.asDiagonal() * V * sv.cwiseInverse().asDiagonal();
    out.covariance = W * W.transpose();
    out.std_dev = out.covariance.diagonal().cwiseSqrt();
  } else {
    out.covariance = Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::quiet_NaN());
    out.std_dev = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

LsqSolution solve(const CompressedSystem& sys, const RankOptions& options) {
  std::vector<int> cols(static_cast<std::size_t>(sys.R.cols()));
  for (std::size_t i = 0; i < cols.size(); ++i) cols[i] = static_cast<int>(i);
  return solve(sys, cols, {}, Eigen::VectorXd(), options);
}

const char* to_string(PnrClass c) {
  switch (c) {
    case PnrClass::g1_plus: return "G1+";
    case PnrClass::g1_tilde: return "G1~";
    case PnrClass::g1_minus: return "G1-";
  }
  return "?";
}

PnrClass classify(double pnr, const PnrThresholds& t) {
  if (pnr >= t.high) return PnrClass::g1_plus;
  if (pnr >= t.low) return PnrClass::g1_tilde;
  return PnrClass::g1_minus;
}

}  // namespace hil::calibration
