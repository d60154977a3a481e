// time_offset: the wrench stream lags the pose stream by τ (s); the model is evaluated on the poses
// interpolated at t - τ (windowed sinc, ContactFamily::kinematics_at). A delay has local minima at
// multiples of the excitation's period: a grid of starts over the bounds precedes LM.
#include <hil/diagnose/contact_family.hpp>

#include <algorithm>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactData& d) {
    const double dt = (d.obs.t_s.back() - d.obs.t_s.front()) / static_cast<double>(d.obs.size() - 1);
    const double lim = std::max(20 * dt, 0.1);
    param_ = {"time_offset_s", "s", dt, true, -lim, lim};
  }
  std::vector<Param> nonlinear() const override { return {param_}; }
  void starts(const ContactSlots& s, const Eigen::VectorXd& zero, std::vector<Eigen::VectorXd>& out) const override {
    for (int i = -20; i <= 20; ++i) {
      if (i == 0) continue;
      Eigen::VectorXd x = zero;
      x(s.nonlinear) = param_.upper * i / 20.0;
      out.push_back(x);
    }
  }
  bool moves_contacts() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.delay_s = phi(s.nonlinear);
    if (c.delay_s != 0.0) c.recompute = true;
  }

 private:
  Param param_;
};

class TimeOffset : public ContactEffect {
 public:
  std::string name() const override { return "time_offset"; }
  std::string description() const override { return "the wrench stream is delayed against the pose stream"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::deflection; }
  int layout_order() const override { return 40; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b.data); }
  bool injectable() const override { return true; }
  bool present(const Effects& e) const override { return e.time_offset_s != 0; }
  void draw(unsigned seed, const contact_id::Scene&, Effects& e) const override {
    EffectDraw r(seed, name());
    e.time_offset_s = r.magnitude(0.015, 0.04);
  }
};

}  // namespace

std::shared_ptr<const Effect> make_time_offset() { return std::make_shared<TimeOffset>(); }

}  // namespace hil::diagnose
