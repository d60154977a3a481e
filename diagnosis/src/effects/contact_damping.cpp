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

class ContactDamping : public ContactEffect {
 public:
  std::string name() const override { return "contact_damping"; }
  std::string description() const override {
    return "the normal force grows with the penetration rate (and the friction of sliding contacts with it)";
  }
  int layout_order() const override { return 70; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
  bool injectable() const override { return true; }
  bool present(const Effects& e) const override { return e.damping_n_s_per_m != 0; }
  void draw(unsigned seed, const contact_id::Scene&, Effects& e) const override {
    EffectDraw r(seed, name());
    e.damping_n_s_per_m = std::abs(r.magnitude(3000, 6000));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_contact_damping() { return std::make_shared<ContactDamping>(); }

}  // namespace hil::diagnose
