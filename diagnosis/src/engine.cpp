#include <hil/diagnose/engine.hpp>
#include <hil/parallel/run_tasks.hpp>
#include <hil/solver/levenberg_marquardt.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace hil::diagnose {

std::vector<Eigen::VectorXd> ModelFamily::starts() const { return {Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nonlinear().size()))}; }

std::vector<Reported> ModelFamily::report(const Fit& f) const {
  std::vector<Reported> out;
  const auto lin = linear();
  const auto nl = nonlinear();
  const Eigen::Index p = static_cast<Eigen::Index>(lin.size());
  for (Eigen::Index i = 0; i < p; ++i) {
    const auto& q = lin[static_cast<std::size_t>(i)];
    out.push_back({q.name, q.unit, f.theta(i), std::sqrt(std::max(0.0, f.cov(i, i))), q.extension});
  }
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(nl.size()); ++i) {
    const auto& q = nl[static_cast<std::size_t>(i)];
    out.push_back({q.name, q.unit, f.phi(i), std::sqrt(std::max(0.0, f.cov(p + i, p + i))), q.extension});
  }
  return out;
}

namespace {

/// The weighted rows of the samples `s` of a 6N-row matrix, into `out` (its storage reused when
/// the size is the same).
void rows_of(const Eigen::MatrixXd& A, const std::vector<int>& s, const Eigen::Matrix<double, 6, 1>& w, Eigen::MatrixXd& out) {
  out.resize(static_cast<Eigen::Index>(6 * s.size()), A.cols());
  for (std::size_t a = 0; a < s.size(); ++a)
    for (int c = 0; c < 6; ++c) out.row(static_cast<Eigen::Index>(6 * a) + c) = w(c) * A.row(6 * s[a] + c);
}

/// Least squares with scaled columns by complete orthogonal decomposition (minimum-norm when
/// rank deficient): never the normal equations. One object solves again and again without
/// allocating: a fit's designs are MBs each, and fresh ones every evaluation cost more in page
/// faults than the decomposition itself (docs/performance.md, "The heap policy").
class LeastSquares {
 public:
  // The threshold decides the rank inside compute(): set before it (set after, it is ignored and a
  // nearly collinear design gets a wrong solution).
  LeastSquares() { cod_.setThreshold(1e-10); }
  Eigen::VectorXd solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
    scale_ = A.colwise().norm().transpose();
    for (Eigen::Index j = 0; j < scale_.size(); ++j)
      if (!(scale_(j) > 0)) scale_(j) = 1.0;
    As_ = A * scale_.cwiseInverse().asDiagonal();
    cod_.compute(As_);
    return cod_.solve(b).cwiseQuotient(scale_);
  }

 private:
  Eigen::VectorXd scale_;
  Eigen::MatrixXd As_;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod_;
};

Eigen::VectorXd solve_ls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) { return LeastSquares().solve(A, b); }

struct Projected {
  Eigen::VectorXd theta, r;
  double cost = 0.0;
  std::vector<bool> held;  ///< per θ: held at its bound 0 (Param::lower) by the projection
};

/// The designs A(φ) already computed, by φ. One cache serves a model's full fit, its folds and
/// their predictions: the starts (every fold evaluates them) are kept; any other design only while
/// it is among the last few.
/// A(φ) is deterministic, so a cached design is the one a new evaluation would give.
class DesignCache {
 public:
  DesignCache(const ModelFamily& m, std::size_t samples) : m_(m), data_(m.make_data()), rows_(static_cast<Eigen::Index>(6 * samples)) {}
  /// A(φ); `keep`: hold it for the rest of the cache's life, while the kept designs stay within
  /// kKeptBytes (beyond it, like any other).
  const Eigen::MatrixXd& get(const Eigen::VectorXd& phi, bool keep = false) {
    const Key key(phi.data(), phi.data() + phi.size());
    if (const auto it = kept_.find(key); it != kept_.end()) return it->second;
    const auto room = [&](const Eigen::MatrixXd& A) {
      const std::size_t bytes = sizeof(double) * static_cast<std::size_t>(A.size());
      if (!keep || kept_bytes_ + bytes > kKeptBytes) return false;
      kept_bytes_ += bytes;
      return true;
    };
    for (auto it = recent_.begin(); it != recent_.end(); ++it)
      if (it->first == key) {
        if (room(it->second)) {
          auto& A = kept_[key];
          A.swap(it->second);
          recent_.erase(it);
          return A;
        }
        return it->second;
      }
    Eigen::MatrixXd A;
    m_.design(phi, A, *data_);
    ++computed;
    if (A.rows() != rows_) throw std::logic_error(m_.name() + ": design has the wrong number of rows");
    if (room(A)) return kept_[key] = std::move(A);
    if (recent_.size() >= kRecent) recent_.pop_back();
    recent_.emplace_front(key, std::move(A));
    return recent_.front().second;
  }
  int computed = 0;  ///< designs evaluated (not served from the cache)

 private:
  using Key = std::vector<double>;
  static constexpr std::size_t kRecent = 24;  // an LM iteration: q columns and up to 12 trials
  // The kept designs' memory per cache (a score has one per worker): ~450 designs of a 1,500-sample
  // run with 8 columns, ~65 of a 10,000-sample one (whose later starts are then designed again).
  static constexpr std::size_t kKeptBytes = std::size_t{256} << 20;
  std::size_t kept_bytes_ = 0;
  const ModelFamily& m_;
  std::unique_ptr<FamilyData> data_;  ///< this cache's evaluator's: a cache is used by one thread
  Eigen::Index rows_;
  std::map<Key, Eigen::MatrixXd> kept_;
  std::list<std::pair<Key, Eigen::MatrixXd>> recent_;
};

class Evaluator {
 public:
  Evaluator(DesignCache& cache, const Observations& obs, const std::vector<int>& train) : cache_(cache), obs_(obs), train_(train) {
    b_.resize(static_cast<Eigen::Index>(6 * train.size()));
    for (std::size_t a = 0; a < train.size(); ++a)
      for (int c = 0; c < 6; ++c) b_(static_cast<Eigen::Index>(6 * a) + c) = obs.weight(c) * obs.y(train[a], c);
  }
  /// The weighted design on the training rows; the columns of fixed θ are 0 (θ_j = 0 then). In
  /// this evaluator's one buffer: valid until its next call.
  const Eigen::MatrixXd& weighted_design(const Eigen::VectorXd& phi, bool keep = false) {
    ++evaluations;
    rows_of(cache_.get(phi, keep), train_, obs_.weight, A_);
    for (std::size_t j = 0; j < fixed_theta.size(); ++j)
      if (fixed_theta[j]) A_.col(static_cast<Eigen::Index>(j)).setZero();
    return A_;
  }
  std::vector<bool> fixed_theta;
  std::vector<bool> nonnegative_theta;  ///< θ bounded below by 0 (Param::lower of a linear parameter)
  /// θ(φ) by least squares; a θ bounded below by 0 that the solution puts below it is held at 0 and
  /// the rest solved again, until none is. For one bounded θ (the only case there is: contact_damping's
  /// μ_D D) that is the bounded problem's solution: the cost is convex in θ, so when its unbounded
  /// minimum lies beyond the bound, the bounded one lies on it. The projected cost stays continuous in φ.
  Projected project(const Eigen::VectorXd& phi, bool keep = false) {
    const Eigen::MatrixXd& A = weighted_design(phi, keep);
    Projected p;
    p.theta = ls_.solve(A, b_);
    p.held.assign(static_cast<std::size_t>(A.cols()), false);
    auto below = [&] {
      bool any = false;
      for (std::size_t j = 0; j < nonnegative_theta.size() && j < p.held.size(); ++j)
        if (nonnegative_theta[j] && !p.held[j] && p.theta(static_cast<Eigen::Index>(j)) < 0.0) {
          p.held[j] = true;
          any = true;
        }
      return any;
    };
    if (below()) {
      Eigen::MatrixXd Ah = A;  // rare: a copy, the buffer stays the design
      do {
        for (std::size_t j = 0; j < p.held.size(); ++j)
          if (p.held[j]) Ah.col(static_cast<Eigen::Index>(j)).setZero();
        p.theta = ls_.solve(Ah, b_);
        for (std::size_t j = 0; j < p.held.size(); ++j)
          if (p.held[j]) p.theta(static_cast<Eigen::Index>(j)) = 0.0;
      } while (below());
    }
    p.r = b_ - A * p.theta;
    p.cost = p.r.squaredNorm();
    return p;
  }
  const Eigen::VectorXd& b() const { return b_; }
  int evaluations = 0;

 private:
  DesignCache& cache_;
  const Observations& obs_;
  const std::vector<int>& train_;
  Eigen::VectorXd b_;
  Eigen::MatrixXd A_;  // weighted_design's buffer
  LeastSquares ls_;
};

Eigen::VectorXd clamp(const Eigen::VectorXd& phi, const std::vector<Param>& nl) {
  Eigen::VectorXd out = phi;
  for (Eigen::Index j = 0; j < out.size(); ++j)
    out(j) = std::clamp(out(j), nl[static_cast<std::size_t>(j)].lower, nl[static_cast<std::size_t>(j)].upper);
  return out;
}

double fd_step(const Param& q, double value) {
  double h = 1e-4 * q.scale;
  if (value + h > q.upper) h = -h;  // stay inside the bounds
  return h;
}

