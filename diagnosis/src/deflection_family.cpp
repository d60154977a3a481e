#include <hil/diagnose/deflection_family.hpp>
#include <hil/diagnose/effect.hpp>
#include <hil/so3/so3.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace hil::diagnose {

const std::vector<std::string>& deflection_extensions() { return effect_names(FamilyKind::deflection); }

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
    const auto i = static_cast<Eigen::Index>(k);
    d.obs.y.row(i).head<3>() = (T.translation() - p0).transpose();
    d.obs.y.row(i).tail<3>() = so3::log(Eigen::Matrix3d(T.linear() * R0.transpose())).transpose();
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

namespace {

std::vector<int> all_samples(std::size_t n) {
  std::vector<int> s(n);
  std::iota(s.begin(), s.end(), 0);
  return s;
}

/// Piecewise-constant mean of the standardised residual z with changes at `p`: prefix sums, gains.
class Segments {
 public:
  explicit Segments(const Eigen::MatrixXd& z) : m_(static_cast<int>(z.rows())), s_(z.rows() + 1, z.cols()) {
    s_.row(0).setZero();
    for (Eigen::Index k = 0; k < z.rows(); ++k) s_.row(k + 1) = s_.row(k) + z.row(k);
  }
  int size() const { return m_; }
  /// The cost decrease of splitting [a, b) at j: (j-a)(b-j)/(b-a) |mean(a,j) - mean(j,b)|².
  double gain(int a, int j, int b) const {
    const double n1 = j - a, n2 = b - j;
    const Eigen::RowVectorXd d = (s_.row(j) - s_.row(a)) / n1 - (s_.row(b) - s_.row(j)) / n2;
    return n1 * n2 / (n1 + n2) * d.squaredNorm();
  }
  /// The best split of [a, b) at an allowed position leaving at least L samples either side; j = -1
  /// when none fits.
  std::pair<int, double> best(int a, int b, int L, const std::vector<char>& allowed) const {
    std::pair<int, double> out{-1, -1.0};
    for (int j = a + L; j <= b - L; ++j)
      if (allowed[static_cast<std::size_t>(j)])
        if (const double g = gain(a, j, b); g > out.second) out = {j, g};
    return out;
  }
  Eigen::RowVectorXd mean(int a, int b) const { return (s_.row(b) - s_.row(a)) / static_cast<double>(b - a); }

 private:
  int m_;
  Eigen::MatrixXd s_;
};

/// Binary segmentation with penalty `beta`, at most `cap` changes, then coordinate descent on the
/// positions and pruning of the changes that no longer pay their penalty.
std::vector<int> segment(const Segments& sg, double beta, int cap, int L, const std::vector<char>& allowed) {
  const int m = sg.size();
  std::vector<int> p;
  auto bounds = [&](std::size_t i) { return std::pair<int, int>{i == 0 ? 0 : p[i - 1], i + 1 < p.size() ? p[i + 1] : m}; };
  auto refine = [&] {
    for (int pass = 0; pass < 20; ++pass) {
      bool moved = false;
      for (std::size_t i = 0; i < p.size(); ++i) {
        const auto [a, b] = bounds(i);
        const int j = sg.best(a, b, L, allowed).first;
        if (j >= 0 && j != p[i]) {
          p[i] = j;
          moved = true;
        }
      }
      if (!moved) return;
    }
  };
  while (static_cast<int>(p.size()) < cap) {
    std::pair<int, double> top{-1, -1.0};
    for (std::size_t i = 0; i <= p.size(); ++i) {
      const int a = i == 0 ? 0 : p[i - 1], b = i < p.size() ? p[i] : m;
      if (const auto c = sg.best(a, b, L, allowed); c.second > top.second) top = c;
    }
    if (top.first < 0 || !(top.second > beta)) break;
    p.insert(std::upper_bound(p.begin(), p.end(), top.first), top.first);
    refine();
  }
  for (;;) {
    std::size_t weakest = p.size();
    double g_min = beta;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const auto [a, b] = bounds(i);
      if (const double g = sg.gain(a, p[i], b); !(g > g_min)) {
        g_min = g;
        weakest = i;
      }
    }
    if (weakest == p.size()) break;
    p.erase(p.begin() + static_cast<std::ptrdiff_t>(weakest));
    refine();
  }
  return p;
}

