#pragma once
/// \file The contact model family of the diagnosis: the nominal surface-compliance model (contact
/// paper eq. 2-7, θ = (K, μK)) and its candidate extensions, and the hidden-effect generator that
/// injects the same effects into a simulation.
///
/// Each extension is one effect (contact_effect.hpp), one file in diagnosis/src/effects/, registered
/// in the effect registry (effect.hpp); the family composes the effects it is built with. Their
/// parameterisations: docs/diagnosis.md, "Candidate causes".
/// Pure numerics on hil::contact_id: no I/O.
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <hil/contact_id/identification.hpp>
#include <hil/contact_id/model.hpp>
#include <hil/diagnose/contact_effect.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/diagnose/effect.hpp>
#include <hil/diagnose/engine.hpp>

namespace hil::diagnose {

namespace cid = hil::contact_id;
using hil::Matrix6d;
using hil::Vector6d;

/// The candidate causes of the contact family, in the order they are reported: the registered
/// effects that extend it (effect_names(FamilyKind::contact)).
const std::vector<std::string>& contact_extensions();
/// One sentence on what each extension means physically (the registry's Effect::description; "none"
/// too; empty for an unknown name).
std::string describe_extension(const std::string& name);

/// The measured run in the form the contact family needs.
struct ContactData {
  cid::Scene scene;
  double v_tm = 1e-3;                                    ///< sticking threshold, m/s
  std::vector<cid::Kinematics> kin;                      ///< measured ee pose and twist per sample
  Observations obs;                                      ///< plate wrench (fp frame, about the fp origin)
  std::vector<std::vector<cid::ContactPoint>> contacts;  ///< per sample, nominal geometry and measured pose
  double delta_ref_m = 1e-4;                             ///< median interference in contact (nonlinear_stiffness)
  std::vector<int> fit_uncertainties;                    ///< observable x_u (geometric_offset fits these)
  std::vector<std::string> unfit_uncertainties;          ///< and why the others are not fitted
  std::size_t samples_in_contact = 0;
  /// Per plate component, the sensor's quantisation step seen in the data (0: not quantised).
  Vector6d resolution = Vector6d::Zero();
  /// Per plate component, the variance of the bias quantisation can leave in a constant offset,
  /// whatever the number of samples (quantisation_bias_variance): step²/12 without dither, far less
  /// when the sensor's noise dithers the quantiser.
  Vector6d quantisation_bias_variance = Vector6d::Zero();
  /// The plate's calibration tolerance (format::ForcePlateDeviceSpec::gain_tolerance): a
  /// `sensor_gain` fit whose gain lies beyond it by more than two std is not physical.
  double plate_gain_tolerance = 0.15;
  /// The ee's linear velocity (world) contact_damping takes its penetration rates from, per sample.
  /// Per axis either the reported twist or, where both streams are quantised and the reported
  /// twist's step is the coarser noise, the least-squares slope of the reported positions over
  /// ± kRateHalfWindow samples (docs/diagnosis.md, "Penetration rates").
  std::vector<Eigen::Vector3d> v_rate_world;
  /// Per linear axis, whether v_rate_world is the pose slope (true) or the reported twist.
  std::array<bool, 3> rate_from_poses{false, false, false};
  /// Per linear axis, the quanta seen in the reported positions and twist (0: not quantised).
  Eigen::Vector3d position_quantum_m = Eigen::Vector3d::Zero(), velocity_quantum_m_per_s = Eigen::Vector3d::Zero();
  /// Per linear axis, the pose slope's estimated mean square error over the twist's (NaN: not compared).
  Eigen::Vector3d rate_mse_ratio = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// Per interval [t_k, t_k+1] (n - 1 of them), where the reported linear and angular velocities
  /// and the penetration rates step (rate_steps: the fraction of the interval, NaN where they vary
  /// smoothly). A robot's piecewise-linear moves and stops: time_offset's delayed twist steps there,
  /// not halfway, nor with a windowed sinc's ringing. Empty: nothing steps.
  std::vector<double> v_step, w_step, rate_step;
  /// One line on where the penetration rates come from, for the report.
  std::string rate_source() const;
};

/// A jump of a sampled rate is a change over kStepRatio times the changes of both neighbouring
/// intervals and over kStepFloor times the larger of the rate's quantum and the median change.
/// Why these: on a smooth rate the ratio of neighbouring changes stays near 1 (at most about 1 where
/// the acceleration crosses zero), and quantised or noisy rates change by a quantum or a noise std.
constexpr double kStepRatio = 4.0, kStepFloor = 6.0;

/// At most this many samples on each side of a step place it (rate_steps).
constexpr int kStepSpan = 8;

/// Where a sampled rate steps (a robot's piecewise-linear move, a start, a stop): per interval j =
/// [t_j, t_j+1], the fraction of the interval at which rate jumps from rate[j] to rate[j+1], or NaN
/// where it varies smoothly. The fraction is placed so that rate[j] until the step and rate[j+1]
/// after it integrate to the change of what `rate` is the rate of (the position, the rotation
/// vector) across the interval, as the increments of up to kStepSpan intervals on each side predict
/// it (the trapezoidal integral of the rate bridges them), by least squares, clipped to [0, 1].
/// \param quantum the rate's quantisation step (norm over components; 0: none).
/// \param increment_quantum the quantisation step of what is integrated (0: none).
/// \pre t_s increasing; sizes n, n, n - 1.
std::vector<double> rate_steps(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& rate,
                               const std::vector<Eigen::Vector3d>& increment, double quantum, double increment_quantum);

/// The delays τ in [lower_s, upper_s] at which a delayed sample instant t_k - τ crosses a placed step
/// of the twist or the penetration rates (ContactData::v_step, w_step, rate_step), or a sample
/// instant while the run has steps (there the delayed twist switches between its step-aware and
/// its sinc interpolation): sorted, crossings closer than merge_s merged into their mean. Between
/// two neighbours time_offset's cost is smooth; at each it may step (docs/diagnosis.md, "Delay
/// plateaus"). Empty when nothing steps. \pre the steps' sizes n - 1 or 0, t_s increasing.
std::vector<double> delay_crossings(const ContactData& d, double lower_s, double upper_s, double merge_s);

/// Half-width of the pose slope's window, samples: measured on the blind suite (± 4 leaves the
/// damping 2 std low at the fine resolution, ± 8 within 1.5 std at both).
constexpr int kRateHalfWindow = 8;

/// The step of a quantised signal: the coarsest grid holding every distinct value and zero (else,
/// an offset signal, every distinct value) whose step is the smallest gap between them or a
/// fraction 1/k of it (k <= 10; k > 1 needs 5 distinct values). A signal that takes few, sparse
/// levels may show a multiple of its quantiser's step (the step divides it), or none. 0: fewer
/// than max(3, min_levels) distinct values, not on such a grid, or a non-finite value.
double quantum_of(std::vector<double> values, std::size_t min_levels = 3);

/// A first-order low-pass filter y' = (x - y) / τ applied along the samples to every column of A
/// (rows: c per sample, sample after sample; c = rows / t_s.size()), in place, the input linear
/// between samples (exact for it). The first sample starts settled; τ <= 0 leaves A as it is.
/// \throws std::invalid_argument when the rows are not a multiple of the samples.
void first_order_lag(const std::vector<double>& t_s, double tau_s, Eigen::Ref<Eigen::MatrixXd> A);

/// The variance of the bias a quantiser of `step` leaves in the mean of a signal dithered by
/// Gaussian noise of std σ, over an unknown position of the signal on the grid: the quantiser's
/// mean error is the Fourier series Σ_k (-1)^k (step/πk) e^{-2π²k²σ²/step²} sin(2πk x/step)
/// (Widrow and Kollár, Quantization Noise, 2008, ch. 4-5), whose mean square over x is
/// Σ_k step²/(2π²k²) e^{-4π²k²σ²/step²}: step²/12 at σ = 0, 3e-19 step² at σ = step. 0 when step is 0.
double quantisation_bias_variance(double step, double sigma);
/// The same with σ estimated from `series` (the quantised samples in time order): from the mean
/// square of its second differences (a slow signal cancels), the largest tenth left out (a jump
/// spoils a few, not the estimate; the Gaussian's trimmed second moment corrected for), less the
/// quantisation's own step²/12. Conservative where σ is below step/4 (it sees less dither than
/// there is) and on a series without second differences (σ = 0).
double quantisation_bias_variance(const std::vector<double>& series, double step);

/// The probability that a contact found at interference δ (m) along the unit normal n touches in
/// truth, when the reported ee positions are quantised per world axis by `quantum_m` (0: exact).
/// Berkson's error: a position that spans many steps lies anywhere within its reported step, so
/// the true interference is δ + Σ_i n_i e_i, e_i uniform over ± q_i / 2. The axis with the largest
/// |n_i| q_i is taken exactly (uniform), the others as a Gaussian of their variance (the exact
/// convolution for one axis, within a few 1e-3 for three): s/(2h) [G((δ+h)/s) - G((δ-h)/s)],
/// G(u) = u Φ(u) + φ(u), h = |n_j| q_j / 2; 1 (0) at δ beyond (below) the errors' reach Σ|n_i| q_i / 2.
/// A force that exists only while a foot touches and does not vanish with δ (viscous friction)
/// jumps at lift-off; the quantum then decides a few samples' contact at random, and such a column
/// read at the reported pose is biased by O(q) (docs/diagnosis.md, "The viscous coefficient's
/// trapezoidal bias"). Weighted by this probability its least squares is not.
double touching_probability(double delta_m, const Eigen::Vector3d& normal, const Eigen::Vector3d& quantum_m);

/// Per sample, the least-squares slope of x over the samples within ± half_window of it (clipped at
/// the ends of the run), against the sample times. \pre t increasing, t.size() == x.size().
std::vector<double> windowed_slope(const std::vector<double>& t_s, const std::vector<double>& x, int half_window);

/// The least-squares slope of x against t over the samples lo..hi (0 when their times do not
/// differ). \pre lo <= hi < t.size() == x.size().
double slope_over(const std::vector<double>& t_s, const std::vector<double>& x, std::size_t lo, std::size_t hi);

/// Where contact_damping's penetration rates come from (ContactData::v_rate_world).
enum class RateSource {
  automatic,  ///< per axis, the pose slope where it is estimated to have less error than the twist
  twist,      ///< the reported twist (a simulation whose twist is exact)
  poses,      ///< the pose slope on every axis
};

/// One axis's penetration-rate source (ContactData::v_rate_world).
struct RateChoice {
  std::vector<double> v_m_per_s;  ///< per sample: the pose slope or the reported velocity
  bool from_poses = false;
  double position_quantum_m = 0.0, velocity_quantum_m_per_s = 0.0;  ///< 0: not quantised
  /// The slope's estimated mean square error (noise + smoothing bias) over the twist's bound q_v²/12
  /// (NaN: not compared; the slope is taken below 0.5 when the twist's error is seen at its bound).
  double mse_ratio = std::numeric_limits<double>::quiet_NaN();
};

/// Chooses, for one axis, between the reported velocity and the slope of the reported positions
/// over ± half_window samples (docs/diagnosis.md, "Penetration rates").
/// \throws std::invalid_argument on mismatched sizes, fewer than 2 samples, half_window < 2, a
/// non-finite value or times that do not increase (naming the sample).
RateChoice choose_rate(const std::vector<double>& t_s, const std::vector<double>& x_m, const std::vector<double>& v_m_per_s,
                       RateSource rates = RateSource::automatic, int half_window = kRateHalfWindow);

/// \param force_scale_n, moment_scale_nm the weights' scales (0: the largest measured component).
/// \throws std::runtime_error if no sample brings the objects into contact.
ContactData make_contact_data(const cid::Scene& scene, double v_tm, const std::vector<cid::Measurement>& m, double force_scale_n = 0.0,
                              double moment_scale_nm = 0.0, RateSource rates = RateSource::automatic);

/// The run's signals the residual analysis looks for structure against (per sample: speed,
/// acceleration, interference, penetration_rate, slip_speed, load, time, px py pz, vx vy vz in W)
/// and each sample's contact state ("2 contacts, sliding", "no contact").
Context contact_context(const ContactData& d);

/// The nominal contact model with a set of extensions. Immutable once built and shared by every
/// thread: when the contacts depend on φ (geometric_offset, robot_compliance, time_offset), the
/// scratch and the last evaluation's contacts a design reuses are its evaluator's (make_data()).
class ContactFamily : public ModelFamily {
 public:
  ContactFamily(const ContactData& d, std::set<std::string> extensions);
  /// \param samples the samples the data-derived choices (robot_compliance's identifiable
  /// directions, sensor_gain's reference component) are made from (empty: all).
  ContactFamily(const ContactData& d, std::set<std::string> extensions, const std::vector<int>& samples);
  std::string name() const override;
  std::vector<Param> linear() const override { return linear_; }
  std::vector<Param> nonlinear() const override { return nonlinear_; }
  std::vector<Eigen::VectorXd> starts() const override;
  std::vector<Eigen::VectorXd> starts_near(const Eigen::VectorXd& best) const override;
  std::unique_ptr<FamilyData> make_data() const override;
  using ModelFamily::design;
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData& data) const override;
  std::vector<Reported> report(const Fit& f) const override;
  /// K > 0, μ >= 0, c_v >= 0, D >= 0 (each within two standard deviations), p > 0, and a positive
  /// semi-definite compliance.
  std::string check(const Fit& f) const override;
  /// Its effects' notes on this run (ContactTerm::note), in the registry's order.
  std::vector<std::string> notes() const;
  /// With robot_compliance or sensor_gain: the family with its basis and references chosen from `train`.
  std::unique_ptr<ModelFamily> restricted(const std::vector<int>& train) const override;
  /// Where the friction acts is a model form the data rarely decide: hil's contact point is the
  /// centroid of the interference, a real contact's friction acts at its surface or, on a point
  /// foot, at the tip. The two alternatives put the tangential forces' line of action ± 3δ/4 along
  /// the normal from the centroid: a convex interference's centroid lies between 1/4 and 3/4 of its
  /// depth from either side (Grünbaum), so that range holds every point of the interference on the
  /// normal through the centroid (docs/diagnosis.md, "Model-form intervals").
  /// With time_offset, a third form: the wrench's lag a pure delay τ_d (time_offset_s) followed
  /// by a first-order low-pass filter of time constant τ_f >= 0 (kLagFilter; a sensor's
  /// anti-aliasing filter), both fitted; it reports time_offset_s as the chain's low-frequency
  /// group delay τ_d + τ_f, the pure delay's meaning. Where the force steps (friction reversing at a
  /// robot's corners) a filter's step response is read as a pure delay of only τ_f ln 2
  /// (docs/diagnosis.md, "A filter's lag instead of a pure delay"). The form nests the model
  /// (τ_f = 0), so its refit fits at least as well; one that does not has failed and is rejected
  /// (ModelForm::decided_by_fit).
  /// With contact_damping, a fourth: Hunt-Crossley's dashpot instead of a linear one, the damping
  /// force D (δ/δ̄) δ̇ (and the friction's share likewise), no force at first touch and the most at
  /// the deepest point. δ̄ is the run's interference weighted by the squared penetration rates,
  /// Σ δ δ̇² / Σ δ̇² over its contacts, so that the form's D is the linear dashpot that matches
  /// its damping force best on this run: the two forms report the same quantity. They differ where
  /// the feet lift off (the linear dashpot's force is clipped there, Hunt-Crossley's vanishes):
  /// a linear fit of a Hunt-Crossley contact read D 2-4 % high (docs/diagnosis.md, "Hunt-Crossley
  /// damping"). The run often tells the two apart: a form that fits worse is rejected
  /// (ModelForm::decided_by_fit), and one it prefers gives the values (taken_when_preferred):
  /// widening alone left Hunt-Crossley runs' D 2-4 % high inside their intervals.
  std::vector<ModelForm> model_forms() const override;
  /// The reported ee positions, per world axis whose quantum the run shows (ContactData::
  /// position_quantum_m): an error uniform over the step, std step / √12. The interference is
  /// the plate's height less the ee's, so that error attenuates K and moves the plate's height
  /// (by mean δ var(e) / var(δ): +0.4 std over the family suite at 2 µm, +1.3 at 8 µm;
  /// docs/diagnosis.md, "Errors in the variables"). The orientation and the twist are not included,
  /// nor an axis the run holds (more than kHeldShare of its samples in runs of kHoldSamples or more
  /// equal reported values: there the error is one offset per hold, not a spread over the step).
  std::vector<ErrorInVariable> errors_in_variables() const override;
  /// The plate's two groups: fz, mx and my carry the normal force, fx, fy and mz the friction
  /// (docs/diagnosis.md, "The plate's two groups of components"). A delay carried by one stop's
  /// friction torque was read 32 std off while the normal group alone read the truth (issue 32).
  std::vector<ComponentGroup> component_groups() const override { return {{"fz, mx, my", {2, 3, 4}}, {"fx, fy, mz", {0, 1, 5}}}; }
  static constexpr std::size_t kHoldSamples = 10;
  static constexpr double kHeldShare = 0.25;
  /// κ: the tangential forces act at the centroid + κ δ e_n (0: the contact paper's model).
  double friction_lever() const { return friction_lever_; }
  /// Whether φ ends with kLagFilter, the time constant of a first-order filter after the delay.
  bool has_lag_filter() const { return lag_filter_; }
  /// δ̄ of the Hunt-Crossley form (0: a linear dashpot, the family's own form).
  double damping_depth_m() const { return damping_depth_m_; }
  /// Whether slow_slip's friction follows the elastic force only with contact_damping in the model
  /// (a model form; the family's own: the total normal force, damping included).
  bool slow_friction_elastic() const { return slow_friction_elastic_; }
  static constexpr const char* kLagFilter = "time_offset_filter_s";
  /// The model form whose slow contacts' friction follows the elastic force only (Score::model_form_taken begins with it when taken).
  static constexpr const char* kSlowFrictionElasticForm = "the slow contacts' friction on the elastic force only, not the damping's";
  const std::set<std::string>& extensions() const { return ext_; }
  /// The measured kinematics at time t (time_offset's pose at t - τ): windowed-sinc (Lanczos, 8
  /// lobes) interpolation of the samples, which keeps a quantised pose stream's noise level at every
  /// fraction of a sample (docs/diagnosis.md); exact at the samples, the ends held beyond the run.
  cid::Kinematics kinematics_at(double t) const;