/// What the model reports, without the parameters that were fixed as not identifiable.
std::vector<Reported> reported_of(const ModelFamily& m, const Fit& f) {
  std::vector<Reported> out = m.report(f);
  out.erase(std::remove_if(out.begin(), out.end(),
                           [&](const Reported& r) {
                             return std::any_of(f.unidentifiable.begin(), f.unidentifiable.end(),
                                                [&](const Unidentifiable& u) { return u.name == r.name; });
                           }),
            out.end());
  return out;
}

/// The Jacobian of the unprojected weighted residual in (θ, φ) at (θ, φ): A(φ) and differences of
/// A(φ) θ, forward and backward. A design may be discontinuous in φ (a contact switches between
/// sticking and sliding at v_tm when a delay moves its slip speed across it): a one-sided
/// difference across a switch measures the jump over the step, not the slope, and gave a delay an
/// asymptotic std 300 times too small. When the two sides agree within 10 % their mean (central
/// difference) is taken, else the smaller: the side without the switch. Fixed parameters' columns are 0.
Eigen::MatrixXd full_jacobian(Evaluator& ev, const std::vector<Param>& nl, const Eigen::VectorXd& theta, const Eigen::VectorXd& phi,
                              const std::vector<bool>& fixed, bool keep = false) {
  const Eigen::MatrixXd& A = ev.weighted_design(phi, keep);  // overwritten by the next design: used here only
  const Eigen::Index p = A.cols(), q = phi.size();
  Eigen::MatrixXd J(A.rows(), p + q);
  J.leftCols(p) = A;
  const Eigen::VectorXd At = A * theta;
  for (Eigen::Index j = 0; j < q; ++j) {
    if (fixed[static_cast<std::size_t>(p + j)]) {
      J.col(p + j).setZero();
      continue;
    }
    const Param& par = nl[static_cast<std::size_t>(j)];
    const double h = fd_step(par, phi(j));
    Eigen::VectorXd ph = phi;
    ph(j) += h;
    const Eigen::VectorXd one = (ev.weighted_design(ph, keep) * theta - At) / h;
    J.col(p + j) = one;
    if (phi(j) - h < par.lower || phi(j) - h > par.upper) continue;  // no room on the other side
    ph(j) = phi(j) - h;
    const Eigen::VectorXd other = (At - ev.weighted_design(ph, keep) * theta) / h;
    const double a = one.norm(), b = other.norm();
    if ((one - other).norm() <= 0.1 * std::max(a, b)) J.col(p + j) = 0.5 * (one + other);
    else if (b < a) J.col(p + j) = other;
  }
  return J;
}

/// Component c of a weighted residual with 6 rows per sample (ns samples), less its mean.
Eigen::VectorXd centred_component(const Eigen::VectorXd& r, Eigen::Index ns, int c) {
  Eigen::VectorXd rc(ns);
  for (Eigen::Index a = 0; a < ns; ++a) rc(a) = r(6 * a + c);
  rc.array() -= rc.mean();
  return rc;
}

/// Two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom.
double t975(int dof) {
  static const double q[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                             2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086};
  if (dof < 1) return std::numeric_limits<double>::infinity();
  return dof <= 20 ? q[dof - 1] : 1.96 + 2.4 / dof;
}

/// (JᵀJ)⁺ by the SVD of J with unit-norm columns (never the normal equations), singular values
/// below 1e-9 of the largest dropped; `rank` counts those kept.
Eigen::MatrixXd normal_pinv(const Eigen::MatrixXd& J, int& rank) {
  Eigen::VectorXd cs = J.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < cs.size(); ++j)
    if (!(cs(j) > 0)) cs(j) = 1.0;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J * cs.cwiseInverse().asDiagonal(), Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double tol = 1e-9 * (sv.size() ? sv(0) : 0.0);
  rank = 0;
  Eigen::MatrixXd inv = Eigen::MatrixXd::Zero(J.cols(), J.cols());
  for (Eigen::Index i = 0; i < sv.size(); ++i)
    if (sv(i) > tol) {
      ++rank;
      inv += svd.matrixV().col(i) * svd.matrixV().col(i).transpose() / (sv(i) * sv(i));
    }
  return cs.cwiseInverse().asDiagonal() * inv * cs.cwiseInverse().asDiagonal();
}

/// Identifiability before (and after) estimation: the columns of J taken in order (nominal
/// parameters first, then the extension's), each kept when its unit-norm column lies farther than
/// `sine` from the span of those kept before it (Gram-Schmidt with reorthogonalisation: a
/// rank-revealing QR whose pivots follow the order). The others are fixed and listed with the kept
/// parameters they are collinear with (the largest coefficients of their projection). `bounded`:
/// parameters that ended at a bound, fixed and listed whatever their sine.
std::vector<Unidentifiable> unidentifiable_columns(const Eigen::MatrixXd& J, const std::vector<Param>& params, double sine,
                                                   const std::vector<bool>& bounded, std::vector<bool>& fixed) {
  const Eigen::Index n = J.cols();
  std::vector<Eigen::Index> order;
  for (int pass = 0; pass < 2; ++pass)
    for (Eigen::Index j = 0; j < n; ++j)
      if (params[static_cast<std::size_t>(j)].extension == (pass == 1)) order.push_back(j);
  Eigen::MatrixXd Q(J.rows(), 0);
  std::vector<Eigen::Index> kept;
  std::vector<Unidentifiable> out;
  auto partners = [&](const Eigen::VectorXd& c) {
    std::vector<std::string> names;
    if (kept.empty()) return names;
    Eigen::MatrixXd K(J.rows(), static_cast<Eigen::Index>(kept.size()));
    for (std::size_t i = 0; i < kept.size(); ++i) K.col(static_cast<Eigen::Index>(i)) = J.col(kept[i]).normalized();
    const Eigen::VectorXd b = K.colPivHouseholderQr().solve(c);
    std::vector<std::pair<double, std::string>> w;
    for (Eigen::Index i = 0; i < b.size(); ++i)
      if (std::abs(b(i)) > 0.1 * b.cwiseAbs().maxCoeff())
        w.emplace_back(-std::abs(b(i)), params[static_cast<std::size_t>(kept[static_cast<std::size_t>(i)])].name);
    std::sort(w.begin(), w.end());
    for (std::size_t i = 0; i < w.size() && i < 3; ++i) names.push_back(w[i].second);
    return names;
  };
  for (const Eigen::Index j : order) {
    if (fixed[static_cast<std::size_t>(j)]) continue;
    const double norm = J.col(j).norm();
    const auto& name = params[static_cast<std::size_t>(j)].name;
    if (!(norm > 0)) {
      fixed[static_cast<std::size_t>(j)] = true;
      out.push_back({name, "does not change the prediction on this run", {}});
      continue;
    }
    const Eigen::VectorXd c = J.col(j) / norm;
    Eigen::VectorXd r = c - Q * (Q.transpose() * c);
    r -= Q * (Q.transpose() * r);
    const bool at_bound = bounded.size() > static_cast<std::size_t>(j) && bounded[static_cast<std::size_t>(j)];
    if (r.norm() < sine || at_bound) {
      fixed[static_cast<std::size_t>(j)] = true;
      Unidentifiable u{name, "", partners(c)};
      const std::string with = u.collinear_with.empty() ? "" : fmt::format("collinear with {}", fmt::join(u.collinear_with, ", "));
      u.reason = at_bound ? fmt::format("ran to its bound{}", with.empty() ? "" : "; " + with) : with;
      out.push_back(std::move(u));
      continue;
    }
    Q.conservativeResize(Eigen::NoChange, Q.cols() + 1);
    Q.col(Q.cols() - 1) = r.normalized();
    kept.push_back(j);
  }
  return out;
}