/// The long-run variance (Bartlett, up to 20 lags, as the engine's variance_inflation) of z around
/// the segment means, averaged over the components, in noise variances (z is standardised by the
/// first-difference noise), at least 1: model error left around the segmentation (slow drifts)
/// makes a change's position less certain than the sensor noise alone would.
double long_run_variance(const Eigen::MatrixXd& z, const Segments& sg, const std::vector<int>& p) {
  const Eigen::Index m = z.rows();
  Eigen::MatrixXd e = z;
  for (std::size_t i = 0; i <= p.size(); ++i) {
    const int a = i == 0 ? 0 : p[i - 1], b = i < p.size() ? p[i] : static_cast<int>(m);
    e.middleRows(a, b - a).rowwise() -= sg.mean(a, b);
  }
  const int L = static_cast<int>(std::min<Eigen::Index>(20, m / 4));
  double lrv = 0.0;
  int active = 0;
  for (Eigen::Index c = 0; c < e.cols(); ++c) {
    const Eigen::VectorXd rc = e.col(c);
    const double v0 = rc.squaredNorm();
    if (!(v0 > 0)) continue;
    double factor = 1.0;
    for (int l = 1; l <= L; ++l) factor += 2.0 * (1.0 - l / (L + 1.0)) * rc.head(m - l).dot(rc.tail(m - l)) / v0;
    lrv += v0 / static_cast<double>(m) * std::max(1.0, factor);
    ++active;
  }
  return active > 0 ? std::max(1.0, lrv / active) : 1.0;
}

/// Per position j: how much a step at j lowers the cost of a line in time fitted to the `window`
/// samples either side (z standardised: in noise variances, summed over the components). A step is
/// abrupt; a slow deflection the model misses is locally a line and gains nothing here.
std::vector<double> local_step_gain(const Eigen::MatrixXd& z, const std::vector<double>& t, int window) {
  const int m = static_cast<int>(z.rows());
  std::vector<double> out(static_cast<std::size_t>(m), 0.0);
  for (int j = 2; j + 2 <= m; ++j) {
    const int a = std::max(0, j - window), b = std::min(m, j + window);
    const Eigen::Index n = b - a;
    Eigen::MatrixXd X(n, 3);
    const double t0 = t[static_cast<std::size_t>(j)];
    const double span = std::max(t[static_cast<std::size_t>(b - 1)] - t[static_cast<std::size_t>(a)], 1e-300);
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(a + k);
      X(k, 0) = 1.0;
      X(k, 1) = (t[i] - t0) / span;
      X(k, 2) = a + k >= j ? 1.0 : 0.0;
    }
    const Eigen::MatrixXd Y = z.middleRows(a, n);
    // Residual cost with and without the step column (Householder QR, no normal equations).
    const Eigen::HouseholderQR<Eigen::MatrixXd> q3(X), q2(X.leftCols(2));
    const Eigen::MatrixXd r3 = Y - X * q3.solve(Y);
    const Eigen::MatrixXd r2 = Y - X.leftCols(2) * q2.solve(Y);
    out[static_cast<std::size_t>(j)] = r2.squaredNorm() - r3.squaredNorm();
  }
  return out;
}

}  // namespace

