// slow_slip: friction where the rig declares the contacts sticking. Below the declared sticking
// threshold v_t,m the nominal model predicts no friction (the contact paper's choice: the slip
// direction of a contact that sticks is noise). A foot that slides slowly through a stop (a yaw
// ramp on a trapezoidal profile) still bears Coulomb friction, and the run's residual then
// follows the stops (issue 32: clean trapezoidal runs said `unexplained`, mz up to 23 noise
// variances, because the truth's friction acts down to 1 µm/s against a declared 0.1 mm/s).
// Per contact whose slip speed is in (0, v_t,m]: μ_s K δ_e e_s, e_s = -v_t / |v_t| the measured
// slip direction; θ = μ_s K. A slow slip of the nominal model's own friction reads μ_s = μ; true
// sticking (static friction, whose direction is not the noise's) reads μ_s ~ 0.
#include <hil/diagnose/contact_family.hpp>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace hil::diagnose {
namespace {

constexpr const char* kMuK = "slow_slip_mu_k_n_per_m";

/// Whether the nominal model calls c sticking while its measured slip is above zero.
bool slow(const cid::ContactPoint& c, double v_tm) { return c.tangent.isZero() && c.slip_speed > 0.0 && c.slip_speed <= v_tm; }

/// What the reported twist's quantisation does to μ_s K through the slow contacts' measured slip
/// directions (slip_direction_error): the fitted μ_s K reads `factor` times the one exact
/// directions would give, within `relative_std`.
struct DirectionError {
  double factor = 1.0;
  double relative_std = 0.0;
};

class Term : public ContactTerm {
 public:
  Term(double v_tm, std::size_t samples, double twist_step_m_per_s)
      : v_tm_(v_tm), samples_(samples), twist_step_m_per_s_(twist_step_m_per_s) {}
  /// What the reported twist's quantisation does to μ_s K (slip_direction_error).
  void set_direction_error(const DirectionError& e) { direction_ = e; }
  std::vector<Param> linear() const override { return {{kMuK, "N/m", 1e4, true}}; }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    if (!slow(c, v_tm_)) return;  // sliding: the nominal μK's
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, at.normal_delta_m * c.slip_direction, at.friction_point);
  }
  /// μ_s / μ = θ_s / (μK) with its std by the delta method (informative: the PNR checks θ_s).
  void report_derived(const ContactSlots& s, Eigen::Index, const Fit& f, std::vector<Reported>& out) const override {
    const Eigen::Index a = s.linear, m = 1;  // θ = (K, μK, ...): μK is the nominal model's second entry
    const double mk = f.theta(m);
    if (!(std::abs(mk) > 0.0)) return;
    const double r = f.theta(a) / mk;
    const double var = (f.cov(a, a) - 2.0 * r * f.cov(a, m) + r * r * f.cov(m, m)) / (mk * mk);
    const double g = direction_.factor;
    out.push_back({"slow_slip_mu_ratio", "", r / g, std::hypot(std::sqrt(std::max(0.0, var)) / g, r / g * direction_.relative_std), false});
    out.back().errors_in_variables = r / g - r;
  }
  /// μ_s K corrected for the slip directions' error in the variables, its std holding what the
  /// correction leaves (slip_direction_error).
  void report(const ContactSlots&, bool linear, Eigen::Index index, const Fit&, Reported& r) const override {
    if (!(linear && index == 0)) return;
    const double least_squares = r.value;
    r.value /= direction_.factor;
    r.errors_in_variables += r.value - least_squares;
    r.std = std::hypot(r.std / direction_.factor, r.value * direction_.relative_std);
  }
  std::string check_line(const Reported& q) const override {
    return q.name == kMuK && q.value < -2.0 * q.std ? fmt::format("{} = {:.4g} ± {:.2g} is negative", q.name, q.value, q.std) : "";
  }
  /// How to read μ_s / μ on this run: the reported twist's step beside the threshold says whether
  /// sliding contacts can read below it.
  std::string note() const override {
    return fmt::format("slow_slip acts on {} samples slipping below the declared sticking threshold ({:.3g} mm/s; twist step {}{}): "
                       "μ_s/μ near 1, they slide with their friction (declare it lower); well below 1, some stick or are misread",
                       samples_, 1e3 * v_tm_,
                       twist_step_m_per_s_ > 0.0 ? fmt::format("{:.3g} mm/s", 1e3 * twist_step_m_per_s_) : std::string("none seen"),
                       direction_.relative_std > 0.0
                           ? fmt::format(", whose error in the slip directions reads μ_s K {:+.2g} % (corrected), ± {:.2g} %",
                                         100 * (direction_.factor - 1.0), 100 * direction_.relative_std)
                           : std::string());
  }

 private:
  double v_tm_;
  std::size_t samples_;
  double twist_step_m_per_s_;
  DirectionError direction_;
};