/// The fit of `m` on `train` with designs from `cache`. `warm`: one more start (a second-step model
/// starts also from the cause's optimum, each of its folds from the cause's fit of that fold; the
/// start with the lowest training cost wins, so the estimate is still its own training data's
/// optimum). `statistics`: identifiability, covariance, rank, reported parameters and validity (a
/// fold's prediction needs none of them). `identify` (a fold's fit, without statistics): what its
/// own samples cannot separate at its best start is fixed, and so is what its fit runs to a bound
/// (then fitted again), as in the full fit, so that a fold decides its parameters from its training
/// samples alone; the full fit's collinearity check at the optimum, which needs another Jacobian,
/// is not repeated (a collinear direction does not change a prediction). `fixed`: parameters held
/// at their nominal value (0).
Fit fit_with(const ModelFamily& m, const Observations& obs, const std::vector<int>& train, const FitOptions& o, DesignCache& cache,
             const Eigen::VectorXd* warm, bool statistics, const std::vector<bool>* fixed_in = nullptr, bool identify = false,
             const std::vector<Eigen::VectorXd>* own_starts = nullptr) {
  if (train.empty()) throw std::runtime_error(m.name() + ": no samples to fit");
  const auto lin = m.linear();
  const auto nl = m.nonlinear();
  const Eigen::Index p = static_cast<Eigen::Index>(lin.size());
  const Eigen::Index q = static_cast<Eigen::Index>(nl.size());
  std::vector<Param> params = lin;
  params.insert(params.end(), nl.begin(), nl.end());
  Evaluator ev(cache, obs, train);
  Fit f;
  f.fixed.assign(static_cast<std::size_t>(p + q), false);
  if (fixed_in && fixed_in->size() == f.fixed.size()) f.fixed = *fixed_in;
  auto hold = [&](Eigen::VectorXd phi) {  // fixed φ at their nominal value
    for (Eigen::Index j = 0; j < q; ++j)
      if (f.fixed[static_cast<std::size_t>(p + j)]) phi(j) = 0.0;
    return phi;
  };
  ev.fixed_theta.assign(f.fixed.begin(), f.fixed.begin() + p);
  for (const auto& b : lin) {
    // A linear parameter takes one bound, θ >= 0: a fixed θ is 0, so a held one is fixed there.
    if (b.upper < 1e300 || (b.lower > -1e300 && b.lower != 0.0))
      throw std::logic_error(m.name() + ": the linear parameter " + b.name + " has a bound other than >= 0");
    ev.nonnegative_theta.push_back(b.lower == 0.0);
  }

  Eigen::VectorXd phi = Eigen::VectorXd::Zero(q);
  Projected cur;
  bool first = true;
  std::vector<Eigen::VectorXd> starts = own_starts ? *own_starts : m.starts();
  if (warm) {
    if (warm->size() != q)
      throw std::logic_error(m.name() + ": a warm start of " + std::to_string(warm->size()) + " values for " + std::to_string(q) +
                             " nonlinear parameters");
    starts.push_back(*warm);
  }
  for (const auto& s0 : starts) {
    const Eigen::VectorXd s = hold(clamp(s0, nl));
    Projected pr = ev.project(s, true);  // every fold evaluates the same starts
    if (first || pr.cost < cur.cost) {
      cur = pr;
      phi = s;
      first = false;
    }
  }
  // Near the best: kept too. The near starts depend on the best start only, and the folds of a
  // single candidate mostly share it, so the folds a worker runs reuse the full fit's designs.
  for (const auto& s0 : m.starts_near(phi)) {
    const Eigen::VectorXd s = hold(clamp(s0, nl));
    Projected pr = ev.project(s, true);
    if (pr.cost < cur.cost) {
      cur = pr;
      phi = s;
    }
  }
  if (!cur.theta.allFinite()) throw std::runtime_error(m.name() + ": the fit is not finite");
  if ((statistics || identify) && o.collinearity_sine > 0) {
    // Before estimation: directions the design cannot separate at the start are fixed, not fitted.
    // Its designs are kept: the folds that share the full fit's best start reuse them.
    auto u = unidentifiable_columns(full_jacobian(ev, nl, cur.theta, phi, f.fixed, true), params, o.collinearity_sine, {}, f.fixed);
    f.unidentifiable.insert(f.unidentifiable.end(), u.begin(), u.end());
    if (!u.empty()) {
      ev.fixed_theta.assign(f.fixed.begin(), f.fixed.begin() + p);
      phi = hold(phi);
      cur = ev.project(phi);
    }
  }

  // Levenberg-Marquardt on the projected residual in scaled units u = φ / scale. The Jacobian is
  // by forward differences (q designs); after an accepted step it is updated by Broyden's secant
  // formula instead (no design), up to o.secant_updates times in a row. A finite-difference Jacobian is
  // recomputed when a secant one gives no descent within a few trials, and always to confirm
  // convergence, so the fit stops on the same test as with finite differences throughout. The
  // contact models' residuals are piecewise smooth and their fits crawl along valleys in small
  // steps, where the Jacobian hardly changes: most iterations then cost one or two designs, not q + 1.
  auto levenberg_marquardt = [&]() {
    if (q == 0) return;
    solver::Problem pb;
    pb.scale.resize(q);
    pb.lower.resize(q);
    pb.upper.resize(q);
    for (Eigen::Index j = 0; j < q; ++j) {
      const auto& b = nl[static_cast<std::size_t>(j)];
      pb.scale(j) = b.scale;
      pb.lower(j) = b.lower;
      pb.upper(j) = b.upper;
    }
    pb.fixed.assign(f.fixed.begin() + p, f.fixed.end());
    Projected trial;
    pb.residual = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
      trial = ev.project(x);
      r = trial.r;
      return trial.cost;
    };
    pb.accepted = [&] { cur = std::move(trial); };
    pb.jacobian = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& r, Eigen::MatrixXd& J) {
      J.resize(r.size(), q);
      for (Eigen::Index j = 0; j < q; ++j) {
        if (f.fixed[static_cast<std::size_t>(p + j)]) {
          J.col(j).setZero();
          continue;
        }
        Eigen::VectorXd ph = x;
        const double h = fd_step(nl[static_cast<std::size_t>(j)], x(j));
        ph(j) += h;
        J.col(j) = (ev.project(ph).r - r) / (h / pb.scale(j));
      }
    };
    solver::Options so;
    so.max_iterations = o.max_iterations;
    so.damping = solver::Damping::fixed_factors;
    so.max_trials = 12;
    so.max_trials_secant = 3;
    so.secant_updates = o.secant_updates;
    const double dof = static_cast<double>(std::max<Eigen::Index>(1, cur.r.size() - p - q));
    so.relative_decrease = std::max(o.tolerance, o.noise_tolerance / dof);
    so.step_absolute = 1e-8;
    const auto sr = solver::levenberg_marquardt(pb, phi, so, cur.cost, &cur.r);
    phi = sr.x;
    f.converged = sr.converged;
  };
  levenberg_marquardt();

  auto finish = [&]() {
    f.theta = cur.theta;
    f.phi = phi;
    f.phi_names.clear();
    for (const auto& q0 : nl) f.phi_names.push_back(q0.name);
    f.parameters = static_cast<int>(p + q);
    f.rows = static_cast<long>(cur.r.size());
    f.rss = cur.cost;
  };
  finish();
  // The parameters that ended at a bound (a bound is no estimate): nonlinear ones within a
  // millionth of their range, linear ones held at 0 by the projection.
  auto at_bounds = [&]() {
    std::vector<bool> bounded(static_cast<std::size_t>(p + q), false);
    for (std::size_t j = 0; j < cur.held.size() && j < static_cast<std::size_t>(p); ++j) bounded[j] = cur.held[j];
    for (Eigen::Index j = 0; j < q; ++j) {
      const auto& b = nl[static_cast<std::size_t>(j)];
      const double tol = 1e-6 * std::max(b.scale, std::min(b.upper - b.lower, 1e300));
      bounded[static_cast<std::size_t>(p + j)] = phi(j) <= b.lower + tol || phi(j) >= b.upper - tol;
    }
    return bounded;
  };
  if (!statistics) {
    if (identify && o.collinearity_sine > 0) {
      const std::vector<bool> bounded = at_bounds();
      bool any = false;
      for (std::size_t j = 0; j < bounded.size(); ++j)
        if (bounded[j] && !f.fixed[j]) {
          f.fixed[j] = true;
          f.unidentifiable.push_back({params[j].name, "ran to its bound", {}});
          any = true;
        }
      if (any) {
        phi = hold(phi);
        cur = ev.project(phi);
        levenberg_marquardt();
        finish();
      }
    }
    f.evaluations = ev.evaluations;
    return f;
  }

  // Statistics from the Jacobian of the unprojected residual in (θ, φ) at the optimum. First the
  // identifiability at the optimum: a direction that became inseparable there, or a nonlinear
  // parameter that ran to a bound (a bound is no estimate), is fixed and the fit repeated once.
  Eigen::MatrixXd J = full_jacobian(ev, nl, cur.theta, phi, f.fixed);
  if (o.collinearity_sine > 0) {
    auto u = unidentifiable_columns(J, params, o.collinearity_sine, at_bounds(), f.fixed);
    if (!u.empty()) {
      f.unidentifiable.insert(f.unidentifiable.end(), u.begin(), u.end());
      ev.fixed_theta.assign(f.fixed.begin(), f.fixed.begin() + p);
      phi = hold(phi);
      cur = ev.project(phi);
      levenberg_marquardt();
      finish();
      J = full_jacobian(ev, nl, cur.theta, phi, f.fixed);
    }
  }
  const Eigen::MatrixXd inv = normal_pinv(J, f.rank);
  f.sigma2 = f.rows > f.rank ? f.rss / static_cast<double>(f.rows - f.rank) : 0.0;
  f.cov = f.sigma2 * inv;
  // Residuals of neighbouring samples are correlated (unmodelled structure, filtering): inflate the
  // covariance by the long-run variance factor 1 + 2 Σ w_l ρ_l (Bartlett weights, per component,
  // averaged by residual variance) so that intervals do not claim the precision of white noise.
  {
    const Eigen::Index ns = static_cast<Eigen::Index>(train.size());
    const int L = static_cast<int>(std::min<Eigen::Index>(20, ns / 4));
    double num = 0.0, den = 0.0;
    for (int c = 0; c < 6; ++c) {
      const Eigen::VectorXd rc = centred_component(cur.r, ns, c);
      const double v0 = rc.squaredNorm();
      if (!(v0 > 0)) continue;
      double factor = 1.0;
      for (int l = 1; l <= L; ++l) factor += 2.0 * (1.0 - l / (L + 1.0)) * rc.head(ns - l).dot(rc.tail(ns - l)) / v0;
      num += v0 * std::max(1.0, factor);
      den += v0;
    }
    f.variance_inflation = den > 0 ? num / den : 1.0;
    f.cov *= f.variance_inflation;
  }
  // The block-clustered sandwich (JᵀJ)⁺ Σ_b g_b g_bᵀ (JᵀJ)⁺ G/(G-1), g_b = J_bᵀ r_b over G
  // consecutive blocks, widened by t_{0.975, G-1} / 1.96: no pooled σ² over components of unequal
  // noise, no single block carrying the estimate. The blocks are twice Andrews' (1991) AR(1)
  // plug-in Bartlett bandwidth long (5 to 40 of them), from the residuals' lag-1 correlation.
  {
    const Eigen::Index ns = static_cast<Eigen::Index>(train.size()), P = J.cols();
    double num = 0.0, den = 0.0;
    for (int c = 0; c < 6; ++c) {
      const Eigen::VectorXd rc = centred_component(cur.r, ns, c);
      const double v0 = rc.squaredNorm();
      if (!(v0 > 0) || ns < 3) continue;
      num += rc.head(ns - 1).dot(rc.tail(ns - 1));
      den += v0;
    }
    const double rho = den > 0 ? std::clamp(num / den, -0.97, 0.97) : 0.0;
    const double alpha = 4 * rho * rho / ((1 - rho) * (1 - rho) * (1 + rho) * (1 + rho));
    const double bandwidth = 1.1447 * std::cbrt(alpha * static_cast<double>(ns));
    const int G = static_cast<int>(std::clamp(std::floor(static_cast<double>(ns) / std::max(1.0, 2 * bandwidth)), 5.0, 40.0));
    // CR2 (Bell and McCaffrey 2002): each block's residual taken as (I − H_bb)^{-1/2} r_b, H_bb =
    // J_b (JᵀJ)⁺ J_bᵀ its leverage. A block that holds most of what the run says of a direction
    // fits its own residual there, and its raw residual then understates the error: the plain
    // sandwich read slow_slip's μ_s K, informed by a few stops, 40 times narrower than the
    // asymptotic std (family draw 36,621,358). In P dimensions, with inv^{1/2} S_b inv^{1/2} = V Λ Vᵀ
    // and S_b = J_bᵀ J_b: J_bᵀ f(H_bb) J_b = f(0) S_b + S_b inv^{1/2} V diag((f(λ) − f(0)) / λ) Vᵀ
    // inv^{1/2} S_b, and J_bᵀ f(H_bb) r_b likewise with g_b = J_bᵀ r_b. A block that alone
    // determines a direction (λ = 1) leaves nothing to measure its error with: no sandwich then.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> inv_es(inv);
    const Eigen::MatrixXd root = inv_es.eigenvectors() * inv_es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                                 inv_es.eigenvectors().transpose();
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(P, P);
    std::vector<Eigen::MatrixXd> T, Q;  // per block J_bᵀ (I − H_bb)^{-1/2} J_b and J_bᵀ (I − H_bb)^{-1} J_b
    bool alone = false;
    for (int b = 0; b < G && !alone; ++b) {
      const Eigen::Index a0 = ns * b / G, a1 = ns * (b + 1) / G;
      if (a1 <= a0) continue;
      const auto Jb = J.middleRows(6 * a0, 6 * (a1 - a0));
      const Eigen::VectorXd g = Jb.transpose() * cur.r.segment(6 * a0, 6 * (a1 - a0));
      const Eigen::MatrixXd S = Jb.transpose() * Jb;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(root * S * root);
      Eigen::VectorXd half(P), full(P);  // (f(λ) − 1) / λ for f = (1 − λ)^{-1/2} and (1 − λ)^{-1}
      for (Eigen::Index i = 0; i < P; ++i) {
        const double l = std::max(0.0, es.eigenvalues()(i));
        if (l > 1.0 - 1e-9) alone = true;
        const double rest = std::max(1.0 - l, 1e-9);
        half(i) = l < 1e-8 ? 0.5 : (1.0 / std::sqrt(rest) - 1.0) / l;
        full(i) = 1.0 / rest;
      }
      const Eigen::MatrixXd SR = S * root * es.eigenvectors();
      const Eigen::MatrixXd RV = es.eigenvectors().transpose() * root;
      const Eigen::VectorXd adjusted = g + SR * half.asDiagonal() * RV * g;
      M += adjusted * adjusted.transpose();
      T.push_back(S + SR * half.asDiagonal() * SR.transpose());
      Q.push_back(S + SR * full.asDiagonal() * SR.transpose());
    }
    const int used = static_cast<int>(T.size());
    if (used > 1 && !alone) {
      // Per parameter j, Bell and McCaffrey's degrees of freedom (sandwich_dof_along): two blocks
      // that hold a parameter's information give it ~1, and t_{0.975} widens it accordingly.
      f.normal_inverse = inv;
      f.sandwich_half = std::move(T);
      f.sandwich_full = std::move(Q);
      Eigen::VectorXd widen = Eigen::VectorXd::Ones(P);
      f.sandwich_dof = Eigen::VectorXd::Zero(P);
      for (Eigen::Index j = 0; j < P; ++j) {
        const double nu = sandwich_dof_along(f, Eigen::VectorXd::Unit(P, j));
        if (!(nu > 0)) continue;
        f.sandwich_dof(j) = nu;
        widen(j) = boost::math::quantile(boost::math::students_t_distribution<double>(std::max(1.0, nu)), 0.975) / 1.96;
      }
      f.cov_sandwich = widen.asDiagonal() * inv * M * inv * widen.asDiagonal();
      f.sandwich_blocks = used;
      f.jacobian = J;
      f.residual = cur.r;
    }
  }
  f.evaluations = ev.evaluations;
  f.reported = reported_of(m, f);
  f.invalid = m.check(f);
  return f;
}

