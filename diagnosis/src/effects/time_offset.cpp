// time_offset: the wrench stream lags the pose stream by τ (s); the model is evaluated on the poses
// interpolated at t - τ (windowed sinc, ContactFamily::kinematics_at). A delay has local minima at
// multiples of the excitation's period: a grid of starts over the bounds precedes LM.
#include <hil/diagnose/contact_family.hpp>

#include <algorithm>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactData& d) : dt_((d.obs.t_s.back() - d.obs.t_s.front()) / static_cast<double>(d.obs.size() - 1)) {
    const double lim = std::max(20 * dt_, 0.1);
    param_ = {"time_offset_s", "s", dt_, true, -lim, lim};
  }
  std::vector<Param> nonlinear() const override { return {param_}; }
  // Over the bounds, and every quarter sample within ± 3 samples: where the motion steps (a robot's
  // moves and stops), friction turns at the step, and the cost steps as a delayed instant crosses
  // one; LM does not cross such steps, so it must start between the right ones (issue 32: a fold
  // started at one sample stayed there, 2 ms off, and mispredicted a yaw reversal's whole moment).
  void starts(const ContactSlots& s, const Eigen::VectorXd& zero, std::vector<Eigen::VectorXd>& out) const override {
    const auto add = [&](double tau) {
      Eigen::VectorXd x = zero;
      x(s.nonlinear) = tau;
      out.push_back(x);
    };
    for (int i = -20; i <= 20; ++i)
      if (i != 0) add(param_.upper * i / 20.0);
    for (int i = -12; i <= 12; ++i)
      if (i != 0 && i % 4 != 0) add(dt_ * i / 4.0);
  }
  bool moves_contacts() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.delay_s = phi(s.nonlinear);
    if (c.delay_s != 0.0) c.recompute = true;
  }

 private:
  double dt_;
  Param param_;
};

/// The generator's wrench stream lags the poses: interpolated at t - τ.
class Delay : public ScalarInjection {
 public:
  explicit Delay(double tau_s) : ScalarInjection("time_offset_s", tau_s, "delay of the wrench, s") {}
  void channels(const contact_id::Scene&, SimulationChannels& c) const override { c.delay_s = value(); }
};

class TimeOffset : public ContactEffect {
 public:
  std::string name() const override { return "time_offset"; }
  int list_order() const override { return 30; }
  std::string description() const override { return "the wrench stream is delayed against the pose stream"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::deflection; }
  int layout_order() const override { return 40; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b.data); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    return inject({{"time_offset_s", r.magnitude(0.015, 0.04)}});
  }
  // To first order a damping force D δ̇ is the normal force D/K earlier: on a smooth normal motion
  // (a sum of sines) the two differ only in second-order amplitude and in the tangential forces.
  std::string separating_experiment(const std::string& other) const override {
    if (other == "contact_damping")
      return "a normal motion whose speed changes abruptly (piecewise-linear presses with stops): damping steps the force at each "
             "kink of the penetration rate, a delay only shifts the kink; or lift-offs, where damping's pull is clipped and a delay's "
             "is not";
    if (other == "viscous_friction")
      return "slides at constant speed in both directions with stops: viscous friction holds while sliding, a delay only shows where "
             "the force changes";
    return "";
  }
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    check_truth_keys(name(), v, {"time_offset_s"});
    return std::make_shared<Delay>(truth_value(v, "time_offset_s"));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_time_offset() { return std::make_shared<TimeOffset>(); }

}  // namespace hil::diagnose
