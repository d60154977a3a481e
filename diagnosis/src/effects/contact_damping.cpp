// contact_damping: D, μ_D D (N s/m), per contact a normal force D δ̇ e_n (δ̇ = -v_rel·e_n, the
// penetration rate) and per sliding contact a friction force μ_D D δ̇ e_t. In Kelvin-Voigt /
// Hunt-Crossley contact the friction bound follows the total normal force, damping included; its own
// coefficient (0 when the friction follows the elastic force only) keeps the family separable.
#include <hil/diagnose/contact_family.hpp>

#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  std::vector<Param> linear() const override {
    return {{"damping_n_s_per_m", "N s/m", 100, true}, {"damping_friction_n_s_per_m", "N s/m", 100, true}};
  }
  bool needs_rates() const override { return true; }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    const auto& T = at.data.scene.T_world_fp;
    const double rate = -contact_id::relative_velocity(at.data.scene, at.rate_kinematics, c.point).dot(c.normal);
    rows.col(s.linear) += plate_wrench_of(T, rate * c.normal, c.point);
    rows.col(s.linear + 1) += plate_wrench_of(T, rate * c.tangent, at.friction_point);  // zero while sticking
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
