// sensor_gain: γ_c per plate component but the reference, w_meas,c = (1 + γ_c) w_c. The reference is
// the component with the largest measured signal: its gain is absorbed by K.
#include <hil/diagnose/contact_family.hpp>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  Term(const ContactData& d, const std::vector<int>& samples) : d_(d) {
    Eigen::Index ref = 0;
    hil::Vector6d energy = hil::Vector6d::Zero();
    for (int k : samples) energy += d.obs.y.row(k).transpose().cwiseProduct(d.obs.weight).cwiseAbs2();
    energy.maxCoeff(&ref);
    reference_ = static_cast<int>(ref);
  }
  std::vector<Param> nonlinear() const override {
    std::vector<Param> p;
    for (int c = 0; c < 6; ++c)
      if (c != reference_) p.push_back({"gain_" + d_.obs.component[static_cast<std::size_t>(c)], "", 0.01, true, -0.5, 0.5});
    return p;
  }
  void finish(const ContactSlots& s, const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const override {
    const auto n = static_cast<Eigen::Index>(d_.obs.size());
    Eigen::Index g = s.nonlinear;
    for (int c = 0; c < 6; ++c) {
      if (c == reference_) continue;
      const double scale = 1.0 + phi(g++);
      for (Eigen::Index k = 0; k < n; ++k) A.row(6 * k + c) *= scale;
    }
  }
  bool derives_from_data() const override { return true; }

 private:
  const ContactData& d_;
  int reference_ = 2;
};

class SensorGain : public ContactEffect {
 public:
  std::string name() const override { return "sensor_gain"; }
  std::string description() const override { return "the force plate's scale differs between components"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::stiffness; }
  int layout_order() const override { return 50; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b.data, b.samples); }
  bool injectable() const override { return true; }
  bool present(const Effects& e) const override { return !e.sensor_gain.isZero(); }
  void draw(unsigned seed, const contact_id::Scene&, Effects& e) const override {
    EffectDraw r(seed, name());
    // The tangential forces and the tilting moments; the dominant normal component's gain is
    // indistinguishable from K, so it stays the reference.
    for (int c : {0, 1, 3, 4}) e.sensor_gain(c) = r.magnitude(0.08, 0.15);
  }
};

}  // namespace

std::shared_ptr<const Effect> make_sensor_gain() { return std::make_shared<SensorGain>(); }

}  // namespace hil::diagnose