 private:
  struct PairTable;
  /// One effect of the family, bound to the run, and where its parameters sit.
  struct Bound {
    std::shared_ptr<const ContactTerm> term;
    ContactSlots slots;
    int report_rank = 0;  ///< its position among the family's effects in the registry's order
  };
  /// The nominal model with `terms` (already bound; `names`: their effects'), e.g. robot_compliance's
  /// design on every symmetric direction while it chooses its identifiable ones.
  ContactFamily(const ContactData& d, std::vector<std::shared_ptr<const ContactTerm>> terms, std::set<std::string> names,
                std::shared_ptr<const PairTable> pairs);
  ContactFamily(const ContactData& d, std::set<std::string> extensions, const std::vector<int>& samples,
                std::shared_ptr<const PairTable> pairs);
  void add_terms(std::vector<Bound> terms);
  bool has(const std::string& e) const { return ext_.count(e) > 0; }
  /// \param v_rate the ee's linear velocity the damping's penetration rates take (ContactData::v_rate_world).
  /// \param ch the stiffness law's exponent and the damping's time D / K.
  void columns(const std::vector<cid::ContactPoint>& cs, const cid::Kinematics& k, const Eigen::Vector3d& v_rate, const ContactChannels& ch,
               Eigen::Ref<Eigen::MatrixXd> out) const;
  /// The Lanczos weights of kinematics_at: the window's first sample and its weights (taps 0: the
  /// sample `first` itself). Fixed storage: one is made per sample of every design under a delay.
  struct SincWeights {
    static constexpr int kMaxTaps = 16;
    std::ptrdiff_t first = 0;
    int taps = 0;
    std::array<double, kMaxTaps> h{};
    std::ptrdiff_t interval = 0;  ///< t lies in [t_interval, t_interval+1) ...
    double fraction = 0.0;        ///< ... at this fraction of it
  };
  /// A velocity at t near a step of it (ContactData::v_step and the like) in sw's window: linear
  /// between the samples v0, v1 around t, or v0 before and v1 after the step when the step lies in
  /// their interval. Empty when no step lies in the window (the sinc's value holds there).
  static std::optional<Eigen::Vector3d> velocity_near_step(const std::vector<double>& steps, const SincWeights& sw,
                                                           const Eigen::Vector3d& v0, const Eigen::Vector3d& v1);
  SincWeights sinc_weights(double t) const;
  Eigen::Vector3d rate_velocity_at(const SincWeights& w) const;
  cid::Kinematics kinematics_at(const SincWeights& w) const;
  const ContactData& d_;
  /// The data d_ refers to when the family made it itself (errors_in_variables' shifted poses).
  std::shared_ptr<const ContactData> owned_;
  std::vector<int> samples_;  ///< the samples its data-derived choices come from (empty: all)
  std::set<std::string> ext_;
  std::vector<Param> linear_, nonlinear_;
  /// The effects in their parameters' layout order (ContactEffect::layout_order): designs, reports
  /// and checks go through them in it; starts in the registry's order (report_rank).
  std::vector<Bound> terms_;
  std::vector<int> linear_owner_, nonlinear_owner_;  ///< per θ / φ entry: its term (-1: nominal)
  bool moves_contacts_ = false, needs_rates_ = false;
  double friction_lever_ = 0.0;
  bool lag_filter_ = false;
  double damping_depth_m_ = 0.0;
  bool slow_friction_elastic_ = false;

