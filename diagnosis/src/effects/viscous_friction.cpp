// viscous_friction: c_v (N s/m), per sliding contact a tangential force c_v |v_t| e_t.
// The force does not vanish with the interference: it jumps where a foot lifts off, and there the
// reported positions' quantum decides the contact at random. The column is weighted by the
// probability that the contact touches (touching_probability): read at the reported pose it read
// c_v 0.13 % low on trapezoidal moves, whose normal motion lingers near lift-off (docs/diagnosis.md).
#include <hil/diagnose/contact_family.hpp>

#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  std::vector<Param> linear() const override { return {{"viscous_n_s_per_m", "N s/m", 100, true}}; }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    const double touching = touching_probability(c.delta, c.normal, at.data.position_quantum_m);
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, touching * c.slip_speed * c.tangent, at.friction_point);
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "viscous_n_s_per_m" && q.value < -2.0 * q.std ? q.name + " = " + std::to_string(q.value) + " is negative" : "";
  }
};

/// c_v times the slip speed along each contact's tangent.
class Viscous : public ScalarInjection {
 public:
  explicit Viscous(double cv) : ScalarInjection("viscous_n_s_per_m", cv, "viscous friction coefficient, N s/m") {}
  void contact_force(const SimulatedContact& at, ContactForce& f) const override { f.tangential_n += value() * at.contact.slip_speed; }
};

class ViscousFriction : public ContactEffect {
 public:
  std::string name() const override { return "viscous_friction"; }
  int list_order() const override { return 60; }
  std::string description() const override { return "the friction force grows with the sliding speed"; }
  int layout_order() const override { return 60; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    return inject({{"viscous_n_s_per_m", std::abs(r.magnitude(4000, 8000))}});
  }
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    check_truth_keys(name(), v, {"viscous_n_s_per_m"});
    return std::make_shared<Viscous>(truth_value(v, "viscous_n_s_per_m"));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_viscous_friction() { return std::make_shared<ViscousFriction>(); }

}  // namespace hil::diagnose
