// contact_damping: per contact the normal force K (δ_e + τ_D δ̇)₊ (δ̇ = -v_rel·e_n, the penetration
// rate; D = K τ_D, reported in N s/m) and per sliding contact a friction force μ_D D δ̇ e_t. The
// normal force is clipped at zero: a foot withdrawing faster than its elastic force allows pushes
// nothing and does not pull, nor bears friction (Hunt-Crossley; issue 32 measured D 2 % low, z
// −3.6, when the model let it pull). The clip makes τ_D a nonlinear parameter: which contacts
// bear force depends on it. In Kelvin-Voigt / Hunt-Crossley contact the friction bound follows the
// total normal force, damping included; its own coefficient (0 when the friction follows the
// elastic force only) keeps the family separable.
#include <hil/diagnose/contact_family.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactBinding& b) : level_shift_(level_shift(b.data, b.samples)) {}
  /// μ_D D >= 0, a bound of the fit: a law whose friction follows the elastic force only has
  /// μ_D D = 0 on the bound, and a check that refused fits reading it below zero lost such runs at
  /// its one-sided rate (4 of 100 off-suite draws, issue 32). Held there, it is reported as having
  /// run to its bound.
  std::vector<Param> linear() const override { return {{"damping_friction_n_s_per_m", "N s/m", 100, true, 0.0}}; }
  /// τ_D = D / K; ± 1 s bounds ten times any contact's D / K seen (17-40 ms), so a bound is no estimate.
  std::vector<Param> nonlinear() const override { return {{"damping_time_s", "s", 0.01, true, -1.0, 1.0}}; }
  bool needs_rates() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.damping_time_s = phi(s.nonlinear);
  }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    const double rate = -contact_id::relative_velocity(at.data.scene, at.rate_kinematics, c.point).dot(c.normal);
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, at.damping_scale * rate * c.tangent,
                                          at.friction_point);  // zero while sticking
  }
  /// τ_D's line as D = K τ_D (N s/m), its variance by the delta method from the joint covariance of
  /// K and τ_D. Fixed as not identifiable, the line keeps τ_D's name, so the report drops it.
  void report(const ContactSlots& s, bool linear, Eigen::Index, const Fit& f, Reported& r) const override {
    const Eigen::Index k = 0, t = f.theta.size() + s.nonlinear;
    if (linear || f.is_fixed(t)) return;
    const double K = f.theta(k), tau = f.phi(s.nonlinear);
    const double var = tau * tau * f.cov(k, k) + K * K * f.cov(t, t) + 2.0 * K * tau * f.cov(k, t);
    r.name = "damping_n_s_per_m";
    r.unit = "N s/m";
    r.value = K * tau;
    r.std = std::hypot(std::sqrt(std::max(0.0, var)), r.value * level_shift_);
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "damping_n_s_per_m" && q.value < -2.0 * q.std ? q.name + " = " + std::to_string(q.value) + " is negative" : "";
  }
  /// The friction the damping adds is μ_D D with 0 <= μ_D (a bound of the fit, linear()), and none
  /// where there is no damping force (D within two std of 0) to carry it. A fit that uses the
  /// friction column with no damping force behind it (D ~ 0, damping_friction thousands of N s/m)
  /// stands in for something else, e.g. a friction that falls with the sliding speed (issue 32's
  /// Stribeck draws). The tighter bound μ_D <= μ (the Coulomb friction of the damping force) was
  /// tried and not kept: on damping runs of the independent truth, whose friction follows the total
  /// normal force with one μ, the fit reads μ_D 3-4 % above μ (the model form; asymptotic std 1 %),
  /// and the bound refused real dampings, which a delay then stood in for (docs/diagnosis.md).
  std::string check(const ContactSlots&, Eigen::Index, const Fit& f) const override {
    const Reported *df = nullptr, *D = nullptr;
    for (const auto& q : f.reported) {
      if (q.name == "damping_friction_n_s_per_m") df = &q;
      if (q.name == "damping_n_s_per_m") D = &q;
    }
    if (!df) return "";  // held at its bound 0
    if (D && df->value > 2.0 * df->std && std::abs(D->value) < 2.0 * D->std)
      return fmt::format("{} = {:.4g} ± {:.2g} with no damping force to carry it (D = {:.4g} ± {:.2g})", df->name, df->value, df->std,
                         D->value, D->std);
    return "";
  }

 private:
  /// The relative shift of D that the reported twist's levels leave, as an uncertainty (issue 32).
  /// A twist quantised at q reads one level for as long as the true speed stays within it: on a
  /// robot's constant-speed segments its error is one value for the whole segment, and one value
  /// for every segment at the same speed, not noise. To first order it shifts the fitted D by
  /// -D Σ_k m_k e_k r_k / Σ_k m_k r_k² (m_k contacts, r_k = -v_k·n the penetration rate, e_k its
  /// error). Measured on DelayAndDampingOnMoves' draws (no noise): the formula with the true errors
  /// -1.4, +2.5, -0.3, +4.0 %, the fit -2.6, +2.1, -0.4, +3.8 % (+0.1 % on the exact twist). The
  /// errors are estimated on every run of one level at least kRun samples long as the level less
  /// the positions' slope over the run, within ± q/2 (the slope of 2 µm poses at 100 Hz has a std
  /// of 6.4e-6 m/s over 10 samples, 5.7e-7 over 50, against 5.8e-6 for a 2e-5 level): long runs,
  /// which carry the shift, are estimated well. The shift they give is added to D's variance, not
  /// subtracted from D: where the poses and the twist disagree for another reason (a deflection the
  /// twist does not carry, hil's ACU runs) a correction would be wrong, a wider interval is not.
  /// Shorter runs (smooth motion) change level every few samples and their errors average out.
  /// Rates from the poses (ContactData::rate_from_poses) have no levels; rotation rates are left out.
  static double level_shift(const ContactData& d, const std::vector<int>& samples) {
    constexpr std::size_t kRun = 10;
    const std::size_t n = d.obs.size();
    std::vector<bool> use(n, samples.empty());
    for (const int k : samples) use[static_cast<std::size_t>(k)] = true;
    const Eigen::Vector3d normal = d.scene.T_world_fp.linear().col(2);
    double S = 0.0, shift = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      if (use[k]) S += static_cast<double>(d.contacts[k].size()) * std::pow(d.v_rate_world[k].dot(normal), 2);
    if (!(S > 0.0)) return 0.0;
    std::vector<double> x(n);
    for (int a = 0; a < 3; ++a) {
      const double q = d.velocity_quantum_m_per_s(a);
      if (d.rate_from_poses[static_cast<std::size_t>(a)] || normal(a) == 0.0) continue;
      for (std::size_t k = 0; k < n; ++k) x[k] = d.kin[k].T_world_ee.translation()(a);
      std::size_t start = 0;
      for (std::size_t k = 0; k < n; ++k) {
        const double level = d.v_rate_world[k](a);
        if (k + 1 < n && d.v_rate_world[k + 1](a) == level) continue;
        // The run [start, k] at one level, against its positions' least-squares slope.
        if (k + 1 - start >= kRun && level != 0.0) {
          double R = 0.0;
          for (std::size_t j = start; j <= k; ++j)
            if (use[j]) R += static_cast<double>(d.contacts[j].size()) * -d.v_rate_world[j].dot(normal);
          // Of v_a (the rate's is -n_a times it), within the level's half quantum where it is known
          // (quantum_of misses it on few sparse levels, and may see a multiple of it there).
          const double raw = level - slope_over(d.obs.t_s, x, start, k);
          const double error = q > 0.0 ? std::clamp(raw, -0.5 * q, 0.5 * q) : raw;
          shift += normal(a) * error * R;
        }
        start = k + 1;
      }
    }
    return shift / S;
  }
  double level_shift_;
};

