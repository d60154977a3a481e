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

/// The normal force K δ_ref (δ/δ_ref)^p.
class Law : public Injection {
 public:
  Law(double p, double delta_ref_m) : p_(p), ref_(delta_ref_m) {}
  TruthValues truth() const override { return {{"stiffness_exponent", p_}, {"delta_ref_m", ref_}}; }
  std::vector<TruthField> file_fields() const override {
    return {{"stiffness_exponent", Eigen::MatrixXd::Constant(1, 1, p_), {}, "exponent p of the nonlinear contact stiffness (1 = linear)"}};
  }
  void contact_force(const SimulatedContact&, ContactForce& f) const override {
    if (p_ != 1.0) f.delta_m = ref_ * std::pow(f.delta_m / ref_, p_);
  }

 private:
  double p_, ref_;
};

class NonlinearStiffness : public ContactEffect {
 public:
  std::string name() const override { return "nonlinear_stiffness"; }
  int list_order() const override { return 80; }
  std::string description() const override { return "the normal force is a power of the interference (Hertz-like)"; }
  int layout_order() const override { return 30; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<Term>(); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    return inject({{"stiffness_exponent", 1.0 + std::abs(r.magnitude(0.25, 0.5))}});
  }
  /// delta_ref_m: the interference at which the law's force equals the linear one (default 0.1 mm).
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    check_truth_keys(name(), v, {"stiffness_exponent", "delta_ref_m"});
    return std::make_shared<Law>(truth_value(v, "stiffness_exponent", 1.0), truth_value(v, "delta_ref_m", 1e-4));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_nonlinear_stiffness() { return std::make_shared<NonlinearStiffness>(); }

}  // namespace hil::diagnose