Eigen::MatrixXd predict_with(const Eigen::MatrixXd& A, const Fit& f, std::size_t samples) {
  const Eigen::VectorXd y = A * f.theta;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(samples), 6);
  for (Eigen::Index k = 0; k < out.rows(); ++k)
    for (int c = 0; c < 6; ++c) out(k, c) = y(6 * k + c);
  return out;
}

/// The prediction of every sample by the fit `f` of `m` with the parameters named in `off` at
/// their nominal value 0, the nominal model's free linear parameters re-solved on `train` (solve_ls) and
/// the rest kept as fitted: what the fit predicts without that part of its model.
Eigen::MatrixXd prediction_without(const ModelFamily& m, const Fit& f, const Observations& obs, const std::vector<int>& train,
                                   const std::set<std::string>& off, DesignCache& cache) {
  const auto lin = m.linear();
  const auto nl = m.nonlinear();
  Eigen::VectorXd phi = f.phi;
  for (std::size_t j = 0; j < nl.size() && static_cast<Eigen::Index>(j) < phi.size(); ++j)
    if (off.count(nl[j].name)) phi(static_cast<Eigen::Index>(j)) = 0.0;
  const Eigen::MatrixXd A = cache.get(phi);  // a copy: the cache may drop it
  Eigen::VectorXd theta = f.theta;
  std::vector<Eigen::Index> resolve;
  for (std::size_t j = 0; j < lin.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    if (off.count(lin[j].name)) theta(i) = 0.0;
    else if (!lin[j].extension && !f.is_fixed(i)) resolve.push_back(i);
  }
  if (!resolve.empty()) {
    for (const auto i : resolve) theta(i) = 0.0;
    const Eigen::Matrix<double, 6, 1> w = obs.weight;
    Eigen::MatrixXd An(static_cast<Eigen::Index>(6 * train.size()), static_cast<Eigen::Index>(resolve.size()));
    Eigen::VectorXd rhs(An.rows());
    const Eigen::VectorXd rest = A * theta;
    for (std::size_t a = 0; a < train.size(); ++a)
      for (int c = 0; c < 6; ++c) {
        const Eigen::Index row = 6 * train[a] + c, out = static_cast<Eigen::Index>(6 * a) + c;
        for (std::size_t j = 0; j < resolve.size(); ++j) An(out, static_cast<Eigen::Index>(j)) = w(c) * A(row, resolve[j]);
        rhs(out) = w(c) * (obs.y(train[a], c) - rest(row));
      }
    const Eigen::VectorXd x = solve_ls(An, rhs);
    for (std::size_t j = 0; j < resolve.size(); ++j) theta(resolve[j]) = x(static_cast<Eigen::Index>(j));
  }
  Fit without = f;
  without.theta = theta;
  return predict_with(A, without, obs.size());
}

}  // namespace

double sandwich_dof_along(const Fit& f, const Eigen::VectorXd& gradient) {
  const Eigen::MatrixXd& inv = f.normal_inverse;
  const std::size_t used = f.sandwich_half.size();
  if (used < 2 || inv.rows() != gradient.size()) return 0.0;
  const Eigen::VectorXd mj = inv * gradient;
  if (!(mj.squaredNorm() > 0)) return 0.0;
  Eigen::MatrixXd W(inv.rows(), static_cast<Eigen::Index>(used));
  Eigen::VectorXd d(static_cast<Eigen::Index>(used));
  for (std::size_t b = 0; b < used; ++b) {
    W.col(static_cast<Eigen::Index>(b)) = f.sandwich_half[b] * mj;
    d(static_cast<Eigen::Index>(b)) = mj.dot(f.sandwich_full[b] * mj);
  }
  Eigen::MatrixXd K = -W.transpose() * inv * W;
  K.diagonal() += d;
  return K.squaredNorm() > 0 ? K.trace() * K.trace() / K.squaredNorm() : 0.0;
}