/// D times the penetration rate on the normal, and on the friction bound when it follows the total normal force.
class Damping : public Injection {
 public:
  Damping(double d, bool friction) : d_(d), friction_(friction) {}
  TruthValues truth() const override { return {{"damping_n_s_per_m", d_}, {"damping_friction", friction_ ? 1.0 : 0.0}}; }
  std::vector<TruthField> file_fields() const override {
    return {{"damping_n_s_per_m", Eigen::MatrixXd::Constant(1, 1, d_), {}, "contact damping, N s/m"}};
  }
  // The simulation clips the total normal force at zero (simulate_with_effects).
  void contact_force(const SimulatedContact& at, ContactForce& f) const override {
    const double rate = -contact_id::relative_velocity(at.scene, at.kin, at.contact.point).dot(at.contact.normal);
    const double damping_n = d_ * rate;
    f.normal_n += damping_n;
    if (friction_) f.friction_normal_n += damping_n;
  }

 private:
  double d_;
  bool friction_;
};

class ContactDamping : public ContactEffect {
 public:
  std::string name() const override { return "contact_damping"; }
  int list_order() const override { return 70; }
  std::string description() const override {
    return "the normal force grows with the penetration rate (and the friction of sliding contacts with it)";
  }
  int layout_order() const override { return 70; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    return inject({{"damping_n_s_per_m", std::abs(r.magnitude(3000, 6000))}});
  }
  /// damping_friction: 1 when the friction bound follows the total normal force (damping included).
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    check_truth_keys(name(), v, {"damping_n_s_per_m", "damping_friction"});
    return std::make_shared<Damping>(truth_value(v, "damping_n_s_per_m"), truth_value(v, "damping_friction") != 0.0);
  }
};

}  // namespace

std::shared_ptr<const Effect> make_contact_damping() { return std::make_shared<ContactDamping>(); }

}  // namespace hil::diagnose
