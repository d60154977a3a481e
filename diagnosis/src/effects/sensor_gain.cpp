// sensor_gain: γ_c per plate component but its references, w_meas,c = (1 + γ_c) w_c. A common scale
// of all six components is K's and μK's: the component with the largest measured signal is a
// reference. On a level plate the components also fall in two groups: fz, mx and my carry the
// normal force (K), fx, fy and mz the friction (μK), and a common scale of the friction group is
// μ's; there each group has a reference (its largest signal), and the other gains are relative to
// their group's. Fitted free, that scale was a near-null direction the fits wandered along to the
// search bound (CI draw 32,602,004: fx, fy and mz at -0.48 to -0.5 for true relative gains under
// 3 %, the folds split between that and the truth), and a friction that falls with speed read as
// it (Stribeck: fx and fy -0.19, mz -0.38).
#include <hil/diagnose/contact_family.hpp>

#include <fmt/format.h>

#include <array>
#include <cmath>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  Term(const ContactBinding& b) : d_(b.data) {
    const ContactData& d = b.data;
    const std::vector<int>& samples = b.samples;
    hil::Vector6d energy = hil::Vector6d::Zero();
    for (int k : samples) energy += d.obs.y.row(k).transpose().cwiseProduct(d.obs.weight).cwiseAbs2();
    auto largest = [&](const std::array<int, 3>& group) {
      int best = group[0];
      for (int c : group)
        if (energy(c) > energy(best)) best = c;
      return best;
    };
    // The friction group's common scale is μ's only where the normal force loads none of fx, fy and
    // mz and the friction none of fz, mx and my: on a level plate (the tripod's runs: shares of
    // 1e-34 and 1e-6 of the K and μK columns' weighted energy). A V-guide's tilted faces load fx
    // with the normal force (ACU 2a: 0.33-0.43) and a friction above the plate's origin loads my
    // (the press bench: 0.73); there fx's gain is seen apart from μ, and fixing it pushed its
    // misfit into the others (ACU 2a draw 13: gain_my -0.167 ± 0.009 for -0.089). 1e-3: orders of
    // magnitude from both.
    Eigen::MatrixXd A;
    b.design_alone(std::make_shared<const ContactTerm>(), Eigen::VectorXd(), A);
    double k_all = 0.0, k_friction = 0.0, mu_all = 0.0, mu_normal = 0.0;
    for (int k : samples)
      for (int c = 0; c < 6; ++c) {
        const double aK = d.obs.weight(c) * A(6 * k + c, 0), aMu = d.obs.weight(c) * A(6 * k + c, 1);
        k_all += aK * aK;
        mu_all += aMu * aMu;
        if (friction(c)) k_friction += aK * aK;
        else mu_normal += aMu * aMu;
      }
    constexpr double kShare = 1e-3;
    if (k_friction <= kShare * k_all && mu_normal <= kShare * mu_all) {
      references_ = {largest(kNormalGroup), largest(kFrictionGroup)};
    } else {
      Eigen::Index ref = 0;
      energy.maxCoeff(&ref);
      references_ = {static_cast<int>(ref), -1};
    }
  }
  static bool friction(int c) { return c == 0 || c == 1 || c == 5; }
  bool reference(int c) const { return c == references_[0] || c == references_[1]; }
  std::vector<Param> nonlinear() const override {
    std::vector<Param> p;
    for (int c = 0; c < 6; ++c)
      if (!reference(c)) p.push_back({"gain_" + d_.obs.component[static_cast<std::size_t>(c)], "", 0.01, true, -0.5, 0.5});
    return p;
  }
  void finish(const ContactSlots& s, const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const override {
    const auto n = static_cast<Eigen::Index>(d_.obs.size());
    Eigen::Index g = s.nonlinear;
    for (int c = 0; c < 6; ++c) {
      if (reference(c)) continue;
      const double scale = 1.0 + phi(g++);
      for (Eigen::Index k = 0; k < n; ++k) A.row(6 * k + c) *= scale;
    }
  }
  bool derives_from_data() const override { return true; }
  std::string note() const override {
    const auto& c = d_.obs.component;
    const auto& r0 = c[static_cast<std::size_t>(references_[0])];
    if (references_[1] < 0)
      return fmt::format("sensor_gain's gains are relative to {}, the largest signal (their common scale is K's; the friction's "
                         "common scale is seen apart from μ on this run)",
                         r0);
    return fmt::format("sensor_gain's gains are relative to {} and {}, the largest signals of the normal force's components "
                       "(fz, mx, my: their common scale is K's) and of the friction's (fx, fy, mz: μ's)",
                       r0, c[static_cast<std::size_t>(references_[1])]);
  }
  // A calibrated plate's components agree in scale to a few percent (ATI states 1-2 % of full
  // scale per axis): a run that needs one component tens of percent off is explained by something
  // else (friction that falls with speed reads as fx and fy scaled down against mz), or the plate
  // is misconfigured, which the lab must fix, not the diagnosis absorb.
  // Checked on the reported std only (once the folds' spread is in it; std_folds is 0 in the
  // candidates' screen): a gain the folds cannot pin down (a component with little signal on this
  // run) is no evidence of a miscalibrated plate. Screened on the asymptotic std, the CI draw
  // 32,602,004 (moves, true gains under 5 %) had its gain_fx read -0.486 ± 0.095 and refused.
  std::string check_line(const Reported& q) const override {
    if (q.name.rfind("gain_", 0) != 0 || q.std_folds == 0.0) return "";
    if (!(std::abs(q.value) - 2.0 * q.std > d_.plate_gain_tolerance)) return "";
    return fmt::format("{} = {:.3f} ± {:.3f} is beyond the plate's calibration tolerance ± {:.2f} (force_plate.gain_tolerance)", q.name,
                       q.value, q.std, d_.plate_gain_tolerance);
  }

 private:
  static constexpr std::array<int, 3> kNormalGroup{2, 3, 4}, kFrictionGroup{0, 1, 5};
  const ContactData& d_;
  std::array<int, 2> references_{2, 0};
};

/// The plate reads (1 + γ_c) w_c per component.
class Gain : public Injection {
 public:
  explicit Gain(const hil::Vector6d& g) : g_(g) {}
  TruthValues truth() const override { return by_component("gain_", g_); }
  std::vector<TruthField> file_fields() const override {
    return {{"sensor_gain", g_, {}, "γ per component: the plate reads (1 + γ) w (0 = none)"}};
  }
  void sensor(hil::Vector6d& w) const override { w = w.cwiseProduct(hil::Vector6d::Ones() + g_); }

 private:
  hil::Vector6d g_;
};

class SensorGain : public ContactEffect {
 public:
  std::string name() const override { return "sensor_gain"; }
  int list_order() const override { return 50; }
  std::string description() const override { return "the force plate's scale differs between components"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::stiffness; }
  int layout_order() const override { return 50; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    // The tangential forces and the tilting moments; the dominant normal component's gain is
    // indistinguishable from K, so it stays the reference.
    TruthValues v;
    for (int c : {0, 1, 3, 4}) v[std::string("gain_") + kWrenchComponents[static_cast<std::size_t>(c)]] = r.magnitude(0.08, 0.15);
    return inject(v);
  }
  /// Keys gain_<component>: γ, the plate reads (1 + γ) w.
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    return std::make_shared<Gain>(per_component(name(), "gain_", v));
  }
};

}  // namespace

std::shared_ptr<const Effect> make_sensor_gain() { return std::make_shared<SensorGain>(); }

}  // namespace hil::diagnose