Fit fit(const ModelFamily& m, const Observations& obs, const std::vector<int>& train, const FitOptions& o) {
  DesignCache cache(m, obs.size());
  return fit_with(m, obs, train, o, cache, nullptr, true);
}

Eigen::MatrixXd predict(const ModelFamily& m, const Fit& f, std::size_t samples) {
  Eigen::MatrixXd A;
  m.design(f.phi, A);
  return predict_with(A, f, samples);
}

ErrorsInVariablesBias errors_in_variables_bias(const ModelFamily& m, const Observations& obs, const Fit& f, const std::vector<int>& train,
                                               int threads) {
  const Eigen::Index p = f.theta.size(), q = f.phi.size();
  ErrorsInVariablesBias out;
  out.bias = Eigen::VectorXd::Zero(p + q);
  const auto vars = m.errors_in_variables();
  if (vars.empty() || train.empty()) return out;
  const auto lin = m.linear();
  const auto nl = m.nonlinear();
  const auto same_parameters = [&](const ModelFamily& o) {
    const auto a = o.linear(), b = o.nonlinear();
    if (a.size() != lin.size() || b.size() != nl.size()) return false;
    for (std::size_t j = 0; j < a.size(); ++j)
      if (a[j].name != lin[j].name) return false;
    for (std::size_t j = 0; j < b.size(); ++j)
      if (b[j].name != nl[j].name) return false;
    return true;
  };
  std::vector<bool> fixed = f.fixed;
  fixed.resize(static_cast<std::size_t>(p + q), false);
  // G = Jᵀ r of the fitted family (task 0) and of each variable shifted by ±σ and ±2σ.
  constexpr double kShift[] = {1.0, -1.0, 2.0, -2.0};
  const std::size_t tasks = 1 + 4 * vars.size();
  std::vector<Eigen::VectorXd> g(tasks);
  std::vector<std::string> differ(tasks);
  Eigen::MatrixXd J0;
  parallel::run_tasks(tasks, parallel::worker_count(tasks, threads), [&](std::size_t i, std::size_t) {
    std::unique_ptr<ModelFamily> own;
    if (i > 0) {
      const auto& v = vars[(i - 1) / 4];
      own = v.shifted ? v.shifted(kShift[(i - 1) % 4] * v.std) : nullptr;
      if (!own || !same_parameters(*own)) {
        differ[i] = v.variable;
        return;
      }
    }
    const ModelFamily& fam = own ? *own : m;
    DesignCache cache(fam, obs.size());
    Evaluator ev(cache, obs, train);
    ev.fixed_theta.assign(fixed.begin(), fixed.begin() + p);
    Eigen::MatrixXd J = full_jacobian(ev, nl, f.theta, f.phi, fixed);
    const Eigen::VectorXd r = ev.b() - J.leftCols(p) * f.theta;
    g[i] = J.transpose() * r;
    if (i == 0) J0 = std::move(J);
  });
  for (const auto& d : differ)
    if (!d.empty()) {
      out.why_not = "shifting " + d + " changes the family's parameters";
      return out;
    }
  // ½ Σ_v σ_v² ∂²G/∂x_v² from the ±σ differences, and again from the ±2σ ones over 4.
  Eigen::VectorXd c1 = Eigen::VectorXd::Zero(p + q), c2 = c1;
  for (std::size_t v = 0; v < vars.size(); ++v) {
    c1 += 0.5 * (g[1 + 4 * v] + g[2 + 4 * v] - 2.0 * g[0]);
    c2 += 0.125 * (g[3 + 4 * v] + g[4 + 4 * v] - 2.0 * g[0]);
  }
  int rank = 0;
  const Eigen::MatrixXd P = normal_pinv(J0, rank);
  Eigen::VectorXd b1 = P * c1, b2 = P * c2;
  for (Eigen::Index j = 0; j < p + q; ++j)
    if (fixed[static_cast<std::size_t>(j)]) b1(j) = b2(j) = 0.0;
  // The expansion holds where the score is smooth at the errors' scale: then the curvature over
  // ±2σ is the one over ±σ. Compared by what each moves the fit's prediction (the weighted rows).
  const double size = (J0 * b1).norm();
  out.mismatch = size > 0 ? (J0 * (b2 - b1)).norm() / size : 0.0;
  if (!b1.allFinite() || !(out.mismatch <= kErrorsInVariablesMismatch)) {
    out.why_not =
        fmt::format("the score is not smooth at the errors' scale (the bias over 2 std differs from the one over 1 std by {:.2g} of it)",
                    out.mismatch);
    return out;
  }
  out.bias = b1;
  out.applied = true;
  return out;
}

double relative_error(const Observations& obs, const Eigen::MatrixXd& prediction, const std::vector<int>& samples) {
  double s = 0.0;
  for (int k : samples)
    for (int c = 0; c < 6; ++c) {
      const double r = obs.weight(c) * (obs.y(k, c) - prediction(k, c));
      s += r * r;
    }
  return samples.empty() ? 0.0 : std::sqrt(s / (6.0 * static_cast<double>(samples.size())));
}

std::vector<std::vector<int>> time_blocks(std::size_t samples, int folds) {
  folds = std::max(1, std::min<int>(folds, static_cast<int>(samples)));
  std::vector<std::vector<int>> out(static_cast<std::size_t>(folds));
  for (std::size_t k = 0; k < samples; ++k)
    out[std::min<std::size_t>(k * static_cast<std::size_t>(folds) / samples, static_cast<std::size_t>(folds) - 1)]
        .push_back(static_cast<int>(k));
  return out;
}

std::vector<std::vector<int>> time_blocks(std::size_t samples, int folds, double offset) {
  if (!(offset >= 0.0 && offset < 1.0))
    throw std::invalid_argument("time_blocks: the grid offset " + std::to_string(offset) + " is outside [0, 1) of a block");
  if (offset == 0.0) return time_blocks(samples, folds);
  folds = std::max(1, std::min<int>(folds, static_cast<int>(samples)));
  std::vector<std::vector<int>> out(static_cast<std::size_t>(folds));
  for (std::size_t k = 0; k < samples; ++k) {
    const double x = static_cast<double>(k) * folds / static_cast<double>(samples) + offset;
    out[static_cast<std::size_t>(std::floor(x)) % static_cast<std::size_t>(folds)].push_back(static_cast<int>(k));
  }
  return out;
}

namespace {

/// The φ of `from` (named `names`) mapped onto the nonlinear parameters `nl`, the others at 0.
Eigen::VectorXd mapped(const std::vector<Param>& nl, const std::vector<std::string>& names, const Eigen::VectorXd& from) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nl.size()));
  for (std::size_t j = 0; j < nl.size(); ++j)
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == nl[j].name) out(static_cast<Eigen::Index>(j)) = from(static_cast<Eigen::Index>(i));
  return out;
}

/// `fixed` (over `from`'s linear then nonlinear parameters) carried over by name to `to`'s parameters.
std::vector<bool> fixed_by_name(const ModelFamily& from, const std::vector<bool>& fixed, const ModelFamily& to) {
  std::vector<Param> a = from.linear(), b = to.linear();
  const auto an = from.nonlinear(), bn = to.nonlinear();
  a.insert(a.end(), an.begin(), an.end());
  b.insert(b.end(), bn.begin(), bn.end());
  std::vector<bool> out(b.size(), false);
  for (std::size_t j = 0; j < b.size(); ++j)
    for (std::size_t i = 0; i < a.size() && i < fixed.size(); ++i)
      if (a[i].name == b[j].name) out[j] = fixed[i];
  return out;
}

void extension_pnr(Score& s) {
  s.min_extension_pnr = std::numeric_limits<double>::infinity();
  s.max_extension_pnr = 0.0;
  bool any = false;
  for (const auto& r : s.full.reported)
    if (r.extension) {
      any = true;
      s.min_extension_pnr = std::min(s.min_extension_pnr, r.pnr());
      s.max_extension_pnr = std::max(s.max_extension_pnr, r.pnr());
    }
  if (!any) s.min_extension_pnr = 0.0;
  s.identifiable = s.max_extension_pnr >= 5.0;
}

std::vector<Reported> values_reported(const ModelFamily& m, Fit f, const Fit& full);

/// Each value `m` reports of `full`, with its sandwich degrees of freedom along its gradient in
/// (θ, φ) (sandwich_dof_along): central differences of the reported values at a thousandth of each
/// parameter's std. Empty where the fit kept no sandwich.
std::map<std::string, double> reported_dof(const ModelFamily& m, const Fit& full) {
  std::map<std::string, double> out;
  const Eigen::Index p = full.theta.size(), P = p + full.phi.size();
  if (full.sandwich_half.size() < 2 || full.normal_inverse.rows() != P || full.cov.rows() != P) return out;
  Fit light = full;  // without the per-sample matrices, which every report would copy
  light.jacobian.resize(0, 0);
  light.residual.resize(0);
  light.sandwich_half.clear();
  light.sandwich_full.clear();
  light.normal_inverse.resize(0, 0);
  light.cov_sandwich.resize(0, 0);
  std::map<std::string, Eigen::VectorXd> gradient;
  for (const auto& r : values_reported(m, light, full)) gradient[r.name] = Eigen::VectorXd::Zero(P);
  for (Eigen::Index j = 0; j < P; ++j) {
    const double h = 1e-3 * std::sqrt(std::max(0.0, full.cov(j, j)));
    if (!(h > 0) || full.is_fixed(j)) continue;
    Fit up = light, down = light;
    (j < p ? up.theta(j) : up.phi(j - p)) += h;
    (j < p ? down.theta(j) : down.phi(j - p)) -= h;
    std::map<std::string, double> above;
    for (const auto& r : values_reported(m, up, full)) above[r.name] = r.value;
    for (const auto& r : values_reported(m, down, full)) {
      const auto a = above.find(r.name);
      const auto g = gradient.find(r.name);
      if (a != above.end() && g != gradient.end() && std::isfinite(a->second - r.value)) g->second(j) = (a->second - r.value) / (2 * h);
    }
  }
  for (const auto& [name, g] : gradient) out[name] = sandwich_dof_along(full, g);
  return out;
}

