// viscous_friction: c_v (N s/m), per sliding contact a tangential force c_v |v_t| e_t.
#include <hil/diagnose/contact_family.hpp>

#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  std::vector<Param> linear() const override { return {{"viscous_n_s_per_m", "N s/m", 100, true}}; }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, c.slip_speed * c.tangent, at.friction_point);
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "viscous_n_s_per_m" && q.value < -2.0 * q.std ? q.name + " = " + std::to_string(q.value) + " is negative" : "";
  }
};

class ViscousFriction : public ContactEffect {
 public:
  std::string name() const override { return "viscous_friction"; }
  std::string description() const override { return "the friction force grows with the sliding speed"; }
  int layout_order() const override { return 60; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
  bool injectable() const override { return true; }
  bool present(const Effects& e) const override { return e.viscous_n_s_per_m != 0; }
  void draw(unsigned seed, const contact_id::Scene&, Effects& e) const override {
    EffectDraw r(seed, name());
    e.viscous_n_s_per_m = std::abs(r.magnitude(4000, 8000));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_viscous_friction() { return std::make_shared<ViscousFriction>(); }

}  // namespace hil::diagnose
