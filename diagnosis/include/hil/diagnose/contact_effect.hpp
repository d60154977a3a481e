#pragma once
/// \file A contact-family effect's model (one file per effect, diagnosis/src/effects/): the parameters
/// it adds (units, scales, bounds), what it writes into the contact geometry (feature offsets, a
/// delay, an ee deflection, the stiffness law), its design columns per contact or per row, its
/// report lines, its physical-validity check, and its injection into the hidden-effect generator
/// (its drawn truth and its part of the forward simulation).
///
/// A ContactEffect (registered, stateless) binds to a run as a ContactTerm: the part of one
/// ContactFamily that is this effect, with the choices it derives from the data (a basis, a
/// reference component). Terms are immutable once bound, so families built from them can be shared.
#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <hil/contact_id/model.hpp>
#include <hil/diagnose/effect.hpp>
#include <hil/diagnose/engine.hpp>
#include <hil/so3/so3.hpp>

namespace hil::diagnose {

struct ContactData;
class ContactTerm;

/// Where a term's parameters start in the family's θ and φ (-1: it has none of that kind).
struct ContactSlots {
  Eigen::Index linear = -1, nonlinear = -1;
};

/// What the terms write from φ into the contact model before the contacts are computed.
struct ContactChannels {
  Eigen::VectorXd x;                                 ///< feature uncertainties x_u (m, rad), from the design
  double delay_s = 0.0;                              ///< the wrench stream's lag behind the poses
  hil::Matrix6d compliance = hil::Matrix6d::Zero();  ///< ee deflection per measured ee wrench (ee frame)
  bool deflect = false;                              ///< the ee pose is deflected by `compliance`
  double stiffness_exponent = 1.0;                   ///< normal force K δ_ref (δ/δ_ref)^p
  /// D / K (s): the normal force K (δ_e + τ_D δ̇)₊, clipped where the foot lifts off (contact_damping)
  double damping_time_s = 0.0;
  bool recompute = false;  ///< the contacts depend on φ: recomputed by mindist
};

/// One contact of one sample, as the per-contact columns see it.
struct ContactAt {
  const ContactData& data;
  const contact_id::ContactPoint& contact;
  const contact_id::Kinematics& rate_kinematics;  ///< the ee's kinematics, linear velocity the penetration-rate one
  const Eigen::Vector3d& friction_point;          ///< where the tangential forces act (world)
  /// The dashpot's factor at this contact: δ / δ̄ in contact_damping's Hunt-Crossley form
  /// (ContactFamily::model_forms), else 1.
  double damping_scale = 1.0;
  /// δ_e: the interference as the stiffness law sees it (δ, or δ_ref (δ/δ_ref)^p), what the nominal
  /// friction column K δ_e e_t scales with
  double elastic_delta_m = 0.0;
  /// The interference the slow contacts' friction bound follows (slow_slip): the total normal
  /// force's, δ_e + τ_D δ̇ (> 0), with contact_damping in the model; δ_e without it, or under the
  /// model form ContactFamily::kSlowFrictionElasticForm.
  double normal_delta_m = 0.0;
};

/// What an effect may use when it binds to a run.
struct ContactBinding {
  const ContactData& data;
  const std::vector<int>& samples;  ///< the samples its data-derived choices are made from (never a fold's held-out block)
  /// A(φ) on every sample of the nominal model extended by `term` alone (its φ alone): e.g. the
  /// Jacobian whose SVD keeps the identifiable directions of a compliance.
  std::function<void(std::shared_ptr<const ContactTerm> term, const Eigen::VectorXd& phi, Eigen::MatrixXd& A)> design_alone;
};

/// One effect bound to a run: the part of a ContactFamily that is this effect. Every hook has a
/// default that does nothing, so an effect writes only what it changes.
class ContactTerm {
 public:
  virtual ~ContactTerm() = default;
  /// θ entries it adds (appended after the nominal K, μK in the effects' layout order).
  virtual std::vector<Param> linear() const { return {}; }
  /// φ entries it adds.
  virtual std::vector<Param> nonlinear() const { return {}; }
  /// Starting points of φ besides 0: `zero` with this term's entries set.
  virtual void starts(const ContactSlots&, const Eigen::VectorXd& zero, std::vector<Eigen::VectorXd>& out) const {
    (void)zero;
    (void)out;
  }
  /// Starting points near the best of the first ones (ModelFamily::starts_near): `best` with this
  /// term's entries changed.
  virtual void starts_near(const ContactSlots&, const Eigen::VectorXd& best, std::vector<Eigen::VectorXd>& out) const {
    (void)best;
    (void)out;
  }
  /// Its contacts depend on φ (geometry, poses or time): the family tables the near pairs.
  virtual bool moves_contacts() const { return false; }
  /// Its columns need the penetration rates (ContactData::v_rate_world, delayed with the poses).
  virtual bool needs_rates() const { return false; }
  virtual void channels(const ContactSlots&, const Eigen::VectorXd& phi, ContactChannels& c) const {
    (void)phi;
    (void)c;
  }
  /// Adds its columns of one contact to the sample's 6 rows (`rows`: 6 x θ).
  virtual void contact_columns(const ContactSlots&, const ContactAt& at, Eigen::Ref<Eigen::MatrixXd> rows) const {
    (void)at;
    (void)rows;
  }
  /// After every sample's contact columns: row scalings or constant columns (6N x θ).
  virtual void finish(const ContactSlots&, const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const {
    (void)phi;
    (void)A;
  }
  /// Adjusts the report line of its `index`-th θ (linear) or φ entry: a derived name, the nominal value, units.
  virtual void report(const ContactSlots&, bool linear, Eigen::Index index, const Fit& f, Reported& r) const {
    (void)linear;
    (void)index;
    (void)f;
    (void)r;
  }
  /// Variance added to its `index`-th θ (linear) or φ entry's asymptotic one (e.g. a resolution's).
  virtual double added_variance(bool linear, Eigen::Index index) const {
    (void)linear;
    (void)index;
    return 0.0;
  }
  /// Derived lines after every parameter's (informative, not PNR-checked).
  virtual void report_derived(const ContactSlots&, Eigen::Index theta_size, const Fit& f, std::vector<Reported>& out) const {
    (void)theta_size;
    (void)f;
    (void)out;
  }
  /// Physical validity of one reported line (empty: valid), asked for every line in report order.
  virtual std::string check_line(const Reported& q) const {
    (void)q;
    return "";
  }
  /// Physical validity of the whole fit, after every line's (empty: valid).
  virtual std::string check(const ContactSlots&, Eigen::Index theta_size, const Fit& f) const {
    (void)theta_size;
    (void)f;
    return "";
  }
  /// It derives choices from the data: a fold's family rebinds it on its training samples.
  virtual bool derives_from_data() const { return false; }
  /// What a reader needs to read its values on this run (e.g. what sensor_gain's gains are relative
  /// to), shown with the run's notes. Empty: nothing.
  virtual std::string note() const { return ""; }
};

// ---------------------------------------------------------------------------------------------
// Injection: the hidden-effect generator's forward simulation (simulate_with_effects), as an effect
// writes its part of it. The generator's own terms are the nominal model's: K δ e_n + μ K δ e_t per
// contact at the scene's true geometry and the commanded poses; an effect adds to them.

/// True values by key: the names the diagnosis reports the effect's parameters under (bias_fz,
/// time_offset_s, C_x_x, an uncertainty's name) and the effect's settings (e.g. damping_friction).
using TruthValues = std::map<std::string, double>;

/// One field of the hidden-effects file (docs/schemas/hil.hidden_effects.schema.json): a number
/// (1 x 1), an array (n x 1), an array of rows (n x m) or, with `labels`, an object label -> value.
struct TruthField {
  std::string key;
  Eigen::MatrixXd value;
  std::vector<std::string> labels;
  std::string description;  ///< what it is, with its units (the schema's description)
};

/// What the forward simulation takes from the effects before it computes the contacts.
struct SimulationChannels {
  Eigen::VectorXd x;                                 ///< the scene's true feature uncertainties (m, rad)
  hil::Matrix6d compliance = hil::Matrix6d::Zero();  ///< ee deflection per ee wrench (ee frame): T = T_cmd Exp(C w_ee)
  double delay_s = 0.0;                              ///< the wrench stream's lag behind the poses
};

/// One contact of the forward simulation.
struct SimulatedContact {
  const contact_id::Scene& scene;
  const contact_id::Kinematics& kin;  ///< the true (deflected) ee kinematics
  const contact_id::ContactPoint& contact;
};

/// The force of one contact as the effects build it: (K δ_e + normal_n) e_n + (μ (K δ_e +
/// friction_normal_n) + tangential_n) e_t, with δ_e the interference the stiffness law sees; none
/// where K δ_e + normal_n <= 0 (a contact pushes, it never pulls: damping at lift-off).
struct ContactForce {
  double delta_m = 0.0;            ///< δ_e: the interference, or what a stiffness law makes of it
  double normal_n = 0.0;           ///< added normal force (e.g. damping)
  double friction_normal_n = 0.0;  ///< added to the normal force the friction bound follows
  double tangential_n = 0.0;       ///< added tangential force (e.g. viscous friction)
};

/// One injected effect: its drawn truth and its part of the forward simulation. Immutable; every
/// hook has a default that does nothing.
class Injection {
 public:
  virtual ~Injection() = default;
  /// Its true values (TruthValues' keys).
  virtual TruthValues truth() const = 0;
  /// Its fields of the hidden-effects file (none: it writes none, e.g. an absent geometric offset).
  virtual std::vector<TruthField> file_fields() const = 0;
  /// The geometry, deflection and delay it changes.
  virtual void channels(const contact_id::Scene& scene, SimulationChannels& c) const {
    (void)scene;
    (void)c;
  }
  /// Its part of one contact's force (in the effects' layout order).
  virtual void contact_force(const SimulatedContact& at, ContactForce& f) const {
    (void)at;
    (void)f;
  }
  /// The sensor's reading of the (delayed) true plate wrench, in place (gains before biases: the layout order).
  virtual void sensor(hil::Vector6d& w) const { (void)w; }
};

/// An injection whose truth is one number, under the same key in TruthValues and in the file.
class ScalarInjection : public Injection {
 public:
  ScalarInjection(std::string key, double value, std::string description)
      : key_(std::move(key)), value_(value), description_(std::move(description)) {}
  TruthValues truth() const override { return {{key_, value_}}; }
  std::vector<TruthField> file_fields() const override { return {{key_, Eigen::MatrixXd::Constant(1, 1, value_), {}, description_}}; }
  double value() const { return value_; }