  // Contacts recomputed for φ (docs/diagnosis.md, "Cost"). mindist on every pair of every sample is
  // what a design costs; most pairs are provably apart or unchanged, and are skipped:
  //  * pruning: a pair that was gap_m apart under the design geometry and the measured pose stays
  //    apart while its polyhedra move by less than that in total (the features by x_u - x_u^d, the
  //    held body with the ee pose);
  //  * finite differences: only the pairs of features whose transform differs from the last
  //    evaluation with the same ee poses (the base) are recomputed, the others copied from it.
  // Both give exactly mindist's contacts, in its order.
  struct NearPair {
    int poly1, poly2;  ///< flattened polyhedron indices in object 1 and 2
    double gap_m;      ///< lower bound on their distance at the design geometry (-inf: interfering)
  };
  struct PairTable {
    std::vector<std::vector<NearPair>> near;                ///< per sample, pairs closer than kReach_m
    std::array<std::vector<std::pair<int, int>>, 2> index;  ///< flattened polyhedron -> (feature, polyhedron)
    std::array<std::vector<double>, 2> radius_m;            ///< farthest vertex from the body origin (design)
  };
  /// Feature transforms at x and how far each polyhedron moved from the design geometry.
  struct Geometry {
    Eigen::VectorXd x;
    std::array<std::vector<Eigen::Isometry3d>, 2> T_body_feature;
    std::array<std::vector<double>, 2> moved_m;  ///< per flattened polyhedron
    std::array<std::vector<bool>, 2> changed;    ///< per feature: differs from the base
  };
  struct Base {
    bool valid = false;
    double tau_s = 0.0;
    Matrix6d C = Matrix6d::Zero();
    std::array<std::vector<Eigen::Isometry3d>, 2> T_body_feature;
    std::vector<std::vector<cid::ContactPoint>> contacts;  ///< per sample
    std::vector<bool> full;                                ///< per sample: by full mindist (not from the table)
  };
  struct Scratch {
    cid::MindistWorkspace ws;
    std::array<std::vector<cid::PosedPolyhedron>, 2> posed;
    std::array<std::vector<char>, 2> done;
  };
  /// One evaluator's: the base a finite difference steps from and the scratch of mindist.
  struct Data : FamilyData {
    Base base;
    Scratch scratch;
  };
  static constexpr double kReach_m = 5e-3;  ///< pairs farther apart are not tabled: beyond, full mindist
  std::shared_ptr<const PairTable> pairs_;
  static std::shared_ptr<const PairTable> make_pairs(const ContactData& d);
  /// \param base the evaluator's base (Geometry::changed is against it; invalid: every feature changed).
  Geometry geometry_at(const Eigen::VectorXd& x, const Base& base) const;
  /// mindist's contacts of sample k at the ee pose of `kin`; `base`: that sample's contacts in the
  /// base (same ee pose), reused for the pairs of unchanged features. Returns false when it ran full mindist.
  bool sample_contacts(std::size_t k, const cid::Kinematics& kin, const Geometry& g, const std::vector<cid::ContactPoint>* base,
                       std::vector<cid::ContactPoint>& out, Scratch& w) const;
};