ChangePoints locate_changes(const Eigen::MatrixXd& residual, const std::vector<double>& t_s, int max_events, int min_segment, int window) {
  if (residual.cols() != 6)
    throw std::invalid_argument("locate_changes: the residual has " + std::to_string(residual.cols()) + " columns, expected 6");
  if (!residual.allFinite()) throw std::invalid_argument("locate_changes: the residual is not finite");
  if (min_segment < 2) throw std::invalid_argument("locate_changes: min_segment must be at least 2");
  if (window < 2) throw std::invalid_argument("locate_changes: window must be at least 2");
  if (!t_s.empty() && t_s.size() != static_cast<std::size_t>(residual.rows()))
    throw std::invalid_argument("locate_changes: " + std::to_string(t_s.size()) + " times for " + std::to_string(residual.rows()) +
                                " residual rows");
  for (std::size_t k = 1; k < t_s.size(); ++k)
    if (!(t_s[k] > t_s[k - 1])) throw std::invalid_argument("locate_changes: the times do not increase at row " + std::to_string(k));
  ChangePoints out;
  const Eigen::Index m = residual.rows();
  if (max_events <= 0 || m < 2 * min_segment) return out;
  // Each component in units of its noise: the median absolute first difference ignores the few
  // differences a step makes (and slow model error); a component without noise (but a step or two)
  // falls back to the rms difference, one without any variation carries nothing.
  Eigen::MatrixXd z = residual;
  for (Eigen::Index c = 0; c < 6; ++c) {
    std::vector<double> ad(static_cast<std::size_t>(m - 1));
    for (Eigen::Index k = 0; k + 1 < m; ++k) ad[static_cast<std::size_t>(k)] = std::abs(residual(k + 1, c) - residual(k, c));
    const std::size_t mid = ad.size() / 2;
    std::nth_element(ad.begin(), ad.begin() + static_cast<std::ptrdiff_t>(mid), ad.end());
    double sigma = 1.4826 * ad[mid] / std::sqrt(2.0);
    if (!(sigma > 0)) {
      const Eigen::VectorXd dc = residual.col(c).tail(m - 1) - residual.col(c).head(m - 1);
      sigma = std::sqrt(dc.squaredNorm() / (2.0 * static_cast<double>(m - 1)));
    }
    if (sigma > 0) z.col(c) /= sigma;
    else z.col(c).setZero();
  }
  const Segments sg(z);
  // BIC: 6 offsets and a time per event, in noise variances.
  const double bic = 7.0 * std::log(static_cast<double>(m));
  // Only abrupt changes: a step must pay its penalty against a local line too.
  std::vector<double> t = t_s;
  if (t.empty())
    for (Eigen::Index k = 0; k < m; ++k) t.push_back(static_cast<double>(k));
  const std::vector<double> local = local_step_gain(z, t, window);
  std::vector<char> allowed(static_cast<std::size_t>(m) + 1, 0);
  for (std::size_t j = 0; j < local.size(); ++j) allowed[j] = local[j] > bic ? 1 : 0;
  // Globally not inflated by the model error left around the segmentation: a compliance fitted
  // without the steps leaves a large slow misfit, against which a fold could no longer see a slip
  // its training samples hold; the local test is what keeps slow misfit out.
  const std::vector<int> p = segment(sg, bic, max_events, min_segment, allowed);
  // The intervals: the split cost's noise is correlated like the residual around the segmentation.
  const double kappa = long_run_variance(z, sg, p);
  out.inflation = kappa;
  out.position = p;
  // The profile of the split cost: positions within 3.84 (χ²₁, 95 %) long-run variances of the best.
  for (std::size_t i = 0; i < p.size(); ++i) {
    const int a = i == 0 ? 0 : p[i - 1], b = i + 1 < p.size() ? p[i + 1] : static_cast<int>(m);
    const double g = sg.gain(a, p[i], b);
    int lo = p[i], hi = p[i];
    for (int j = a + min_segment; j <= b - min_segment; ++j)
      if (g - sg.gain(a, j, b) <= 3.84 * kappa) {
        lo = std::min(lo, j);
        hi = std::max(hi, j);
      }
    out.lower.push_back(lo);
    out.upper.push_back(hi);
  }
  return out;
}

DeflectionFamily::DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions)
    : DeflectionFamily(d, std::move(extensions), all_samples(d.obs.size())) {}

DeflectionFamily::DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions, const std::vector<int>& train)
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
  first_step_ = linear_.size();
  if (ext_.count("rest_change")) locate(train);
}

std::vector<LocatedEvent> DeflectionFamily::located_events() const {
  std::vector<LocatedEvent> out;
  for (std::size_t e = 0; e < events_.size(); ++e)
    out.push_back({"event_" + std::to_string(e + 1) + "_s", events_[e].t_s, events_[e].lower_s, events_[e].upper_s,
                   events_[e].first_sample});
  return out;
}

