// nonlinear_stiffness: φ = p - 1, normal force K δ_ref (δ/δ_ref)^p, δ_ref the median interference in
// contact (the friction follows it). Reported as the exponent p, nominal 1.
#include <hil/diagnose/contact_family.hpp>

#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  std::vector<Param> nonlinear() const override { return {{"stiffness_exponent_minus_1", "", 0.1, true, -0.7, 2.0}}; }
  void starts(const ContactSlots& s, const Eigen::VectorXd& zero, std::vector<Eigen::VectorXd>& out) const override {
    for (double e : {-0.3, 0.5}) {
      Eigen::VectorXd x = zero;
      x(s.nonlinear) = e;
      out.push_back(x);
    }
  }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.stiffness_exponent = 1.0 + phi(s.nonlinear);
  }
  void report(const ContactSlots&, bool linear, Eigen::Index, const Fit&, Reported& r) const override {
    if (linear) return;
    r.name = "stiffness_exponent";
    r.value += 1.0;
    r.nominal = 1.0;
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "stiffness_exponent" && !(q.value > 0) ? "the stiffness exponent is not positive" : "";
  }
};

class NonlinearStiffness : public ContactEffect {
 public:
  std::string name() const override { return "nonlinear_stiffness"; }
  std::string description() const override { return "the normal force is a power of the interference (Hertz-like)"; }
  int layout_order() const override { return 30; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
  bool injectable() const override { return true; }
  bool present(const Effects& e) const override { return e.stiffness_exponent != 1.0; }
  void draw(unsigned seed, const contact_id::Scene&, Effects& e) const override {
    EffectDraw r(seed, name());
    e.stiffness_exponent = 1.0 + std::abs(r.magnitude(0.25, 0.5));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_nonlinear_stiffness() { return std::make_shared<NonlinearStiffness>(); }

}  // namespace hil::diagnose