/// max over z of the smallest eigenvalue of C + Σ z_k N_k (symmetric C, N_k): whether some matrix
/// that agrees with C outside the free directions N_k is positive semi-definite (result >= 0).
/// Subgradient ascent from z = 0 (the function is concave); stops once it is >= 0.
double max_min_eigenvalue(const Matrix6d& C, const std::vector<Matrix6d>& free_directions, int iterations = 2000);

// plate_wrench_of: contact_effect.hpp.

// ---------------------------------------------------------------------------------------------
// The hidden-effect generator.

/// Effects injected into a simulation, each its own Injection (contact_effect.hpp).
struct Effects {
  /// The scene's true feature uncertainties by name before any effect (a truth file's; those absent
  /// are at their design value). geometric_offset's injection replaces them.
  std::map<std::string, double> geometric;
  /// The injected effects by name.
  std::map<std::string, std::shared_ptr<const Injection>> injected;
  /// The effects present, in the registry's order.
  std::vector<std::string> names() const;
  /// The true value of a parameter the diagnosis reports under `name`: an injected effect's, else
  /// a feature uncertainty's (`geometric`, else its design value); none when the test cannot know it.
  std::optional<double> truth_of(const std::string& name, const cid::Scene& scene) const;
};

/// The contact effects the hidden-effect generator can hide (ContactEffect::injectable), in the
/// registry's order: what `hil contact simulate --inject` and `hil demo --effect` accept.
std::vector<std::string> injectable_contact_effects();
/// Draws an effect of the named kind with a seeded random magnitude into `e` (ContactEffect::draw).
/// \throws std::invalid_argument on an unknown or not injectable name.
void draw_effect(const std::string& name, unsigned seed, const cid::Scene& scene, Effects& e);
/// Injects an effect with the given true values into `e` (ContactEffect::inject).
/// \throws std::invalid_argument on an unknown or not injectable name, or a key it does not know.
void inject_effect(const std::string& name, const TruthValues& values, Effects& e);
/// The hidden-effects file's fields of `e`: every injectable effect's, the absent ones at zero
/// magnitude, in the registry's order (a later field of the same key replaces an earlier one).
std::vector<TruthField> truth_file_fields(const Effects& e);

/// Forward simulation with effects: for each true (commanded) kinematics, the plate wrench of the
/// nominal model with each injected effect's part (Injection's hooks, in the effects' layout
/// order); the measured kinematics are the commanded ones (the pose the robot reports). `t_s`
/// gives the times (for a delay); the sensor model quantises and adds noise.
std::vector<cid::SimulatedSample> simulate_with_effects(const cid::Scene& s, const cid::ContactModel& m, const Effects& e,
                                                        const std::vector<double>& t_s, const std::vector<cid::Kinematics>& truth,
                                                        const cid::SensorModel& sensor);

}  // namespace hil::diagnose