/// Whether every fold's estimate x_i of a value lies where the model says removing the fold's block
/// can move it: |x_i - x| <= kOneEventFoldZ sqrt(s_i² - s²), x and s the full fit's value and
/// asymptotic std, s_i the fold's asymptotic std at the full optimum. Under the model the full fit
/// is the efficient one, so x_i - x has the variance s_i² - s² (Hausman 1978). A fold without the
/// event that carries the value knows it poorly (s_i ≫ s) and may wander far; a fold that keeps the
/// event must stay close. Issue 32: on a trapezoidal delay draw whose slow slip carried τ (ν 1.15),
/// the full fit read τ 0.31 ms early with a model std of 0.066 ms (z -4.7), the folds 0.38 ms apart.
/// Its cost: slow_slip's μ_s on clean runs with stops, where one stop reads it higher than the
/// others by more than the model's noise, is then reported with the folds' spread (docs/diagnosis.md).
bool one_event_agrees(double x, double s, const std::vector<double>& folds, const std::vector<double>& fold_std) {
  for (std::size_t i = 0; i < folds.size(); ++i) {
    // Only a fold that lost a fifth of the value's information or more: where s_i ~ s the allowed
    // spread is below the fits' convergence (draw 36,631,517: μ_s K's folds 1-4 within 10 N/m of
    // the full fit's 60,547 ± 740, a ratio of 2.8 on fold 1 for an allowed 3.6 N/m). A fold whose
    // pseudo-inverse dropped the value's direction (s_i below s) cannot know it and is skipped too.
    if (fold_std[i] * fold_std[i] < 1.25 * s * s) continue;
    const double spread = std::sqrt(std::max(0.0, fold_std[i] * fold_std[i] - s * s));
    if (!(std::abs(folds[i] - x) <= kOneEventFoldZ * spread)) return false;
  }
  return true;
}

