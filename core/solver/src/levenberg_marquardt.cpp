#include <hil/solver/levenberg_marquardt.hpp>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hil::solver {

const char* to_string(StopReason reason) noexcept {
  switch (reason) {
    case StopReason::relative_decrease: return "relative decrease below tolerance";
    case StopReason::statistical: return "statistically insignificant decrease";
    case StopReason::step_size: return "step below tolerance";
    case StopReason::small_rejected_step: return "rejected step below tolerance";
    case StopReason::no_decrease: return "no trial step decreased the cost";
    case StopReason::stall: return "stalled: too little gain over the last iterations";
    case StopReason::gradient: return "gradient below tolerance";
    case StopReason::max_iterations: return "iteration limit reached";
    case StopReason::no_parameters: return "no parameters to fit";
  }
  return "unknown stop reason";
}

Result levenberg_marquardt(const Problem& pb, const Eigen::VectorXd& x0, const Options& o, double cost0, const Eigen::VectorXd* r0) {
  if (!pb.residual || !pb.jacobian) throw std::invalid_argument("levenberg_marquardt: residual and jacobian are required");
  const Eigen::Index n = x0.size();
  const bool scaled = pb.scale.size() == n;
  const bool bounded = pb.lower.size() == n && pb.upper.size() == n;
  auto is_fixed = [&](Eigen::Index j) { return static_cast<std::size_t>(j) < pb.fixed.size() && pb.fixed[static_cast<std::size_t>(j)]; };
  auto unit_norm = [&](const Eigen::VectorXd& x) { return scaled ? x.cwiseQuotient(pb.scale).norm() : x.norm(); };

  Result res;
  res.x = x0;
  if (cost0 >= 0.0 && r0) {
    res.cost = cost0;
    res.r = *r0;
  } else {
    res.cost = pb.residual(res.x, res.r);
    ++res.evaluations;
    if (pb.accepted) pb.accepted();
  }
  if (n == 0) {
    res.converged = true;
    res.stop_reason = StopReason::no_parameters;
    return res;
  }
  double& f = res.cost;
  Eigen::VectorXd& x = res.x;
  Eigen::VectorXd& r = res.r;

  Eigen::MatrixXd J;
  Eigen::VectorXd D = Eigen::VectorXd::Ones(n), grad;
  double mu = -1.0, mu0 = 1.0, nu = 2.0;
  int secant = 0;        // secant updates since J was last computed
  bool need_jac = true;  // compute J before the next iteration
  std::vector<double> history{f};
  int insignificant = 0;
  Eigen::VectorXd rn;
  for (res.iterations = 0; res.iterations < o.max_iterations; ++res.iterations) {
    const bool fresh = need_jac || secant >= o.secant_updates;
    if (fresh) {
      pb.jacobian(x, r, J);
      ++res.jacobians;
      for (Eigen::Index j = 0; j < n; ++j)
        if (is_fixed(j)) J.col(j).setZero();
      secant = 0;
      need_jac = false;
    }
    if (o.kink_damping || o.gradient_tolerance > 0.0) {
      const Eigen::VectorXd gn = J.transpose() * r;
      if (o.kink_damping && grad.size() == n)
        for (Eigen::Index i = 0; i < n; ++i) D[i] = gn[i] * grad[i] < 0.0 ? 8.0 * D[i] : std::max(1.0, 0.5 * D[i]);
      grad = gn;
    }
    if (mu < 0.0 && o.damping == Damping::gain_ratio) {
      const double jmax = J.colwise().squaredNorm().maxCoeff();
      mu = mu0 = 1e-3 * (jmax > 0.0 ? jmax : 1.0);
    }
    // Stall: the last stall_iterations accepted steps together gained too little.
    const auto h = static_cast<std::size_t>(std::max(0, o.stall_iterations));
    if (o.stall_iterations > 0 && history.size() > h && history[history.size() - 1 - h] - f <= o.stall_tolerance * f) {
      res.converged = true;
      res.stop_reason = StopReason::stall;
      break;
    }
    if (o.gradient_tolerance > 0.0 && grad.lpNorm<Eigen::Infinity>() < o.gradient_tolerance * std::max(1.0, f)) {
      if (!fresh) {
        need_jac = true;
        continue;
      }
      res.converged = true;
      res.stop_reason = StopReason::gradient;
      break;
    }
    // The damped step min ‖r + J d‖² + μ dᵀD d by the SVD of J D^-1/2 (d = D^-1/2 e): one
    // factorisation per iteration serves every trial μ.
    const Eigen::VectorXd Dh = D.cwiseSqrt();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(o.kink_damping ? Eigen::MatrixXd(J * Dh.cwiseInverse().asDiagonal()) : J,
                                          Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    const Eigen::VectorXd g = svd.matrixU().transpose() * r;
    if (mu < 0.0) mu = mu0 = 1e-3 * (sv.size() > 0 && sv(0) > 0 ? sv(0) * sv(0) : 1.0);
    const double mu_before = mu;
    bool accepted = false, small_rejected = false;
    double df = 0.0, f_old = f, step_norm = 0.0;
    const int trials = fresh ? o.max_trials : o.max_trials_secant;
    for (int tries = 0; tries < trials && !accepted; ++tries) {
      Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
      for (Eigen::Index i = 0; i < sv.size(); ++i)
        if (sv(i) > o.singular_cutoff * sv(0)) d -= (sv(i) * g(i) / (sv(i) * sv(i) + mu)) * svd.matrixV().col(i);
      if (o.kink_damping) d = d.cwiseQuotient(Dh);
      Eigen::VectorXd trial = scaled ? Eigen::VectorXd(x + d.cwiseProduct(pb.scale)) : Eigen::VectorXd(x + d);
      for (Eigen::Index j = 0; j < n; ++j) {
        if (bounded) trial(j) = std::clamp(trial(j), pb.lower(j), pb.upper(j));
        if (is_fixed(j)) trial(j) = x(j);
      }
      const double fn = pb.residual(trial, rn);
      ++res.evaluations;
      if (fn < f) {
        df = f - fn;
        step_norm = d.norm();
        if (o.damping == Damping::gain_ratio) {
          const double predicted = r.squaredNorm() - (r + J * d).squaredNorm();  // undamped linear model
          const double rho = predicted > 0.0 ? df / predicted : 0.0;
          mu = std::max(mu * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)), 1e-12 * mu0);
          nu = 2.0;
        } else {
          mu = std::max(mu / 3.0, 1e-12);
        }
        if (o.secant_updates > 0) {  // Broyden: J du = Δr for the step taken (after the bounds)
          const Eigen::VectorXd du = scaled ? Eigen::VectorXd((trial - x).cwiseQuotient(pb.scale)) : Eigen::VectorXd(trial - x);
          if (du.squaredNorm() > 0) {
            J += ((rn - r) - J * du) * (du.transpose() / du.squaredNorm());
            ++secant;
          }
        }
        f_old = f;
        x = trial;
        r.swap(rn);
        f = fn;
        if (pb.accepted) pb.accepted();
        accepted = true;
        history.push_back(f);
      } else {
        if (o.damping == Damping::gain_ratio) {
          mu *= nu;
          nu *= 2.0;
        } else {
          mu *= 4.0;
        }
        if (o.stop_on_small_rejected_step && d.norm() <= o.step_absolute + o.step_relative * unit_norm(x)) {
          small_rejected = true;
          break;
        }
      }
    }
    bool stop = !accepted;
    StopReason reason = small_rejected ? StopReason::small_rejected_step : StopReason::no_decrease;
    auto stop_for = [&](StopReason why) {  // the first rule that holds names the stop
      if (!stop) reason = why;
      stop = true;
    };
    if (accepted) {
      if (o.statistical_tolerance > 0.0) {
        const double noise = o.data_rows >= 0 ? r.head(o.data_rows).squaredNorm() : r.squaredNorm();
        insignificant = df <= o.statistical_tolerance * noise / o.degrees_of_freedom ? insignificant + 1 : 0;
        if (insignificant >= o.statistical_repeats) stop_for(StopReason::statistical);
      }
      if (df <= o.relative_decrease * f_old) stop_for(StopReason::relative_decrease);
      const bool step_rule = o.step_absolute > 0.0 || o.step_relative > 0.0;
      if (step_rule && step_norm <= o.step_absolute + o.step_relative * unit_norm(x)) stop_for(StopReason::step_size);
    }
    if (stop) {
      if (!fresh) {  // confirm with a freshly computed Jacobian
        if (!accepted) mu = mu_before;
        need_jac = true;
        continue;
      }
      res.converged = true;
      res.stop_reason = reason;
      break;
    }
  }
  if (!res.converged) res.stop_reason = StopReason::max_iterations;
  return res;
}

}  // namespace hil::solver