void DeflectionFamily::add_steps() {
  linear_.resize(first_step_);
  for (std::size_t e = 0; e < events_.size(); ++e)
    for (std::size_t c = 0; c < 6; ++c)
      linear_.push_back({"step_" + std::to_string(e + 1) + "_" + d_.obs.component[c], d_.obs.unit[c], 1e-3, true});
}

void DeflectionFamily::locate(const std::vector<int>& train) {
  if (train.size() < 2) throw std::runtime_error("rest_change: too few samples to locate events");
  const auto& t = d_.obs.t_s;
  // The weighted residual on `train` of the model's columns before the steps.
  auto search = [&](const ModelFamily& m, const Fit& f) {
    Eigen::MatrixXd A;
    m.design(f.phi, A);
    const Eigen::Index p = static_cast<Eigen::Index>(first_step_);
    const Eigen::VectorXd y = A.leftCols(p) * f.theta.head(p);
    Eigen::MatrixXd r(static_cast<Eigen::Index>(train.size()), 6);
    for (std::size_t a = 0; a < train.size(); ++a)
      for (int c = 0; c < 6; ++c) r(static_cast<Eigen::Index>(a), c) = d_.obs.weight(c) * (d_.obs.y(train[a], c) - y(6 * train[a] + c));
    std::vector<double> tt;
    for (int k : train) tt.push_back(t[static_cast<std::size_t>(k)]);
    const ChangePoints cp = locate_changes(r, tt);
    events_.clear();
    for (std::size_t e = 0; e < cp.position.size(); ++e) {
      const auto j = static_cast<std::size_t>(cp.position[e]);
      // Between the last sample searched at the old rest pose and the first at the new one: for a
      // fold whose held-out block holds the change, that is the whole gap.
      RestEvent ev;
      ev.first_sample = train[j];
      ev.before_s = t[static_cast<std::size_t>(train[j - 1])];
      ev.after_s = t[static_cast<std::size_t>(train[j])];
      ev.t_s = 0.5 * (ev.before_s + ev.after_s);
      ev.lower_s = t[static_cast<std::size_t>(train[static_cast<std::size_t>(cp.lower[e]) - 1])];
      ev.upper_s = t[static_cast<std::size_t>(train[static_cast<std::size_t>(cp.upper[e])])];
      events_.push_back(ev);
    }
    add_steps();
  };
  std::set<std::string> others = ext_;
  others.erase("rest_change");
  const DeflectionFamily without(d_, others);
  search(without, fit(without, d_.obs, train));
  if (events_.empty()) return;
  // Once more, on the residual of the joint fit without its steps.
  search(*this, fit(*this, d_.obs, train));
}

std::vector<Reported> DeflectionFamily::report(const Fit& f) const {
  std::vector<Reported> out = ModelFamily::report(f);
  for (auto& r : out)
    if (r.name.rfind("step_", 0) == 0) r.fold_comparable = false;
  return out;
}

std::unique_ptr<ModelFamily> DeflectionFamily::restricted(const std::vector<int>& train) const {
  if (!ext_.count("rest_change")) return nullptr;
  return std::unique_ptr<ModelFamily>(new DeflectionFamily(d_, ext_, train));
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

void DeflectionFamily::design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const {
  const std::size_t n = d_.obs.size();
  A.setZero(static_cast<Eigen::Index>(6 * n), static_cast<Eigen::Index>(linear_.size()));
  const double tau = i_tau_ >= 0 ? phi(i_tau_) : 0.0;
  const auto& t = d_.obs.t_s;
  for (std::size_t k = 0; k < n; ++k) {
    const auto r = static_cast<Eigen::Index>(6 * k);
    for (int c = 0; c < 6; ++c) A(r + c, c) = 1.0;
    for (std::size_t e = 0; e < events_.size(); ++e) {
      const RestEvent& ev = events_[e];
      const double h = t[k] >= ev.after_s ? 1.0 : t[k] <= ev.before_s ? 0.0 : (t[k] - ev.before_s) / (ev.after_s - ev.before_s);
      if (h > 0.0)
        for (int c = 0; c < 6; ++c) A(r + c, static_cast<Eigen::Index>(first_step_ + 6 * e) + c) = h;
    }
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