/// What the full fit's rows `rows` alone say of the reported values: each value one linear step
/// from the full optimum, A⁺ J_rowsᵀ r_rows (a fold's estimate as the full fit's linearisation
/// predicts it, or a group of components' reading), with its asymptotic std at the full optimum
/// from those rows, the full fit's σ² and long-run inflation: what the model says they know.
/// `light`: the full fit without its per-sample matrices (what is copied).
std::vector<Reported> rows_reading(const ModelFamily& m, const Fit& full, const Fit& light, const std::vector<Eigen::Index>& rows) {
  const Eigen::MatrixXd& J = full.jacobian;
  Eigen::MatrixXd Jr(static_cast<Eigen::Index>(rows.size()), J.cols());
  Eigen::VectorXd rr(Jr.rows());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Jr.row(static_cast<Eigen::Index>(i)) = J.row(rows[i]);
    rr(static_cast<Eigen::Index>(i)) = full.residual(rows[i]);
  }
  int rank = 0;
  const Eigen::MatrixXd inverse = normal_pinv(Jr, rank);
  const Eigen::VectorXd d = inverse * (Jr.transpose() * rr);
  Fit at = light;
  at.theta += d.head(at.theta.size());
  at.phi += d.tail(at.phi.size());
  std::vector<Reported> out = values_reported(m, at, full);
  at.theta = full.theta;
  at.phi = full.phi;
  at.cov = full.sigma2 * full.variance_inflation * inverse;
  std::map<std::string, double> sd;
  for (const auto& r : reported_of(m, at)) sd[r.name] = r.std;
  for (auto& r : out) {
    const auto it = sd.find(r.name);
    r.std = it != sd.end() ? it->second : std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

/// Each component group's reading of the reported values, one linear step from the full optimum on
/// the group's rows alone, and its asymptotic std there (ModelFamily::component_groups): per value
/// name, one entry per group.
struct GroupReadings {
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> value, std;
};

/// Sets r.std_components and r.components_disagree from the group whose reading contradicts r the
/// most (one_event_agrees' bound), if any: the std whose ±1.96 reaches across its 95 % interval.
void disagreeing_group(Reported& r, const GroupReadings& groups) {
  const auto v = groups.value.find(r.name);
  const auto sd = groups.std.find(r.name);
  if (v == groups.value.end() || sd == groups.std.end()) return;
  for (std::size_t g = 0; g < v->second.size() && g < sd->second.size() && g < groups.names.size(); ++g) {
    if (one_event_agrees(r.value, r.std, {v->second[g]}, {sd->second[g]})) continue;
    const double reach = std::abs(v->second[g] - r.value) / 1.96 + sd->second[g];
    if (!(reach > r.std_components)) continue;
    r.std_components = reach;
    r.components_disagree = fmt::format("{} alone read {:.5g} ± {:.2g}", groups.names[g], v->second[g], 1.96 * sd->second[g]);
  }
}

/// Intervals that hold when the model is not exactly right or the residuals are not white: the
/// spread of the folds' estimates (delete-a-block jackknife, g blocks: var = (g-1)/g Σ (x_i - x̄)²)
/// measures what the asymptotic formula assumes away (misfit, autocorrelation beyond its lags,
/// a multimodal cost). With g - 1 degrees of freedom its ±1.96 std would cover too rarely, so it
/// is scaled by t_{0.975, g-1} / 1.96. The reported std is the larger of the two, except where the
/// block-clustered sandwich can stand alone: the residuals' correlation short (at least
/// kSandwichMinBlocks blocks) and every fold's estimate within one sandwich std of its linear
/// prediction from the full fit (`linear`), i.e. no fold found another minimum or a nonlinearity
/// the sandwich cannot see. Then the folds' spread is the leverage of unequally informative blocks,
/// which the sandwich weighs properly, and the sandwich is the std. A value carried by one event
/// (Reported::model_based) keeps the asymptotic std where the folds and the component groups agree
/// with it (one_event_agrees); a group that disagrees widens it to reach across that group's
/// interval (Reported::std_components). The PNR keeps the asymptotic std (Reported::pnr).
void honest_intervals(Score& s, const ModelFamily& m, const std::map<std::string, std::vector<double>>& by_name,
                      const std::map<std::string, std::vector<double>>& linear, const std::map<std::string, std::vector<double>>& fold_std,
                      std::size_t folds, const GroupReadings& groups) {
  if (folds < 3) return;
  std::map<std::string, double> sandwich_std;
  if (s.full.cov_sandwich.size() > 0) {
    Fit f = s.full;
    f.cov = s.full.cov_sandwich;
    for (const auto& r : reported_of(m, f)) sandwich_std[r.name] = r.std;
  }
  const std::map<std::string, double> dof = reported_dof(m, s.full);
  const double g = static_cast<double>(folds);
  const double widen = t975(static_cast<int>(folds) - 1) / 1.96;
  for (auto& r : s.full.reported) {
    const auto nu = dof.find(r.name);
    if (nu != dof.end()) r.sandwich_dof = nu->second;
    const auto it = by_name.find(r.name);
    if (!r.fold_comparable || it == by_name.end() || it->second.size() != folds) continue;
    const Eigen::Map<const Eigen::VectorXd> v(it->second.data(), static_cast<Eigen::Index>(folds));
    if (!v.allFinite()) continue;
    const double var = (g - 1.0) / g * (v.array() - v.mean()).square().sum();
    r.std_folds = widen * std::sqrt(var);
    r.std_asymptotic = r.std;
    const auto sw = sandwich_std.find(r.name);
    // One event's worth: the sandwich and the folds' spread have no degrees of freedom to measure
    // this value's error with (t at ν ~ 1 widens 6.5 times; a fold without the event barely sees
    // it), so the model's std stands, said as such. Only where the residuals' correlation is short
    // (as many blocks as the sandwich needs to stand alone), so that the long-run inflation holds
    // what correlation there is: with a few long blocks every value has a small ν, and there the
    // folds' spread is the measure (Engine.IntervalsCoverTheTruthUnderStronglyCorrelatedErrors...).
    // The model's std stands only where the folds agree with it (one_event_agrees): a fold whose
    // estimate lies beyond what the model says removing its block can move it saw the value
    // elsewhere in the run, and then the folds' spread measures its error.
    const bool one_event = s.full.sandwich_blocks >= kSandwichMinBlocks && r.sandwich_dof > 0 && r.sandwich_dof < kOneEventDof;
    // And the component groups: the folds cut the run in time, and a misfit at the one event that
    // carries the value moves every fold that keeps it alike. Under the model each group's rows
    // read the value too; one that reads it beyond its Hausman spread says the model is wrong where
    // the other looks (issue 32: a delay carried by one stop's friction torque, mz, while fz, mx
    // and my read it 0.27 ms earlier, near the truth).
    if (one_event) disagreeing_group(r, groups);
    const auto fs = fold_std.find(r.name);
    if (one_event && r.std_components == 0.0 && fs != fold_std.end() && fs->second.size() == folds &&
        one_event_agrees(r.value, r.std, it->second, fs->second)) {
      if (sw != sandwich_std.end()) r.std_sandwich = sw->second;
      r.model_based = true;
      continue;
    }
    r.std = std::max(r.std, r.std_folds);
    const auto lin = linear.find(r.name);
    if (sw != sandwich_std.end() && sw->second > 0 && lin != linear.end() && lin->second.size() == folds) {
      r.std_sandwich = sw->second;
      double worst = 0.0;
      for (std::size_t i = 0; i < folds; ++i) worst = std::max(worst, std::abs(it->second[i] - lin->second[i]));
      if (s.full.sandwich_blocks >= kSandwichMinBlocks && worst <= sw->second) {
        r.std = sw->second;
        r.sandwich = true;
      }
    }
    if (r.std_components > r.std) {
      r.std = r.std_components;
      r.sandwich = false;
    }
  }
}

/// The values `m` reports for a fit made without statistics (a fold's, a model form's): its
/// covariance zero, its unidentifiable directions the full fit's. Only the values are meaningful.
std::vector<Reported> values_reported(const ModelFamily& m, Fit f, const Fit& full) {
  f.cov = Eigen::MatrixXd::Zero(f.theta.size() + f.phi.size(), f.theta.size() + f.phi.size());
  f.unidentifiable = full.unidentifiable;
  return reported_of(m, f);
}

/// Intervals that hold whichever of the family's alternative model forms is right, within the range
/// they bound (e.g. the friction acting anywhere between the interference's deepest point and its
/// surface): the full fit is repeated under each, from the full fit's optimum with the same
/// parameters fixed, and each reported value's largest shift d widens its interval as an
/// uncertainty uniform over ± d (std d / √3, added in quadrature). The PNR keeps the asymptotic std:
/// the alternatives move the estimate, they do not make the run less informative.
/// The full model refitted under one alternative model form (ModelFamily::model_forms), warm-started
/// from the full fit: what model_form_intervals measures the shifts on.
Fit model_form_fit(const ModelFamily::ModelForm& form, const ModelFamily& m, const Score& s, const Observations& obs,
                   const std::vector<int>& all, const FitOptions& o) {
  DesignCache cache(*form.model, obs.size());
  const Eigen::VectorXd warm = mapped(form.model->nonlinear(), s.full.phi_names, s.full.phi);
  const std::vector<bool> fixed = fixed_by_name(m, s.full.fixed, *form.model);
  if (!form.refit_from) return fit_with(*form.model, obs, all, o, cache, &warm, false, &fixed);
  const std::vector<Eigen::VectorXd> starts = form.refit_from(warm);
  return fit_with(*form.model, obs, all, o, cache, &warm, false, &fixed, false, &starts);
}

/// Widens the full fit's intervals by the largest shift of each value under the model forms; a
/// form the run decides against widens nothing.
void model_form_intervals(Score& s, const std::vector<ModelFamily::ModelForm>& forms, const std::vector<Fit>& fits) {
  if (forms.empty()) return;
  std::map<std::string, double> shift;
  const double variance = s.full.sigma2 * s.full.variance_inflation;
  std::size_t taken = forms.size();
  double margin = kFormRejection;  // the best-fitting form the run prefers by more than this is taken
  for (std::size_t i = 0; i < forms.size(); ++i) {
    const double excess = variance > 0 ? (fits[i].rss - s.full.rss) / variance : 0.0;
    if (forms[i].taken_when_preferred && -excess > margin) {
      margin = -excess;
      taken = i;
    }
    if (forms[i].decided_by_fit && !(excess <= kFormRejection)) {
      s.model_forms_rejected.push_back(fmt::format("{} (its weighted RSS {:.3g} long-run residual variances above the model's)",
                                                   forms[i].assumption, excess));
      continue;
    }
    for (const auto& r : values_reported(*forms[i].model, fits[i], s.full))
      for (const auto& q : s.full.reported)
        if (q.name == r.name && std::isfinite(r.value)) shift[q.name] = std::max(shift[q.name], std::abs(r.value - q.value));
    s.model_forms.push_back(forms[i].assumption);
  }
  for (auto& r : s.full.reported) {
    const auto it = shift.find(r.name);
    if (it == shift.end()) continue;
    r.std_model_form = it->second / std::sqrt(3.0);
    if (r.std_asymptotic == 0.0) r.std_asymptotic = r.std;
    r.std = std::hypot(r.std, r.std_model_form);
  }
  if (taken < forms.size())
    s.model_form_taken = fmt::format("{} (its weighted RSS {:.3g} long-run residual variances below the model's)", forms[taken].assumption,
                                     margin);
  if (taken < forms.size() && !forms[taken].weighted) {
    for (const auto& r : values_reported(*forms[taken].model, fits[taken], s.full))
      for (auto& q : s.full.reported)
        if (q.name == r.name && std::isfinite(r.value)) q.value = r.value;
    return;
  }
  // The weighted forms and the model's own, averaged by their likelihoods relative to the model's
  // (weights exp(-excess / 2), the model's 1), each value where the form reports it (else the model's).
  std::vector<std::size_t> weighted;
  std::vector<double> log_w;
  for (std::size_t i = 0; i < forms.size(); ++i)
    if (forms[i].taken_when_preferred && forms[i].weighted && variance > 0) {
      weighted.push_back(i);
      log_w.push_back(-0.5 * (fits[i].rss - s.full.rss) / variance);
    }
  if (weighted.empty()) return;
  const double top = std::max(0.0, *std::max_element(log_w.begin(), log_w.end()));
  double total = std::exp(-top);
  for (const double l : log_w) total += std::exp(l - top);
  const double w_model = std::exp(-top) / total;
  std::map<std::string, double> mean;
  for (const auto& q : s.full.reported) mean[q.name] = w_model * q.value;
  s.model_form_weights.push_back(fmt::format("the model's own form: {:.3g}", w_model));
  for (std::size_t j = 0; j < weighted.size(); ++j) {
    const double w = std::exp(log_w[j] - top) / total;
    s.model_form_weights.push_back(fmt::format("{}: {:.3g}", forms[weighted[j]].assumption, w));
    std::map<std::string, double> v;
    for (const auto& r : values_reported(*forms[weighted[j]].model, fits[weighted[j]], s.full))
      if (std::isfinite(r.value)) v[r.name] = r.value;
    for (const auto& q : s.full.reported) {
      const auto it = v.find(q.name);
      mean[q.name] += w * (it != v.end() ? it->second : q.value);
    }
  }
  for (auto& q : s.full.reported) q.value = mean[q.name];
}

/// The reported values corrected for the errors in the family's variables (errors_in_variables_bias):
/// θ and φ stay the least-squares optimum (the predictions and residuals are its); each reported
/// value moves by what the corrected (θ, φ) change in it, a model form's taken values too.
void correct_errors_in_variables(Score& s, const ModelFamily& m, const Observations& obs, const std::vector<int>& all, int threads) {
  const auto vars = m.errors_in_variables();
  if (vars.empty()) return;
  const ErrorsInVariablesBias eiv = errors_in_variables_bias(m, obs, s.full, all, threads);
  if (!eiv.applied) {
    for (const auto& v : vars) s.errors_in_variables.push_back(fmt::format("{}: not corrected, {}", v.variable, eiv.why_not));
    return;
  }
  const Eigen::VectorXd& bias = eiv.bias;
  Fit corrected = s.full;
  corrected.theta -= bias.head(s.full.theta.size());
  corrected.phi -= bias.tail(s.full.phi.size());
  const auto before = values_reported(m, s.full, s.full);
  const auto after = values_reported(m, corrected, s.full);
  for (std::size_t i = 0; i < before.size() && i < after.size(); ++i)
    for (auto& r : s.full.reported)
      if (r.name == before[i].name && after[i].name == r.name) {
        const double d = after[i].value - before[i].value;
        if (!std::isfinite(d)) continue;
        r.value += d;
        r.errors_in_variables += d;  // beside a family's own (slow_slip's slip directions)
      }
  for (const auto& v : vars) s.errors_in_variables.push_back(fmt::format("{} (error std {:.3g})", v.variable, v.std));
}

}  // namespace

/// A family's component groups name columns of Observations::y (0..5), none empty: said before any fit.
void check_component_groups(const ModelFamily& m) {
  for (const auto& g : m.component_groups()) {
    if (g.components.empty())
      throw std::invalid_argument(fmt::format("model '{}': component group '{}' has no components", m.name(), g.name));
    for (const int c : g.components)
      if (c < 0 || c > 5)
        throw std::invalid_argument(fmt::format("model '{}': component group '{}' names component {}, outside the observation's 0..5",
                                                m.name(), g.name, c));
  }
}

