// Observability of the geometric uncertainties on a run: analyse_observability.
#include <hil/contact_id/identification.hpp>
#include "identification_detail.hpp"

#include <Eigen/SVD>
#include <array>
#include <cmath>

namespace hil::contact_id {

Observability analyse_observability(const ContactProblem& p, const Eigen::VectorXd& x) {
  const int M = p.uncertainties();
  Observability o;
  o.ratio.setZero(M, 2);
  o.touched.resize(static_cast<std::size_t>(M));
  Eigen::MatrixX2d A;
  p.regressor(x, A);
  const Eigen::Index n = A.rows();
  auto centred = [](const Eigen::VectorXd& v) { return Eigen::VectorXd(v.array() - v.mean()); };
  auto sd = [&](const Eigen::VectorXd& v) {
    return std::sqrt(centred(v).squaredNorm() / std::max<double>(1.0, static_cast<double>(v.size()) - 1.0));
  };
  std::array<Eigen::MatrixXd, 2> C;
  for (int c = 0; c < 2; ++c) {
    C[static_cast<std::size_t>(c)].resize(n, M + 1);
    C[static_cast<std::size_t>(c)].col(0) = A.col(c);
  }
  const auto& sc = p.scene();
  std::vector<Eigen::MatrixX2d> dAs(static_cast<std::size_t>(M));
  for (int j = 0; j < M; ++j) {
    const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
    o.touched[static_cast<std::size_t>(j)] = p.touches(j);
    p.sensitivity(x, j, p.fd_step(j), dAs[static_cast<std::size_t>(j)]);
    const auto& dA = dAs[static_cast<std::size_t>(j)];
    for (int c = 0; c < 2; ++c) {
      C[static_cast<std::size_t>(c)].col(j + 1) = dA.col(c);
      const double s0 = sd(A.col(c));
      o.ratio(j, c) = s0 > 0.0 ? sd(dA.col(c)) / s0 : 0.0;
    }
    const double prior = detail::fitting_std(u);
    if (!p.touches(j) || dA.norm() == 0.0) {
      o.unobservable.push_back(u.name + " (its feature is never in contact)");
    } else if (dA.norm() * prior < 1e-2 * A.norm()) {
      o.weak.push_back(u.name);
    }
  }
  auto corr = [&](const Eigen::MatrixXd& X) {
    const Eigen::Index k = X.cols();
    Eigen::MatrixXd Z(X.rows(), k);
    for (Eigen::Index i = 0; i < k; ++i) {
      Eigen::VectorXd v = centred(X.col(i));
      const double nv = v.norm();
      Z.col(i) = nv > 0.0 ? Eigen::VectorXd(v / nv) : Eigen::VectorXd::Zero(X.rows());
    }
    return Eigen::MatrixXd(Z.transpose() * Z);
  };
  o.P1 = corr(C[0]);
  o.P2 = corr(C[1]);
  const bool col2 = A.col(1).norm() > 0.0;
  for (int j = 0; j < M; ++j) {
    if (!o.touched[static_cast<std::size_t>(j)]) continue;
    const double c1 = std::abs(o.P1(0, j + 1)), c2 = col2 ? std::abs(o.P2(0, j + 1)) : 1.0;
    if (c1 >= 0.85 && c2 >= 0.85) o.coupled.emplace_back(sc.uncertainties[static_cast<std::size_t>(j)].name, "theta");
    for (int l = j + 1; l < M; ++l) {
      const double d1 = std::abs(o.P1(j + 1, l + 1)), d2 = col2 ? std::abs(o.P2(j + 1, l + 1)) : 1.0;
      if (d1 >= 0.85 && d2 >= 0.85)
        o.coupled.emplace_back(sc.uncertainties[static_cast<std::size_t>(j)].name, sc.uncertainties[static_cast<std::size_t>(l)].name);
    }
  }
  // Singular values of the projected (Kaufman) Jacobian in prior-std units: how well the data
  // determine x beyond what θ absorbs.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(1e-12);
  const Eigen::Vector2d th = svd.solve(p.y());
  const Eigen::MatrixXd& U = svd.matrixU();
  Eigen::MatrixXd J(n, M);
  for (int j = 0; j < M; ++j) {
    const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
    const double prior = detail::fitting_std(u);
    Eigen::VectorXd g = dAs[static_cast<std::size_t>(j)] * th;
    g -= U * (U.transpose() * g);
    J.col(j) = prior * g / std::sqrt(static_cast<double>(n));
  }
  if (M > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> sj(J);
    for (Eigen::Index i = 0; i < sj.singularValues().size(); ++i) o.projected_singular_values.push_back(sj.singularValues()[i]);
  }
  return o;
}

}  // namespace hil::contact_id