 private:
  std::string key_;
  double value_;
  std::string description_;
};

/// The plate's wrench components in their order, as the diagnosis names them (bias_fx, gain_mz, ...).
inline constexpr std::array<const char*, 6> kWrenchComponents{"fx", "fy", "fz", "mx", "my", "mz"};

/// `values`' entry `key`, or `fallback` when it has none.
double truth_value(const TruthValues& values, const std::string& key, double fallback = 0.0);
/// \throws std::invalid_argument naming `effect` and the first key of `values` not in `known`.
void check_truth_keys(const std::string& effect, const TruthValues& values, const std::vector<std::string>& known);
/// Per wrench component, `values`' entry `<prefix><component>` (bias_fx ... bias_mz; 0 where absent).
/// \throws std::invalid_argument naming `effect` on any other key.
hil::Vector6d per_component(const std::string& effect, const std::string& prefix, const TruthValues& values);
/// The inverse of per_component: `<prefix><component>` -> w(c).
TruthValues by_component(const std::string& prefix, const hil::Vector6d& w);
/// Sets the entries of x (the scene's uncertainties, in order) named in `by_name`.
/// \throws std::invalid_argument on a name the scene does not declare.
void set_uncertainties(const contact_id::Scene& scene, const TruthValues& by_name, Eigen::VectorXd& x);

/// A contact-family effect: its registry entry and the model it binds.
class ContactEffect : public Effect {
 public:
  bool extends(FamilyKind family) const override { return family == FamilyKind::contact; }
  const ContactEffect* contact() const override { return this; }
  /// The order of its parameters in θ and φ, lowest first: the collinearity check takes columns in
  /// this order, so an effect earlier in it keeps a parameter a later one is collinear with.
  virtual int layout_order() const { return 1000; }
  /// \throws std::runtime_error when the run cannot have it (e.g. no observable feature uncertainty).
  virtual std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const = 0;
  /// The hidden-effect generator: its injection with a seeded random magnitude, sized to stand well
  /// above the sensor's resolution on the scene.
  /// \throws std::invalid_argument when it cannot be injected (default: not injectable).
  virtual std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene& scene) const;
  /// Its injection with the given true values (keys it does not know: std::invalid_argument; keys
  /// left out: absent, e.g. inject({}) is the effect at zero magnitude).
  virtual std::shared_ptr<const Injection> inject(const TruthValues& values) const;
  virtual bool injectable() const { return false; }
};

/// The generator's seeded random source for one effect (each effect draws from its own stream).
class EffectDraw {
 public:
  EffectDraw(unsigned seed, const std::string& name) : rng_(seed * 7919ULL + std::hash<std::string>{}(name)) {}
  double uniform() { return u_(rng_); }
  double sign() { return u_(rng_) < 0.5 ? -1.0 : 1.0; }
  /// A signed magnitude in [lo, hi): the sign drawn first.
  double magnitude(double lo, double hi) {
    const double s = sign();
    return s * (lo + (hi - lo) * u_(rng_));
  }

 private:
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
};

/// The wrench on the plate (fp frame, about the fp origin) of a force f (world) applied to object 1
/// at the point p (world): the plate feels -f at p.
hil::Vector6d plate_wrench_of(const Eigen::Isometry3d& T_world_fp, const Eigen::Vector3d& f_world, const Eigen::Vector3d& p_world);

}  // namespace hil::diagnose