/// The relative error of μ_s K that the reported twist's quantisation leaves through the measured
/// slip directions, as a std (issue 32). A slow contact slips at a few twist steps, and a step's
/// error turns its direction e_s = -v_t/|v_t| by tens of degrees: the column is measured with
/// error, which no residual-based std sees (errors in the variables). Measured on the family
/// suite's trapezoidal development draws (docs/diagnosis.md): the twist's error drawn independent
/// per sample and axis, uniform over the step, spreads the fitted μ_s / μ by 0.3-10 % per draw,
/// the widest on the draws whose quantised twist put it furthest off. Estimated here the same way,
/// from the measured twist (as SIMEX does): R replicates of the twist with such an error added,
/// each slow contact's direction recomputed, and the coefficient of the perturbed column fitted to
/// the measured one next to the nominal K and μK columns (partialled out: they share the
/// samples); the root mean square of its departure from 1. The slow set is the measured one.
/// The positions' and the orientation's errors are left out (under 1 %, measured).
/// The replicates' mean coefficient is the factor the error multiplies μ_s K by, and μ_s K is
/// divided by it (the step SIMEX extrapolates; regression calibration). On the suite's draws it is
/// above 1, as the fits were: the error does not attenuate the coefficient towards zero here (the
/// column is six components of several feet, not one scalar; docs/diagnosis.md). The std keeps
/// the replicates' root mean square departure from 1, the correction's own size included.
DirectionError slip_direction_error(const ContactBinding& b, double v_tm) {
  const ContactData& d = b.data;
  const Eigen::Vector3d q = d.velocity_quantum_m_per_s;
  if (!(q.maxCoeff() > 0.0)) return {};
  const std::size_t n = d.obs.size();
  std::vector<int> used = b.samples;
  if (used.empty())
    for (std::size_t k = 0; k < n; ++k) used.push_back(static_cast<int>(k));
  Eigen::MatrixXd N;  // the nominal K and μK columns on every sample
  b.design_alone(std::make_shared<const ContactTerm>(), Eigen::VectorXd(), N);
  const Eigen::Matrix<double, 6, 1> w = d.obs.weight;
  const Eigen::Isometry3d& T_fp = d.scene.T_world_fp;
  // The weighted slow column X_a of one sample, with the ee's linear velocity v.
  auto column = [&](std::size_t k, const Eigen::Vector3d& v) {
    cid::Kinematics kin = d.kin[k];
    kin.v_world_ee = v;
    Vector6d x = Vector6d::Zero();
    for (const auto& c : d.contacts[k]) {
      if (!slow(c, v_tm)) continue;
      const Eigen::Vector3d u = cid::relative_velocity(d.scene, kin, c.point);
      const Eigen::Vector3d ut = u - u.dot(c.normal) * c.normal;
      const double s = ut.norm();
      if (s > 0.0) x += plate_wrench_of(T_fp, -c.delta / s * ut, c.point);
    }
    return Vector6d(w.cwiseProduct(x));
  };
  std::vector<std::size_t> slow_samples;
  std::vector<Vector6d> X;
  Eigen::Matrix2d NtN = Eigen::Matrix2d::Zero();
  for (const int i : used) {
    const auto k = static_cast<std::size_t>(i);
    const auto rows = N.block(6 * static_cast<Eigen::Index>(k), 0, 6, 2);
    const Eigen::Matrix<double, 6, 2> Nk = w.asDiagonal() * rows;
    NtN += Nk.transpose() * Nk;
    bool any = false;
    for (const auto& c : d.contacts[k]) any = any || slow(c, v_tm);
    if (!any) continue;
    slow_samples.push_back(k);
    X.push_back(column(k, d.kin[k].v_world_ee));
  }
  if (slow_samples.empty()) return {};
  // An axis the twist reports exactly zero through a whole stretch of slow samples is held: the
  // quantiser leaves no error where the truth rests on its grid (a robot's move along one axis;
  // a yaw about the ee), and an error added there turned directions that were exact.
  std::vector<Eigen::Vector3d> scale(slow_samples.size(), q);
  for (std::size_t a = 0; a < slow_samples.size();) {
    std::size_t end = a + 1;
    while (end < slow_samples.size() && slow_samples[end] == slow_samples[end - 1] + 1) ++end;
    for (int j = 0; j < 3; ++j) {
      bool held = true;
      for (std::size_t m = a; m < end && held; ++m) held = d.kin[slow_samples[m]].v_world_ee[j] == 0.0;
      if (held)
        for (std::size_t m = a; m < end; ++m) scale[m][j] = 0.0;
    }
    a = end;
  }
  const Eigen::Matrix2d NtN_inv = NtN.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::Vector2d NtX = Eigen::Vector2d::Zero();
  for (std::size_t j = 0; j < slow_samples.size(); ++j)
    NtX += (w.asDiagonal() * N.block(6 * static_cast<Eigen::Index>(slow_samples[j]), 0, 6, 2)).transpose() * X[j];
  // A fixed generator (SplitMix64): the same run gives the same interval.
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uniform = [&state]() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (static_cast<double>(z >> 11) + 0.5) / 9007199254740992.0 - 0.5;  // in (-1/2, 1/2)
  };
  constexpr int kReplicates = 200;
  double mse = 0.0, sum = 0.0;
  int counted = 0;  // a replicate whose partialled column vanishes says nothing of the error
  for (int r = 0; r < kReplicates; ++r) {
    double xy = 0.0, xx = 0.0;
    Eigen::Vector2d NtXr = Eigen::Vector2d::Zero();
    for (std::size_t j = 0; j < slow_samples.size(); ++j) {
      const std::size_t k = slow_samples[j];
      const Eigen::Vector3d& h = scale[j];
      const Eigen::Vector3d v = d.kin[k].v_world_ee + Eigen::Vector3d(h(0) * uniform(), h(1) * uniform(), h(2) * uniform());
      const Vector6d xr = column(k, v);
      xy += xr.dot(X[j]);
      xx += xr.squaredNorm();
      NtXr += (w.asDiagonal() * N.block(6 * static_cast<Eigen::Index>(k), 0, 6, 2)).transpose() * xr;
    }
    // y = X_a regressed on [N, X'_a]: the coefficient of X'_a partialled on N.
    const double num = xy - NtXr.dot(NtN_inv * NtX), den = xx - NtXr.dot(NtN_inv * NtXr);
    if (!(den > 0.0)) continue;
    mse += std::pow(num / den - 1.0, 2);
    sum += num / den;
    ++counted;
  }
  if (counted == 0) return {};
  return {sum / counted, std::sqrt(mse / counted)};
}

