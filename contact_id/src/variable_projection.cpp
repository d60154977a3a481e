// Geometric identification by variable projection: identify_geometry and projected_objective.
#include <hil/contact_id/identification.hpp>
#include "identification_detail.hpp"
#include <hil/solver/levenberg_marquardt.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace hil::contact_id {

using detail::row_variances;

namespace {

struct Vp {
  const ContactProblem& p;
  double lambda;
  std::vector<int> idx;  ///< fitted uncertainty indices
  Eigen::VectorXd xd, sd;
  int evaluations = 0;
  int jacobians = 0;
  Eigen::MatrixX2d A;
  Eigen::MatrixX2d dA;

  Vp(const ContactProblem& pp, double lam, const std::vector<bool>& fitted) : p(pp), lambda(lam) {
    xd = p.scene().design();
    sd.resize(p.uncertainties());
    for (int j = 0; j < p.uncertainties(); ++j) {
      sd[j] = detail::fitting_std(p.scene().uncertainties[static_cast<std::size_t>(j)]);
      if (fitted[static_cast<std::size_t>(j)]) idx.push_back(j);
    }
  }
  int m() const { return static_cast<int>(idx.size()); }
  Eigen::VectorXd x_of(const Eigen::VectorXd& z) const {
    Eigen::VectorXd x = xd;
    for (int i = 0; i < m(); ++i) x[idx[static_cast<std::size_t>(i)]] += sd[idx[static_cast<std::size_t>(i)]] * z[i];
    return x;
  }
  /// Residual [r/sqrt(n); sqrt(λ/m) z]; fills the SVD of A if asked.
  double residual(const Eigen::VectorXd& z, Eigen::VectorXd& R, Eigen::Vector2d& theta, double* fc = nullptr, double* gc = nullptr) {
    ++evaluations;
    p.regressor(x_of(z), A);
    const double n = static_cast<double>(A.rows());
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-12);
    theta = svd.solve(p.y());
    R.resize(A.rows() + m());
    R.head(A.rows()) = (p.y() - A * theta) / std::sqrt(n);
    R.tail(m()) = std::sqrt(lambda / std::max(1, m())) * z;
    const double f = R.head(A.rows()).squaredNorm();
    const double g = z.squaredNorm() / std::max(1, m());
    if (fc) *fc = f;
    if (gc) *gc = g;
    return f + lambda * g;
  }
  /// Jacobian of the residual at z (after residual(z) filled A and theta).
  void jacobian(const Eigen::VectorXd& z, const Eigen::VectorXd& R, const Eigen::Vector2d& theta, VpJacobian kind, Eigen::MatrixXd& J) {
    ++jacobians;
    const Eigen::Index n = A.rows();
    const double sn = std::sqrt(static_cast<double>(n));
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::MatrixXd& U = svd.matrixU();
    const Eigen::Vector2d s = svd.singularValues();
    const Eigen::Matrix2d V = svd.matrixV();
    Eigen::Vector2d sinv;
    for (int i = 0; i < 2; ++i) sinv[i] = s[i] > 1e-12 * s[0] ? 1.0 / s[i] : 0.0;
    const Eigen::VectorXd r = R.head(n) * sn;
    const Eigen::VectorXd x = x_of(z);
    J.setZero(n + m(), m());
    for (int i = 0; i < m(); ++i) {
      const int j = idx[static_cast<std::size_t>(i)];
      p.sensitivity(x, j, p.fd_step(j), dA);
      Eigen::VectorXd g = dA * theta;
      g -= U * (U.transpose() * g);  // P⊥ dA θ
      if (kind == VpJacobian::golub_pereyra) {
        const Eigen::Vector2d t = V.transpose() * (dA.transpose() * r);
        g += U * sinv.cwiseProduct(t);  // (A^+)^T dA^T r
      }
      J.col(i).head(n) = -sd[j] * g / sn;
    }
    J.bottomRows(m()).diagonal().setConstant(std::sqrt(lambda / std::max(1, m())));
  }
};

}  // namespace

double projected_objective(const ContactProblem& p, const Eigen::VectorXd& x, double lambda, const std::vector<bool>& fitted,
                           double* force_cost, double* geometric_cost) {
  Vp vp(p, lambda, fitted);
  Eigen::VectorXd z(vp.m());
  for (int i = 0; i < vp.m(); ++i) {
    const int j = vp.idx[static_cast<std::size_t>(i)];
    z[i] = (x[j] - vp.xd[j]) / vp.sd[j];
  }
  Eigen::VectorXd R;
  Eigen::Vector2d th;
  return vp.residual(z, R, th, force_cost, geometric_cost);
}

