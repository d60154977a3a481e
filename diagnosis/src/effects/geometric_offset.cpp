// geometric_offset: the contact features are shifted or turned from their design. φ: the rig's
// observable feature uncertainties x_u - x_u^d (m, rad); the contacts are recomputed by mindist.
#include <hil/diagnose/contact_family.hpp>

#include <stdexcept>

namespace hil::diagnose {
namespace {

class Term : public ContactTerm {
 public:
  explicit Term(const ContactData& d) : d_(d) {
    if (d.fit_uncertainties.empty()) throw std::runtime_error("geometric_offset: the rig declares no observable feature uncertainty");
    for (int j : d.fit_uncertainties) {
      const auto& u = d.scene.uncertainties[static_cast<std::size_t>(j)];
      const bool rot = u.kind == contact_id::Uncertainty::Kind::rotation;
      const double s = u.prior_std > 0 ? u.prior_std : (rot ? 1e-3 : 1e-4);
      params_.push_back({u.name, rot ? "rad" : "m", s, true, -50 * s, 50 * s});
    }
  }
  std::vector<Param> nonlinear() const override { return params_; }
  bool moves_contacts() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    for (std::size_t j = 0; j < d_.fit_uncertainties.size(); ++j)
      c.x(d_.fit_uncertainties[j]) += phi(s.nonlinear + static_cast<Eigen::Index>(j));
    c.recompute = true;
  }
  void report(const ContactSlots&, bool linear, Eigen::Index j, const Fit&, Reported& r) const override {
    if (linear) return;
    // Reported as the feature's value, its design value the nominal.
    const auto& u = d_.scene.uncertainties[static_cast<std::size_t>(d_.fit_uncertainties[static_cast<std::size_t>(j)])];
    r.value += u.design_value;
    r.nominal = u.design_value;
  }

 private:
  const ContactData& d_;
  std::vector<Param> params_;
};

/// The features at true values of their uncertainties (by name; the others as the scene's truth has them).
class Features : public Injection {
 public:
  explicit Features(TruthValues x) : x_(std::move(x)) {}
  TruthValues truth() const override { return x_; }
  /// The file's "geometric": every uncertainty's true value (none when absent: the scene's truth stays).
  std::vector<TruthField> file_fields() const override {
    if (x_.empty()) return {};
    TruthField f{"geometric",
                 Eigen::MatrixXd(static_cast<Eigen::Index>(x_.size()), 1),
                 {},
                 "true value of each geometric uncertainty by name (those absent stay at their design value), m or rad"};
    for (const auto& [name, value] : x_) {
      f.value(static_cast<Eigen::Index>(f.labels.size()), 0) = value;
      f.labels.push_back(name);
    }
    return {f};
  }
  void channels(const contact_id::Scene& scene, SimulationChannels& c) const override { set_uncertainties(scene, x_, c.x); }

 private:
  TruthValues x_;
};

class GeometricOffset : public ContactEffect {
 public:
  std::string name() const override { return "geometric_offset"; }
  int list_order() const override { return 10; }
  std::string description() const override { return "the contact features are shifted or turned from their design (x_u)"; }
  int layout_order() const override { return 10; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b.data); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene& scene) const override {
    EffectDraw r(seed, name());
    if (scene.uncertainties.empty()) throw std::invalid_argument("geometric_offset: the rig declares no uncertainties");
    // Like the contact paper's hidden truth: shifts of 1-2 prior std, rotations of 1-2e-4 rad.
    TruthValues v;
    for (const auto& q : scene.uncertainties) {
      const bool rot = q.kind == contact_id::Uncertainty::Kind::rotation;
      const double s = rot ? 1e-4 : (q.prior_std > 0 ? q.prior_std : 1e-4);
      v[q.name] = q.design_value + r.magnitude(1.0, 2.0) * s;
    }
    return inject(v);
  }
  /// Keys: the scene's uncertainties by name, their true values (checked against the scene when simulated).
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override { return std::make_shared<Features>(v); }
};

}  // namespace

std::shared_ptr<const Effect> make_geometric_offset() { return std::make_shared<GeometricOffset>(); }

}  // namespace hil::diagnose