class SlowSlip : public ContactEffect {
 public:
  std::string name() const override { return "slow_slip"; }
  int list_order() const override { return 65; }
  std::string description() const override {
    return "friction acts where the rig declares the contacts sticking: they slide below the declared threshold, or the "
           "measured slip reads them below it (μ_s/μ says which)";
  }
  int layout_order() const override { return 65; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override {
    const double v_tm = b.data.v_tm;
    auto slow_sample = [&](std::size_t k) {
      for (const auto& c : b.data.contacts[k])
        if (slow(c, v_tm)) return true;
      return false;
    };
    std::size_t n = 0;
    if (b.samples.empty())
      for (std::size_t k = 0; k < b.data.contacts.size(); ++k) n += slow_sample(k) ? 1 : 0;
    for (const int k : b.samples) n += slow_sample(static_cast<std::size_t>(k)) ? 1 : 0;
    if (n == 0)
      throw std::runtime_error(fmt::format("slow_slip: no contact slips below the declared sticking threshold ({:.3g} mm/s) on this run",
                                           1e3 * v_tm));
    auto term = std::make_shared<Term>(v_tm, n, b.data.velocity_quantum_m_per_s.maxCoeff());
    term->set_direction_error(slip_direction_error(b, v_tm));
    return term;
  }
  std::string separating_experiment(const std::string& other) const override {
    (void)other;
    return "a run that holds still in contact and then slides slowly (well below the declared sticking threshold, then above it)";
  }
};

}  // namespace

std::shared_ptr<const Effect> make_slow_slip() { return std::make_shared<SlowSlip>(); }

}  // namespace hil::diagnose
