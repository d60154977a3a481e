// time_offset: the wrench stream lags the pose stream by τ (s); the model is evaluated on the poses
// interpolated at t - τ (windowed sinc, ContactFamily::kinematics_at). A delay has local minima at
// multiples of the excitation's period: a grid of starts over the bounds precedes LM. Where the
// motion steps, the cost steps too, and the starts go to the plateaus between (below).
#include <hil/diagnose/contact_family.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactData& d) : dt_((d.obs.t_s.back() - d.obs.t_s.front()) / static_cast<double>(d.obs.size() - 1)) {
    const double lim = std::max(20 * dt_, 0.1);
    param_ = {"time_offset_s", "s", dt_, true, -lim, lim};
    crossings_ = delay_crossings(d, -lim, lim, kMerge * dt_);
  }
  std::vector<Param> nonlinear() const override { return {param_}; }
  // Over the bounds, and every quarter sample within ± 3 samples. Where the motion steps (a robot's
  // moves and stops), friction turns at the step, and the cost steps as a delayed instant crosses
  // one (delay_crossings); LM does not cross such steps, so it must start between the right ones:
  // each start is moved to the middle of its plateau, and then (starts_near) every plateau within
  // ± 1 sample of the best start is tried (issue 32: a fold started at one sample stayed there, 2 ms
  // off, and mispredicted a yaw reversal's whole moment; a start on a whole sample sits on the
  // steps the clipped placements put there, and the 0.45 ms plateau that held a 19.3 ms delay lay
  // between two quarter samples). Every plateau within ± 3 samples at once: 4 times the designs.
  void starts(const ContactSlots& s, const Eigen::VectorXd& zero, std::vector<Eigen::VectorXd>& out) const override {
    std::vector<double> tau;
    for (int i = -20; i <= 20; ++i)
      if (i != 0) tau.push_back(param_.upper * i / 20.0);
    for (int i = -12; i <= 12; ++i)
      if (i != 0 && i % 4 != 0) tau.push_back(dt_ * i / 4.0);
    if (!crossings_.empty())
      for (double& t : tau) t = middle(plateau(t));
    add(s, zero, tau, out);
  }
  void starts_near(const ContactSlots& s, const Eigen::VectorXd& best, std::vector<Eigen::VectorXd>& out) const override {
    const double at = best(s.nonlinear);
    std::vector<double> tau;
    for (std::size_t i = 0; i + 1 < crossings_.size(); ++i) {
      const double m = 0.5 * (crossings_[i] + crossings_[i + 1]);
      if (std::abs(m - at) <= dt_) tau.push_back(m);
    }
    add(s, best, tau, out);
  }
  bool moves_contacts() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    c.delay_s = phi(s.nonlinear);
    if (c.delay_s != 0.0) c.recompute = true;
  }
  // Between two crossings the delayed twist does not step, so what locates τ within its plateau
  // is only the poses' smooth part: the plateau's width, as a uniform uncertainty (w / √12), is
  // added to the interval (at a crossing itself, both neighbours').
  void report(const ContactSlots& s, bool linear, Eigen::Index, const Fit& f, Reported& r) const override {
    if (linear || crossings_.empty()) return;
    const auto [lo, hi] = plateau(f.phi(s.nonlinear), true);
    r.std = std::hypot(r.std, (hi - lo) / std::sqrt(12.0));
  }

 private:
  static constexpr double kMerge = 1e-3;  ///< crossings closer than this many samples are one
  /// The crossings around τ: [lo, hi) holds τ. `across`: where τ lies on a crossing (within the
  /// merge distance), both neighbouring plateaus' span.
  std::pair<double, double> plateau(double tau, bool across = false) const {
    const auto it = std::upper_bound(crossings_.begin(), crossings_.end(), tau);
    double lo = it == crossings_.begin() ? param_.lower : *(it - 1);
    double hi = it == crossings_.end() ? param_.upper : *it;
    if (across && it != crossings_.begin() && tau - lo < kMerge * dt_) lo = it - 1 == crossings_.begin() ? param_.lower : *(it - 2);
    if (across && it != crossings_.end() && hi - tau < kMerge * dt_) hi = it + 1 == crossings_.end() ? param_.upper : *(it + 1);
    return {lo, hi};
  }
  static double middle(std::pair<double, double> p) { return 0.5 * (p.first + p.second); }
  /// `base` with this term's τ set to each of `tau` (sorted, duplicates once).
  static void add(const ContactSlots& s, const Eigen::VectorXd& base, std::vector<double> tau, std::vector<Eigen::VectorXd>& out) {
    std::sort(tau.begin(), tau.end());
    tau.erase(std::unique(tau.begin(), tau.end()), tau.end());
    for (const double t : tau) {
      Eigen::VectorXd x = base;
      x(s.nonlinear) = t;
      out.push_back(x);
    }
  }
  double dt_;
  Param param_;
  std::vector<double> crossings_;  ///< delay_crossings over the bounds
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
