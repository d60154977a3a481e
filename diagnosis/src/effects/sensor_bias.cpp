// sensor_bias: b per plate component (N, N m), added to the prediction. A constant offset is not known
// better than the bias quantisation can leave in a mean, whatever the number of samples: the step
// over √12 when nothing dithers the quantiser, far less when the sensor's noise does
// (ContactData::quantisation_bias_variance; before 2026-12-01 always step/√12, which made the
// intervals of the blind suite over motion families 10 times too wide at 0.1 N noise on 0.1 N steps).
#include <hil/diagnose/contact_family.hpp>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactData& d) : d_(d) {}
  std::vector<Param> linear() const override {
    std::vector<Param> p;
    for (std::size_t c = 0; c < 6; ++c) p.push_back({"bias_" + d_.obs.component[c], d_.obs.unit[c], 1, true});
    return p;
  }
  void finish(const ContactSlots& s, const Eigen::VectorXd&, Eigen::MatrixXd& A) const override {
    const auto n = static_cast<Eigen::Index>(d_.obs.size());
    for (Eigen::Index k = 0; k < n; ++k)
      for (int c = 0; c < 6; ++c) A(6 * k + c, s.linear + c) = 1.0;
  }
  double added_variance(bool linear, Eigen::Index j) const override { return linear ? d_.quantisation_bias_variance(j) : 0.0; }

 private:
  const ContactData& d_;
};

/// The plate reads a constant too much per component.
class Bias : public Injection {
 public:
  explicit Bias(const hil::Vector6d& b) : b_(b) {}
  TruthValues truth() const override { return by_component("bias_", b_); }
  std::vector<TruthField> file_fields() const override { return {{"sensor_bias", b_, {}, "fx fy fz (N), mx my mz (N m)"}}; }
  void sensor(hil::Vector6d& w) const override { w += b_; }

 private:
  hil::Vector6d b_;
};

class SensorBias : public ContactEffect {
 public:
  std::string name() const override { return "sensor_bias"; }
  int list_order() const override { return 40; }
  std::string description() const override { return "the force plate has a constant offset per component"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::stiffness; }
  int layout_order() const override { return 80; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b.data); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    TruthValues v;
    for (int c = 0; c < 6; ++c)
      v[std::string("bias_") + kWrenchComponents[static_cast<std::size_t>(c)]] = c < 3 ? r.magnitude(3.0, 8.0) : r.magnitude(0.3, 0.8);
    return inject(v);
  }
  /// Keys bias_<component>, N or N m.
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    return std::make_shared<Bias>(per_component(name(), "bias_", v));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_sensor_bias() { return std::make_shared<SensorBias>(); }

}  // namespace hil::diagnose
