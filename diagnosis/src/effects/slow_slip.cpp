// slow_slip: friction where the rig declares the contacts sticking. Below the declared sticking
// threshold v_t,m the nominal model predicts no friction (the contact paper's choice: the slip
// direction of a contact that sticks is noise). A foot that slides slowly through a stop (a yaw
// ramp on a trapezoidal profile) still bears Coulomb friction, and the run's residual then
// follows the stops (issue 32: clean trapezoidal runs said `unexplained`, mz up to 23 noise
// variances, because the truth's friction acts down to 1 µm/s against a declared 0.1 mm/s).
// Per contact whose slip speed is in (0, v_t,m]: μ_s K δ_e e_s, e_s = -v_t / |v_t| the measured
// slip direction; θ = μ_s K. A slow slip of the nominal model's own friction reads μ_s = μ; true
// sticking (static friction, whose direction is not the noise's) reads μ_s ~ 0.
#include <hil/diagnose/contact_family.hpp>

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace hil::diagnose {
namespace {

constexpr const char* kMuK = "slow_slip_mu_k_n_per_m";

class Term : public ContactTerm {
 public:
  Term(double v_tm, std::size_t samples, double twist_step_m_per_s)
      : v_tm_(v_tm), samples_(samples), twist_step_m_per_s_(twist_step_m_per_s) {}
  std::vector<Param> linear() const override { return {{kMuK, "N/m", 1e4, true}}; }
  void contact_columns(const ContactSlots& s, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const override {
    const auto& c = at.contact;
    if (!c.tangent.isZero() || !(c.slip_speed > 0.0) || c.slip_speed > v_tm_) return;  // sliding: the nominal μK's
    rows.col(s.linear) += plate_wrench_of(at.data.scene.T_world_fp, at.elastic_delta_m * c.slip_direction, at.friction_point);
  }
  /// μ_s / μ = θ_s / (μK) with its std by the delta method (informative: the PNR checks θ_s).
  void report_derived(const ContactSlots& s, Eigen::Index, const Fit& f, std::vector<Reported>& out) const override {
    const Eigen::Index a = s.linear, m = 1;  // θ = (K, μK, ...): μK is the nominal model's second entry
    const double mk = f.theta(m);
    if (!(std::abs(mk) > 0.0)) return;
    const double r = f.theta(a) / mk;
    const double var = (f.cov(a, a) - 2.0 * r * f.cov(a, m) + r * r * f.cov(m, m)) / (mk * mk);
    out.push_back({"slow_slip_mu_ratio", "", r, std::sqrt(std::max(0.0, var)), false});
  }
  std::string check_line(const Reported& q) const override {
    return q.name == kMuK && q.value < -2.0 * q.std ? fmt::format("{} = {:.4g} ± {:.2g} is negative", q.name, q.value, q.std) : "";
  }
  /// How to read μ_s / μ on this run: the reported twist's step beside the threshold says whether
  /// sliding contacts can read below it.
  std::string note() const override {
    return fmt::format("slow_slip acts on {} samples slipping below the declared sticking threshold ({:.3g} mm/s; twist step {}): "
                       "μ_s/μ near 1, they slide with their friction (declare it lower); well below 1, some stick or are misread",
                       samples_, 1e3 * v_tm_,
                       twist_step_m_per_s_ > 0.0 ? fmt::format("{:.3g} mm/s", 1e3 * twist_step_m_per_s_) : std::string("none seen"));
  }

 private:
  double v_tm_;
  std::size_t samples_;
  double twist_step_m_per_s_;
};

class SlowSlip : public ContactEffect {
 public:
  std::string name() const override { return "slow_slip"; }
  int list_order() const override { return 65; }
  std::string description() const override {
    return "friction acts where the rig declares the contacts sticking: they slide below the declared threshold, or the "
           "measured slip reads them below it (μ_s/μ says which)";
  }
  int layout_order() const override { return 65; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override {
    const double v_tm = b.data.v_tm;
    auto slow = [&](std::size_t k) {
      for (const auto& c : b.data.contacts[k])
        if (c.slip_speed > 0.0 && c.slip_speed <= v_tm) return true;
      return false;
    };
    std::size_t n = 0;
    if (b.samples.empty())
      for (std::size_t k = 0; k < b.data.contacts.size(); ++k) n += slow(k) ? 1 : 0;
    for (const int k : b.samples) n += slow(static_cast<std::size_t>(k)) ? 1 : 0;
    if (n == 0)
      throw std::runtime_error(fmt::format("slow_slip: no contact slips below the declared sticking threshold ({:.3g} mm/s) on this run",
                                           1e3 * v_tm));
    return std::make_shared<Term>(v_tm, n, b.data.velocity_quantum_m_per_s.maxCoeff());
  }
  std::string separating_experiment(const std::string& other) const override {
    (void)other;
    return "a run that holds still in contact and then slides slowly (well below the declared sticking threshold, then above it)";
  }
};

}  // namespace

std::shared_ptr<const Effect> make_slow_slip() { return std::make_shared<SlowSlip>(); }

}  // namespace hil::diagnose