GeometricEstimate identify_geometry(const ContactProblem& p, const GeometricOptions& o, const Eigen::VectorXd* x0) {
  if (!(o.lambda >= 0.0) || !std::isfinite(o.lambda)) throw std::invalid_argument("lambda must be finite and >= 0");
  const int M = p.uncertainties();
  std::vector<bool> fitted(static_cast<std::size_t>(M), false);
  for (int j = 0; j < M; ++j) fitted[static_cast<std::size_t>(j)] = (o.fit.empty() || o.fit[static_cast<std::size_t>(j)]) && p.touches(j);
  Vp vp(p, o.lambda, fitted);
  if (vp.m() == 0)
    throw std::runtime_error("no geometric uncertainty can be fitted: the features they move are never near a contact "
                             "in this run (unobservable)");
  const int m = vp.m();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(m);
  if (x0)
    for (int i = 0; i < m; ++i) {
      const int j = vp.idx[static_cast<std::size_t>(i)];
      z[i] = ((*x0)[j] - vp.xd[j]) / vp.sd[j];
    }
  GeometricEstimate g;
  g.lambda = o.lambda;
  Eigen::VectorXd R;
  Eigen::Vector2d th;
  double f = vp.residual(z, R, th);

  if (o.solver == Solver::levenberg_marquardt) {
    // Levenberg-Marquardt in prior-std units (z) by hil::solver, damping μ D with a per-parameter
    // diagonal D.
    //
    // Where the max-depth δ has a kink (a face turning through parallel: the deepest vertex jumps
    // to the other end) the objective is V-shaped along that parameter and its minimum sits on the
    // kink. The Gauss-Newton model, built from the slope of one side, then overshoots across the
    // kink at every step; a single μ for all parameters makes every other parameter crawl with it
    // (the old behaviour: 200 iterations). A change of sign of ∂f/∂z_j between two accepted
    // iterates says the step went past the minimum along z_j, so z_j's own damping D_jj is raised
    // (x8, relaxed /2 while the sign holds): a parameter sitting on a kink converges to it
    // geometrically while the smooth ones keep Gauss-Newton steps.
    //
    // Stopping: besides the relative tolerance, progress is statistically meaningless once an
    // accepted step lowers the objective by less than statistical_tolerance × σ²/(6L), σ² ≈ the force
    // cost (a change of Δχ² = 6L Δf/σ² < statistical_tolerance), twice in a row; or when five
    // iterations together gained less than 100 x tolerance.
    Eigen::VectorXd Rn;
    Eigen::Vector2d thn;
    solver::Problem pb;
    pb.residual = [&](const Eigen::VectorXd& zt, Eigen::VectorXd& r) { return vp.residual(zt, r, thn); };
    pb.accepted = [&] { th = thn; };
    pb.jacobian = [&](const Eigen::VectorXd& zc, const Eigen::VectorXd& r, Eigen::MatrixXd& J) { vp.jacobian(zc, r, th, o.jacobian, J); };
    solver::Options so;
    so.max_iterations = o.max_iterations;
    so.damping = solver::Damping::gain_ratio;
    so.max_trials = 30;
    so.kink_damping = true;
    so.relative_decrease = o.tolerance / (1.0 + o.tolerance);  // f_old - f_new <= tolerance × f_new
    so.statistical_tolerance = o.statistical_tolerance;
    so.data_rows = p.rows();  // the force rows; the last m are the prior's
    so.degrees_of_freedom = static_cast<double>(p.rows());
    so.statistical_repeats = 2;
    so.step_absolute = so.step_relative = o.x_tolerance;
    so.stop_on_small_rejected_step = true;
    so.stall_iterations = 5;
    so.stall_tolerance = 100.0 * o.tolerance;
    so.gradient_tolerance = 1e-14;
    const auto sr = solver::levenberg_marquardt(pb, z, so, f, &R);
    z = sr.x;
    R = sr.r;
    f = sr.cost;
    g.iterations = sr.iterations;
    g.converged = sr.converged;
  } else {
    // Nelder-Mead with the adaptive coefficients of Gao and Han (2012).
    const double n = m;
    const double alpha = 1.0, beta = 1.0 + 2.0 / n, gamma = 0.75 - 1.0 / (2.0 * n), delta = 1.0 - 1.0 / n;
    std::vector<Eigen::VectorXd> S(static_cast<std::size_t>(m + 1), z);
    std::vector<double> F(static_cast<std::size_t>(m + 1));
    // A simplex of unit steps (one prior std) about z0, whose value is f0.
    auto start = [&](const Eigen::VectorXd& z0, double f0) {
      for (auto& v : S) v = z0;
      F[0] = f0;
      for (int i = 0; i < m; ++i) {
        S[static_cast<std::size_t>(i + 1)][i] += 1.0;
        F[static_cast<std::size_t>(i + 1)] = vp.residual(S[static_cast<std::size_t>(i + 1)], R, th);
      }
    };
    start(z, f);
    std::vector<int> ord(static_cast<std::size_t>(m + 1));
    auto eval = [&](const Eigen::VectorXd& v) { return vp.residual(v, R, th); };
    for (g.iterations = 0; g.iterations < o.max_iterations * 50 && vp.evaluations < o.max_evaluations; ++g.iterations) {
      std::iota(ord.begin(), ord.end(), 0);
      std::sort(ord.begin(), ord.end(), [&](int a, int b) { return F[static_cast<std::size_t>(a)] < F[static_cast<std::size_t>(b)]; });
      const auto best = static_cast<std::size_t>(ord.front()), worst = static_cast<std::size_t>(ord.back()),
                 second = static_cast<std::size_t>(ord[ord.size() - 2]);
      double diam = 0.0;
      for (const auto& v : S) diam = std::max(diam, (v - S[best]).lpNorm<Eigen::Infinity>());
      if (F[best] <= o.stop_at_objective) {
        g.converged = true;
        break;
      }
      if (F[worst] - F[best] <= o.tolerance * std::abs(F[best]) + 1e-300 && diam <= o.x_tolerance * 10.0) {
        // Collapsed. A restart from a full-size simplex about the best vertex can leave a kink
        // the collapsed simplex could not (the usual remedy for Nelder-Mead's stalls).
        if (g.restarts < o.nelder_mead_restarts) {
          ++g.restarts;
          start(Eigen::VectorXd(S[best]), F[best]);
          continue;
        }
        g.converged = true;
        break;
      }
      Eigen::VectorXd c = Eigen::VectorXd::Zero(m);
      for (std::size_t i = 0; i < S.size(); ++i)
        if (i != worst) c += S[i];
      c /= n;
      const Eigen::VectorXd xr = c + alpha * (c - S[worst]);
      const double fr = eval(xr);
      if (fr < F[best]) {
        const Eigen::VectorXd xe = c + beta * (xr - c);
        const double fe = eval(xe);
        if (fe < fr) {
          S[worst] = xe;
          F[worst] = fe;
        } else {
          S[worst] = xr;
          F[worst] = fr;
        }
      } else if (fr < F[second]) {
        S[worst] = xr;
        F[worst] = fr;
      } else {
        const bool outside = fr < F[worst];
        const Eigen::VectorXd xc = outside ? Eigen::VectorXd(c + gamma * (xr - c)) : Eigen::VectorXd(c - gamma * (xr - c));
        const double fc = eval(xc);
        if (fc < (outside ? fr : F[worst])) {
          S[worst] = xc;
          F[worst] = fc;
        } else {
          for (std::size_t i = 0; i < S.size(); ++i)
            if (i != best) {
              S[i] = S[best] + delta * (S[i] - S[best]);
              F[i] = eval(S[i]);
            }
        }
      }
    }
    const auto bi = static_cast<std::size_t>(std::min_element(F.begin(), F.end()) - F.begin());
    z = S[bi];
  }

  g.x = vp.x_of(z);
  g.fitted = fitted;
  g.objective = vp.residual(z, R, th, &g.force_cost, &g.geometric_cost);
  g.evaluations = vp.evaluations;
  g.jacobian_evaluations = vp.jacobians;

  // θ at x and the joint covariance of (θ, x_fitted): sandwich form of the regularised estimator.
  Eigen::MatrixX2d A;
  p.regressor(g.x, A);
  g.theta = solve_theta(A, p.y());
  const Eigen::Index n = A.rows();
  Eigen::MatrixXd J(n, 2 + m);
  J.leftCols<2>() = A;
  Eigen::MatrixX2d dA;
  for (int i = 0; i < m; ++i) {
    const int j = vp.idx[static_cast<std::size_t>(i)];
    p.sensitivity(g.x, j, p.fd_step(j), dA);
    J.col(2 + i) = dA * g.theta.theta;
  }
  const Eigen::VectorXd e = p.y() - A * g.theta.theta;
  const Eigen::VectorXd s2 = row_variances(e, 2 + m);
  const double c = static_cast<double>(n) * o.lambda / std::max(1, m);
  Eigen::MatrixXd Jaug = Eigen::MatrixXd::Zero(n + m, 2 + m);
  Jaug.topRows(n) = J;
  for (int i = 0; i < m; ++i) Jaug(n + i, 2 + i) = std::sqrt(c) / vp.sd[vp.idx[static_cast<std::size_t>(i)]];
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Jaug);
  const Eigen::MatrixXd Rf = qr.matrixQR().topRows(2 + m).triangularView<Eigen::Upper>();
  // H^{-1} = R^{-1} R^{-T}; cov = s2 H^{-1} (J^T J) H^{-1} = s2 (R^{-1} R^{-T} J^T)(...)^T
  const Eigen::MatrixXd Ri = Rf.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(2 + m, 2 + m));
  const Eigen::MatrixXd B = J * (Ri * Ri.transpose());  // n x (2+m)
  Eigen::MatrixXd cov = B.transpose() * s2.asDiagonal() * B;
  g.x_std = Eigen::VectorXd::Zero(M);
  for (int i = 0; i < m; ++i) g.x_std[vp.idx[static_cast<std::size_t>(i)]] = std::sqrt(std::max(0.0, cov(2 + i, 2 + i)));
  if (g.theta.rank == 2) {
    g.theta.cov = cov.topLeftCorner<2, 2>();
    g.theta.K_std = std::sqrt(g.theta.cov(0, 0));
    const Eigen::Vector2d gr(-g.theta.theta[1] / (g.theta.theta[0] * g.theta.theta[0]), 1.0 / g.theta.theta[0]);
    g.theta.mu_std = std::sqrt(std::max(0.0, gr.dot(g.theta.cov * gr)));
  }
  return g;
}

}  // namespace hil::contact_id
