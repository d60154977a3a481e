// contact_damping: per contact the normal force K (δ_e + τ_D δ̇)₊ (δ̇ = -v_rel·e_n, the penetration
// rate; D = K τ_D, reported in N s/m) and per sliding contact a friction force μ_D D δ̇ e_t. The
// normal force is clipped at zero: a foot withdrawing faster than its elastic force allows pushes
// nothing and does not pull, nor bears friction (Hunt-Crossley; issue 32 measured D 2 % low, z
// −3.6, when the model let it pull). The clip makes τ_D a nonlinear parameter: which contacts
// bear force depends on it. In Kelvin-Voigt / Hunt-Crossley contact the friction bound follows the
// total normal force, damping included; its own coefficient (0 when the friction follows the
// elastic force only) keeps the family separable.
#include <hil/diagnose/contact_family.hpp>

#include <algorithm>
#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  std::vector<Param> linear() const override { return {{"damping_friction_n_s_per_m", "N s/m", 100, true}}; }
  /// τ_D = D / K; ± 1 s bounds ten times any contact's D / K seen (17-40 ms), so a bound is no estimate.
  std::vector<Param> nonlinear() const override { return {{"damping_time_s", "s", 0.01, true, -1.0, 1.0}}; }
  bool needs_rates() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.damping_time_s = phi(s.nonlinear);
  }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    const double rate = -contact_id::relative_velocity(at.data.scene, at.rate_kinematics, c.point).dot(c.normal);
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, rate * c.tangent, at.friction_point);  // zero while sticking
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
    r.std = std::sqrt(std::max(0.0, var));
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "damping_n_s_per_m" && q.value < -2.0 * q.std ? q.name + " = " + std::to_string(q.value) + " is negative" : "";
  }
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
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
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