Score score(const ModelFamily& m, const Observations& obs, const CvOptions& o, const Score* extends) {
  const auto t0 = std::chrono::steady_clock::now();
  check_component_groups(m);
  Score s;
  s.model = m.name();
  const std::size_t n = obs.size();
  std::vector<int> all(n);
  for (std::size_t k = 0; k < n; ++k) all[k] = static_cast<int>(k);
  DesignCache cache(m, n);
  const auto nl = m.nonlinear();
  std::optional<Eigen::VectorXd> from;
  if (extends) from = mapped(nl, extends->full.phi_names, extends->full.phi);
  s.full = fit_with(m, obs, all, o.fit, cache, from ? &*from : nullptr, true);
  s.train_error = relative_error(obs, predict_with(cache.get(s.full.phi), s.full, n), all);
  const double rows = static_cast<double>(s.full.rows);
  const double rank = static_cast<double>(s.full.rank);
  const double ll = rows * std::log(std::max(s.full.rss, 1e-300) / rows);
  s.bic = ll + rank * std::log(rows);
  s.aic = ll + 2.0 * rank;
  extension_pnr(s);
  if (o.screen) s.screened = o.screen(s);
  if (!s.screened.empty()) {
    s.full.jacobian.resize(0, 0);
    s.full.residual.resize(0);
    s.cv_error = std::numeric_limits<double>::quiet_NaN();
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return s;
  }
  FitOptions fold_fit = o.fit;
  fold_fit.noise_tolerance = std::max(fold_fit.noise_tolerance, o.fold_noise_tolerance);
  const int offsets = std::max(1, o.offsets);
  // The folds, offset after offset, in a fixed order: fold i's warm start is the model it extends' fold i.
  struct Fold {
    int shift = 0;
    std::vector<int> block, train;
    std::unique_ptr<ModelFamily> own;  ///< the fold's own model (ModelFamily::restricted), if any
    Fit fit;
    Eigen::MatrixXd prediction;
    Eigen::MatrixXd without;  ///< the prediction without CvOptions::effect_of (empty: not sized)
  };
  std::vector<Fold> folds;
  for (int shift = 0; shift < offsets; ++shift)
    for (auto& block : time_blocks(n, o.folds, static_cast<double>(shift) / offsets)) {
      if (block.empty()) continue;
      // Training: every sample farther than gap_samples from each held-out one (a shifted grid's
      // block 0 is two runs of samples, at the end and at the start).
      std::vector<int> near(n + 1, 0), train;
      for (int k : block) {
        ++near[static_cast<std::size_t>(std::max(0, k - o.gap_samples))];
        --near[static_cast<std::size_t>(std::min(static_cast<int>(n), k + o.gap_samples + 1))];
      }
      int covered = 0;
      for (int k : all)
        if ((covered += near[static_cast<std::size_t>(k)]) == 0) train.push_back(k);
      if (train.empty()) continue;
      Fold f;
      f.shift = shift;
      f.block = std::move(block);
      f.train = std::move(train);
      folds.push_back(std::move(f));
    }
  // One fold: its fit on its training samples and its prediction of every sample. `shared`: the
  // full fit's design cache (its kept starts), or another one for the family `m` on another thread.
  auto run_fold = [&](std::size_t i, DesignCache& shared) {
    Fold& fd = folds[i];
    // Leak-free: the family's data-derived choices and every start come from `train` alone.
    fd.own = m.restricted(fd.train);
    const ModelFamily& fm = fd.own ? *fd.own : m;
    std::optional<DesignCache> own_cache;
    if (fd.own) own_cache.emplace(fm, n);
    DesignCache& fc = fd.own ? *own_cache : shared;
    // The fold's model may differ from the full one in its parameters: warm start by name. What it
    // fixes as not identifiable it decides from its training samples (the full fit's flags would
    // carry its held-out block's information into it).
    std::optional<Eigen::VectorXd> warm;
    if (extends && i < extends->fold_phi.size()) warm = mapped(fm.nonlinear(), extends->fold_phi_names[i], extends->fold_phi[i]);
    fd.fit = fit_with(fm, obs, fd.train, fold_fit, fc, warm ? &*warm : nullptr, false, nullptr, true);
    fd.prediction = predict_with(fc.get(fd.fit.phi), fd.fit, n);
    if (!o.effect_of.empty()) fd.without = prediction_without(fm, fd.fit, obs, fd.train, o.effect_of, fc);
  };
  // The model forms' refits (they need the full fit only) and the folds are independent: they run
  // side by side, the refits first (the longest), each worker with its own data and design cache
  // (worker 0 the full fit's). Each result goes to its own slot, so the outcome is the serial one.
  const std::vector<ModelFamily::ModelForm> forms = o.model_forms ? m.model_forms() : std::vector<ModelFamily::ModelForm>{};
  std::vector<Fit> form_fits(forms.size());
  const std::size_t tasks = forms.size() + folds.size();
  const std::size_t workers = parallel::worker_count(tasks, o.threads);
  std::vector<std::optional<DesignCache>> worker_cache(workers);
  std::mutex told;
  int done = 0;
  const auto tell = [&] {
    if (!o.on_task) return;
    std::lock_guard<std::mutex> lock(told);
    o.on_task(done++, static_cast<int>(tasks));
  };
  tell();
  parallel::run_tasks(tasks, workers, [&](std::size_t i, std::size_t w) {
    if (i < forms.size()) {
      form_fits[i] = model_form_fit(forms[i], m, s, obs, all, o.fit);
    } else {
      if (w > 0 && !worker_cache[w]) worker_cache[w].emplace(m, n);
      run_fold(i - forms.size(), w > 0 ? *worker_cache[w] : cache);
    }
    tell();
  });
  // The full fit without its per-sample matrices: what the folds' and the groups' linear readings
  // copy and report from (a copy of the Jacobian per fold grew with the run).
  Fit light = s.full;
  light.jacobian.resize(0, 0);
  light.residual.resize(0);
  light.sandwich_half.clear();
  light.sandwich_full.clear();
  std::map<std::string, std::vector<double>> by_name, linear, fold_std;
  std::size_t folds_unshifted = 0;
  double pooled_sq = 0.0, effect_sq = 0.0;
  std::size_t next = 0;
  for (int shift = 0; shift < offsets; ++shift) {
    Eigen::MatrixXd held_out = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), 6);
    for (; next < folds.size() && folds[next].shift == shift; ++next) {
      const Fold& fd = folds[next];
      for (int k : fd.block) held_out.row(k) = fd.prediction.row(k);
      if (fd.without.size() > 0)
        for (int k : fd.block)
          for (int c = 0; c < 6; ++c) {
            const double r = obs.weight(c) * (obs.y(k, c) - fd.prediction(k, c));
            const double r0 = obs.weight(c) * (obs.y(k, c) - fd.without(k, c));
            effect_sq += r0 * r0 - r * r;
          }
      s.fold_phi.push_back(fd.fit.phi);
      s.fold_phi_names.push_back(fd.fit.phi_names);
      if (shift > 0) continue;
      // The fold's estimates of what the full fit reports (derived quantities included): the
      // intervals' spread is that of the plain grid's folds (a shifted grid's overlap them).
      for (const auto& r : values_reported(fd.own ? *fd.own : m, fd.fit, s.full)) by_name[r.name].push_back(r.value);
      // The fold's estimate as the full fit's linearisation predicts it: A_i⁺ J_trainᵀ r_train
      // from the full optimum (honest_intervals compares the fold's own with it).
      if (s.full.jacobian.size() > 0) {
        std::vector<Eigen::Index> train_rows;
        train_rows.reserve(6 * fd.train.size());
        for (int k : fd.train)
          for (Eigen::Index c = 0; c < 6; ++c) train_rows.push_back(6 * static_cast<Eigen::Index>(k) + c);
        // The fold's asymptotic std of each value is what the model says the fold knows (the
        // one-event check in honest_intervals).
        for (const auto& r : rows_reading(m, s.full, light, train_rows)) {
          linear[r.name].push_back(r.value);
          fold_std[r.name].push_back(r.std);
        }
      }
      ++folds_unshifted;
    }
    const double e = relative_error(obs, held_out, all);
    pooled_sq += e * e;
    if (shift == 0) s.cv_prediction = std::move(held_out);
    else s.cv_shifted.push_back(std::move(held_out));
  }
  s.cv_error = std::sqrt(pooled_sq / offsets);
  if (!o.effect_of.empty()) s.held_out_effect = effect_sq / (6.0 * static_cast<double>(n) * offsets);
  GroupReadings groups;
  if (s.full.jacobian.size() > 0)
    for (const auto& g : m.component_groups()) {
      std::vector<Eigen::Index> group_rows;
      group_rows.reserve(g.components.size() * n);
      for (std::size_t k = 0; k < n; ++k)
        for (int c : g.components) group_rows.push_back(6 * static_cast<Eigen::Index>(k) + c);
      groups.names.push_back(g.name);
      for (const auto& r : rows_reading(m, s.full, light, group_rows)) {
        groups.value[r.name].push_back(r.value);
        groups.std[r.name].push_back(r.std);
      }
    }
  honest_intervals(s, m, by_name, linear, fold_std, folds_unshifted, groups);
  s.full.jacobian.resize(0, 0);  // its rows scale with the run: not kept beyond their use
  s.full.residual.resize(0);
  s.full.sandwich_half.clear();
  s.full.sandwich_full.clear();
  s.full.normal_inverse.resize(0, 0);
  model_form_intervals(s, forms, form_fits);
  if (o.errors_in_variables) correct_errors_in_variables(s, m, obs, all, o.threads);
  s.full.invalid = m.check(s.full);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

}  // namespace hil::diagnose
