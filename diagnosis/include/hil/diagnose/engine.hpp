#pragma once
/// \file The model-selection engine of the diagnosis: separable model families, their fit by
/// variable projection, blocked cross-validation, information criteria and practical
/// identifiability (parameter-to-noise ratio, stiffness paper eq. 10).
///
/// A model family predicts 6 components per sample (a wrench or a deflection) as A(φ) θ: θ enters
/// linearly (solved by least squares on QR/SVD for each φ), φ nonlinearly (Levenberg-Marquardt on
/// the projected residual, forward-difference Jacobian). Rows are weighted per component (1/scale),
/// so residuals are relative errors. Pure numerics: no I/O.
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace hil::diagnose {

/// The measured outputs: 6 components per sample.
struct Observations {
  std::vector<double> t_s;                                                   ///< sample times, s (increasing)
  Eigen::MatrixXd y;                                                         ///< N x 6, physical units
  Eigen::Matrix<double, 6, 1> weight = Eigen::Matrix<double, 6, 1>::Ones();  ///< 1 / scale per component
  std::vector<std::string> component{"fx", "fy", "fz", "mx", "my", "mz"};
  std::vector<std::string> unit{"N", "N", "N", "N m", "N m", "N m"};
  std::size_t size() const { return t_s.size(); }
};

/// One parameter of a family.
struct Param {
  std::string name;
  std::string unit;
  double scale = 1.0;      ///< typical magnitude: finite-difference steps, LM scaling
  bool extension = false;  ///< belongs to the extension (PNR-checked), not to the nominal model
  /// Bounds. A linear parameter takes only lower = 0 (θ >= 0): held there by the projection and
  /// then fixed, as a nonlinear parameter that ends at a bound is ("ran to its bound").
  double lower = -1e300, upper = 1e300;
};

/// A reported (possibly derived) parameter with its standard deviation.
struct Reported {
  std::string name, unit;
  double value = 0.0, std = 0.0;
  bool extension = false;
  double nominal = 0.0;  ///< the value under the nominal model (the PNR measures the distance from it)
  /// The standard deviation from the spread of the cross-validation folds' estimates (delete-a-block
  /// jackknife, scaled to Student's t of its degrees of freedom); 0: not computed. `std` is the
  /// larger of it and the asymptotic one, unless the sandwich's is taken (`std_sandwich`).
  double std_folds = 0.0;
  /// The block-clustered sandwich's standard deviation (0: not computed), taken as `std` where the
  /// residuals' correlation is short and every fold lies within its reach (docs/diagnosis.md,
  /// "Intervals"); `sandwich` says whether it was.
  double std_sandwich = 0.0;
  bool sandwich = false;
  /// Bell and McCaffrey's degrees of freedom of the sandwich along this value's gradient: how many
  /// blocks' worth of the run its information is spread over (0: not computed).
  double sandwich_dof = 0.0;
  /// Its information sits in fewer than kOneEventDof blocks' worth of a run whose residuals'
  /// correlation is short (at least kSandwichMinBlocks blocks): one event, e.g. a single stop. No
  /// residual-based std (sandwich, folds) has the degrees of freedom to measure its error, and
  /// `std` is the model's, σ² (JᵀJ)⁻¹ inflated, which the residuals cannot check; taken only where
  /// every fold's estimate lies where the model says its block's removal can move it
  /// (kOneEventFoldZ): else the rest of the run knows the value too, and the folds measure it.
  /// Nor where a group of components contradicts it (`std_components`).
  bool model_based = false;
  /// A value carried by one event whose reading by one group of the observation's components alone
  /// (ModelFamily::component_groups) lies beyond what the model allows (kOneEventFoldZ of the
  /// Hausman spread): the model is wrong where one group looks, and which group reads the truth the
  /// run cannot say. This is the std whose ±1.96 reaches across that group's own 95 % interval,
  /// |x_g - x| / 1.96 + s_g; `std` is at least this (0: every group agrees, or not one event's).
  double std_components = 0.0;
  /// The group that contradicts the value and what it reads (empty: none), for the report.
  std::string components_disagree = {};
  /// The asymptotic standard deviation, σ² (JᵀJ)⁻¹ inflated for autocorrelation (0: same as std).
  double std_asymptotic = 0.0;
  /// The model-form part (0: none): the largest shift of the value when the fit is repeated under
  /// the family's alternative assumptions (ModelFamily::model_forms), taken as uniform over ± that
  /// shift (shift / √3). `std` includes it in quadrature; the PNR does not.
  double std_model_form = 0.0;
  /// The correction for errors in the variables already in `value` (ModelFamily::errors_in_variables,
  /// plus a term's own: slow_slip's slip directions): value minus the least-squares estimate's (0: none).
  /// The std is the least-squares estimate's (slow_slip's scaled with its value).
  double errors_in_variables = 0.0;
  /// false: the value's meaning depends on data-derived choices a fold makes anew (e.g. the
  /// coordinates of a compliance basis chosen from its samples), so the folds cannot measure its spread.
  bool fold_comparable = true;
  /// Parameter-to-noise ratio |value - nominal| / std (stiffness paper eq. 10), on the asymptotic
  /// covariance as in the paper: a measure of the design's practical identifiability, used to
  /// screen candidates. The reported interval (std) may be wider.
  double pnr() const {
    const double d = std::abs(value - nominal);
    const double sd = std_asymptotic > 0 ? std_asymptotic : std;
    return sd > 0 ? d / sd : (d != 0 ? 1e300 : 0.0);
  }
};

struct Fit;

/// A quantity a family locates from the data instead of fitting it (e.g. rest_change's event times):
/// reported with the interval where it can be, not a standard deviation.
struct LocatedEvent {
  std::string name;  ///< e.g. event_1_s
  double t_s = 0.0;  ///< where the model puts it
  double lower_s = 0.0, upper_s = 0.0;
  int first_sample = 0;  ///< the first sample (index into the observations) after it
};

/// What one evaluator of a family keeps between its designs: scratch space and caches (Pinocchio's
/// Data to the family's Model). The family itself is immutable once built, so one family serves
/// every thread; each thread designs with its own data (ModelFamily::make_data). A family's data
/// never changes a design's values, only what it costs.
class FamilyData {
 public:
  virtual ~FamilyData() = default;
};

/// A separable model family: prediction = A(φ) θ, 6 rows per sample (row 6k + c).
/// Thread-safe: every member is const and keeps nothing; per-evaluator state lives in FamilyData.
/// A model form the run can decide is rejected when its refit's weighted RSS exceeds the model's by
/// more than this many long-run residual variances: χ² of one degree of freedom at 0.99 (a form
/// that has the model's parameters, or nests it with one more; one that fits worse by that much is
/// the wrong form, or for a nested one a failed refit).
constexpr double kFormRejection = 6.63;

class ModelFamily {
 public:
  virtual ~ModelFamily() = default;
  virtual std::string name() const = 0;
  virtual std::vector<Param> linear() const = 0;
  virtual std::vector<Param> nonlinear() const { return {}; }
  /// Starting points for φ (the best by projected cost starts LM). Default: φ = 0.
  virtual std::vector<Eigen::VectorXd> starts() const;
  /// More starting points near the best of starts() (a finer search where the cost has many flat
  /// steps, e.g. a delay on moves); the best of all starts LM. Default: none.
  virtual std::vector<Eigen::VectorXd> starts_near(const Eigen::VectorXd& best) const {
    (void)best;
    return {};
  }
  /// A fresh workspace for design(), one per evaluator (thread). Default: an empty one.
  virtual std::unique_ptr<FamilyData> make_data() const { return std::make_unique<FamilyData>(); }
  /// A(φ) in physical units, 6N x linear().size(). Must be deterministic, whatever `data` holds.
  /// \param data from this family's make_data(), used by one thread at a time.
  virtual void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData& data) const = 0;
  /// A(φ) with a fresh workspace (one-off designs; an evaluator keeps its data instead).
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const {
    const auto data = make_data();
    design(phi, A, *data);
  }
  /// The parameters people read (e.g. K and μ from θ = (K, μK)); default: θ and φ as they are.
  virtual std::vector<Reported> report(const Fit& f) const;
  /// Physical validity of fitted parameters (e.g. a compliance must be positive semi-definite):
  /// empty when valid, else why not. Default: valid.
  virtual std::string check(const Fit&) const { return ""; }
  /// The same family with every choice it derives from the data (a basis of identifiable
  /// directions, a reference component, event times) made from the samples `train` only: what a
  /// cross-validation fold fits, so that nothing of its held-out block leaks into its prediction.
  /// Its parameters must have the same names. Default: nullptr (the family derives nothing).
  virtual std::unique_ptr<ModelFamily> restricted(const std::vector<int>& train) const {
    (void)train;
    return nullptr;
  }
  /// The family under each alternative assumption the run cannot decide (e.g. where in the
  /// interference the friction acts), the ends of the plausible range: the same parameters, another
  /// model form. score() refits under each and widens the intervals by the shifts
  /// (Reported::std_model_form). Default: none.
  struct ModelForm {
    std::string assumption;
    std::unique_ptr<ModelFamily> model;
    /// The run can tell this form from the family's own (e.g. a filter's lag from a pure delay where
    /// the force steps): it widens the intervals only while its refit's weighted RSS exceeds the
    /// full fit's by at most kFormRejection long-run residual variances (σ² times the variance
    /// inflation). false: the run rarely decides it, always covered.
    bool decided_by_fit = false;
    /// The refit's starts instead of the form's own (ModelFamily::starts), given the model's optimum
    /// mapped to the form's parameters (itself always a start): where a parameter the form adds sits
    /// at a stationary point at its nominal value (a filter's time constant of 0 moves the cost only
    /// to second order), a refit from the optimum stays there. The best of them, then its
    /// starts_near, then Levenberg-Marquardt. Empty function: the form's own starts.
    std::function<std::vector<Eigen::VectorXd>(const Eigen::VectorXd& optimum)> refit_from = {};
    /// Where its refit's weighted RSS falls more than kFormRejection long-run residual variances
    /// below the full fit's, the form's values are reported instead of the model's (the interval,
    /// widened by the shift, still holds the model's reading). Off by default: a form's better fit
    /// on a run whose model is wrong elsewhere too is no evidence for it (the delay's lag form was
    /// preferred by hundreds of variances on pure delays; docs/diagnosis.md, "Forms the run
    /// decides"). For a form the run's other misfits do not pull towards, shown on fresh draws.
    bool taken_when_preferred = false;
    /// With taken_when_preferred: the form's values mean the model's quantities under another
    /// assumption (where the friction acts), so the run's evidence weighs them continuously. The
    /// reported values are the average of the model's and every such form's, weighted by their
    /// likelihoods relative to the model's, exp(-excess / 2) with excess the refit's weighted RSS
    /// less the full fit's in long-run residual variances (equal prior weights: Bayesian model
    /// averaging). A form preferred beyond kFormRejection then carries almost all the weight, as a
    /// taken one does; one preferred by less moves the values part of the way instead of none
    /// (issue 32: on moves, a point foot's lever preferred by 3 variances left the delay on the
    /// centroid's reading, 60-260 µs high; docs/diagnosis.md, "Model-form intervals"). The
    /// intervals are widened as before. A form that is not weighted and is taken replaces the values.
    bool weighted = false;
  };
  virtual std::vector<ModelForm> model_forms() const { return {}; }
  /// A regressor the family takes from a measurement whose error has a known variance (errors in
  /// the variables: e.g. a pose quantised to a known step, whose error is uniform over the step):
  /// the same family with that measurement shifted by a given amount on every sample. Least
  /// squares reads such an error as part of the signal and biases the fit to second order in the
  /// std (a slope attenuated by var(error) / var(regressor)); score() removes that bias
  /// (errors_in_variables_bias). The shifted families must have the family's parameters.
  struct ErrorInVariable {
    std::string variable;  ///< what is measured and how it errs, for the report
    double std = 0.0;      ///< the error's standard deviation, in the variable's unit
    /// The family with the measurement shifted by this much (the variable's unit) on every sample;
    /// called while the family lives.
    std::function<std::unique_ptr<ModelFamily>(double)> shifted;
  };
  /// Default: none (the regressors are exact).
  virtual std::vector<ErrorInVariable> errors_in_variables() const { return {}; }
  /// Groups of the observation's components that see the parameters through different physics
  /// (a plate's normal force in fz, mx and my, the friction in fx, fy and mz). Under the model each
  /// group's rows alone estimate the same values, less precisely; a value carried by one event is
  /// reported on the model's std only where every group's reading agrees with it (Reported::
  /// std_components). Default: none.
  struct ComponentGroup {
    std::string name;             ///< e.g. "fz, mx, my"
    std::vector<int> components;  ///< columns of Observations::y
  };
  virtual std::vector<ComponentGroup> component_groups() const { return {}; }
  /// What the family located from the data on every sample (its effects' Effect::locates_events). Default: none.
  virtual std::vector<LocatedEvent> located_events() const { return {}; }
};

/// A parameter the run cannot determine: fixed at its nominal value (0) and not reported.
struct Unidentifiable {
  std::string name;
  std::string reason;  ///< e.g. "collinear with muK, gain_fy"
  std::vector<std::string> collinear_with;
};

struct Fit {
  Eigen::VectorXd theta, phi;
  /// Per parameter (θ then φ): fixed at its nominal value because the run cannot separate it from
  /// the others (see `unidentifiable`); its covariance rows are 0. Empty: none fixed.
  std::vector<bool> fixed;
  std::vector<Unidentifiable> unidentifiable;
  bool is_fixed(Eigen::Index j) const { return static_cast<std::size_t>(j) < fixed.size() && fixed[static_cast<std::size_t>(j)]; }
  Eigen::MatrixXd cov;              ///< of (θ, φ): σ² (JᵀJ)⁺ at the optimum, times variance_inflation
  double variance_inflation = 1.0;  ///< long-run variance factor of the autocorrelated residuals (>= 1)
  int rank = 0;                     ///< numerical rank of J (θ and φ columns)
  int parameters = 0;               ///< θ + φ
  double rss = 0.0;                 ///< weighted residual sum of squares over the fitted rows
  double sigma2 = 0.0;              ///< rss / (rows - rank)
  long rows = 0;
  int evaluations = 0;                 ///< designs computed
  std::vector<std::string> phi_names;  ///< the names of φ's entries (the model's nonlinear())
  bool converged = true;
  std::vector<Reported> reported;
  std::string invalid;  ///< why the fitted parameters are not physical (empty: they are)
  /// The block-clustered sandwich covariance of (θ, φ) over `sandwich_blocks` consecutive blocks
  /// sized from the residuals' correlation, leverage-corrected (CR2) and widened per parameter by
  /// Student's t of its Bell-McCaffrey degrees of freedom `sandwich_dof` (the blocks its information
  /// is spread over); empty: not computed. And, until score() has used them for the folds' linear
  /// predictions, the weighted Jacobian and residual at the optimum.
  Eigen::MatrixXd cov_sandwich;
  int sandwich_blocks = 0;
  Eigen::VectorXd sandwich_dof;
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd residual;
  /// What sandwich_dof_along needs, kept as long as the Jacobian: (JᵀJ)⁺ and, per block b,
  /// J_bᵀ (I − H_bb)^{-1/2} J_b and J_bᵀ (I − H_bb)^{-1} J_b.
  Eigen::MatrixXd normal_inverse;
  std::vector<Eigen::MatrixXd> sandwich_half, sandwich_full;
};

/// Bell and McCaffrey's degrees of freedom of the sandwich for the linear combination gradientᵀ (θ, φ)
/// of `f`'s parameters: (tr K)² / ‖K‖²_F, K = diag(m ᵀ Q_b m) − Wᵀ (JᵀJ)⁺ W with w_b = T_b m and
/// m = (JᵀJ)⁺ gradient (Imbens and Kolesár 2016, under working errors iid). 0 where `f` kept no
/// sandwich or the gradient is 0.
double sandwich_dof_along(const Fit& f, const Eigen::VectorXd& gradient);

/// The reported std is the block-clustered sandwich's only with at least this many blocks: the
/// residuals correlated over less than a twentieth of the run (blocks of twice the bandwidth).
/// Fewer, longer blocks' influences under-covered a slope under AR(1) errors (48-49 of 60 against
/// the rule's 51, docs/diagnosis.md), where the folds' spread covers.
constexpr int kSandwichMinBlocks = 10;

/// A reported value whose sandwich degrees of freedom are below this is carried by one event of
/// the run (Reported::model_based): t_{0.975} at 3 is 1.6 times 1.96, and the information of
/// slow_slip's μ_s K, which sits in a stop or two, gives 1.0-2.1 (docs/diagnosis.md).
constexpr double kOneEventDof = 3.0;
/// The one-event rule's check on the folds: every fold within z_{1 - 0.025/5} = 2.576 of the
/// Hausman spread its block's removal allows (95 % jointly over the 5 folds, Bonferroni). The
/// component groups' check takes the same bound (with the two contact groups, at most 7 % of the
/// values the model holds are sent to the other rules).
constexpr double kOneEventFoldZ = 2.576;

struct FitOptions {
  int max_iterations = 40;
  double tolerance = 1e-6;  ///< relative cost decrease that ends LM
  /// LM also ends when an iteration lowers the cost by less than this many residual variances
  /// (cost / (rows - parameters)); 0: off. A change of the training cost that small moves no
  /// prediction and no test statistic (a parameter one standard deviation off costs one variance).
  double noise_tolerance = 0.0;
  /// Broyden secant updates of the Jacobian allowed between finite-difference ones (0: finite
  /// differences at every iteration). Convergence is always confirmed by finite differences.
  int secant_updates = 4;
  /// Identifiability before estimation: a parameter whose column of the scaled Jacobian (at the
  /// start and at the optimum; columns taken in order, nominal parameters first) lies within this
  /// sine of the span of the columns kept before it is fixed at its nominal value and listed as
  /// not identifiable; so is a nonlinear one that ends at a bound. 0: off.
  double collinearity_sine = 1e-3;
};

/// Fits `m` on the samples `train` (indices into obs). \throws std::runtime_error if the design is zero.
Fit fit(const ModelFamily& m, const Observations& obs, const std::vector<int>& train, const FitOptions& o = {});
/// The first-order bias of a least-squares fit's (θ, φ) that the errors in the family's variables
/// leave (ModelFamily::errors_in_variables). The fit solves G(θ, φ; x) = Jᵀ r = 0 with the
/// regressors x measured as x + e; to second order in e, E[G(θ*; x + e)] is ½ Σ_v σ_v² ∂²G/∂x_v²,
/// and the bias (JᵀJ)⁺ times it. The second derivative along each variable is the central
/// difference over ± σ_v (a shift common to every sample: each sample's score depends on its own
/// regressors only, so the sum's curvature is the curvature of the sum). It is taken only where the
/// score is smooth at the errors' scale: the same over ± 2σ_v (divided by 4) must move the fit's
/// prediction within kErrorsInVariablesMismatch of what the ± σ_v one moves it (a design whose
/// contacts switch within a few σ, e.g. sharp guides, fails this and is not corrected).
struct ErrorsInVariablesBias {
  Eigen::VectorXd bias;  ///< of (θ, φ), to be subtracted; 0 when not applied (fixed parameters: 0)
  bool applied = false;
  double mismatch = 0.0;  ///< |J (b_2σ - b_σ)| / |J b_σ|
  std::string why_not;    ///< when not applied (empty: the family declares no errors)
};
/// How far the ± 2σ curvature's bias may move the prediction from the ± σ one's, as a share of the
/// latter, for the expansion to be taken as holding: a quadratic score gives 0, and second-order
/// accuracy needs the next order well below the first.
constexpr double kErrorsInVariablesMismatch = 0.25;
/// \param threads as CvOptions::threads.
ErrorsInVariablesBias errors_in_variables_bias(const ModelFamily& m, const Observations& obs, const Fit& f, const std::vector<int>& train,
                                               int threads = 0);

/// N x 6 prediction of the fitted model on every sample.
Eigen::MatrixXd predict(const ModelFamily& m, const Fit& f, std::size_t samples);

/// sqrt(mean((w (y - ŷ))²)) over the rows of `samples`: the contact paper's mean relative error.
double relative_error(const Observations& obs, const Eigen::MatrixXd& prediction, const std::vector<int>& samples);

struct Score;

struct CvOptions {
  int folds = 5;        ///< contiguous time blocks
  int gap_samples = 5;  ///< samples either side of a test block left out of training
  FitOptions fit;
  /// A fold's fit only predicts its held-out block: it starts from the family's own starts (and, in
  /// a second step, from the same fold's fit of the model it extends), never from a point computed
  /// with its held-out block, and stops when an iteration gains less than this many residual
  /// variances (FitOptions::noise_tolerance).
  double fold_noise_tolerance = 0.1;
  /// Called after the full fit: a non-empty answer (why) skips the folds (Score::screened), for a
  /// model that already fails a criterion needing no held-out data.
  std::function<std::string(const Score&)> screen;
  /// Refit the full model under the family's alternative model forms and widen the intervals by
  /// the shifts (after the folds; a screened model is not refitted).
  bool model_forms = true;
  /// Correct the full fit's reported values for the errors in the family's variables
  /// (ModelFamily::errors_in_variables, errors_in_variables_bias; a screened model is not corrected).
  bool errors_in_variables = true;
  /// Repeated blocked CV: the folds are run once per offset of the block grid, i/offsets of a block
  /// for i = 0 .. offsets - 1 (the block holding the run's end then also holds its start), and the
  /// held-out error is pooled over them. One offset is plain blocked CV. Why more: a model whose
  /// events are located from the data (rest_change) cannot predict an event inside a held-out
  /// block, so its held-out error depends on where the block edges cut the events; averaging over
  /// the grid's offsets removes that dependence (docs/diagnosis.md, "Repeated blocked CV"). The
  /// intervals, warm starts and plotted held-out predictions of offset 0 are unchanged by it.
  int offsets = 1;
  /// The parameters (by name) whose effect each fold sizes on its held-out block
  /// (Score::held_out_effect): the added candidate's, in a second step. Empty: not sized.
  std::set<std::string> effect_of;
  /// Threads the folds run on (0: one per core). The folds are independent fits, each with its
  /// own family data and design cache; the results do not depend on the number of threads.
  int threads = 0;
  /// Called after the full fit (0 of the tasks done) and after each fold or model-form refit, from
  /// the thread that ran it, one call at a time: (done, total). For progress lines.
  std::function<void(int, int)> on_task;
};

/// The score of one model.
struct Score {
  std::string model;
  Fit full;                       ///< fitted on every sample (parameters, intervals)
  Eigen::MatrixXd cv_prediction;  ///< N x 6, each block predicted by the fit on the others
  /// With CvOptions::offsets > 1: the same held-out prediction on the grid shifted by i/offsets of
  /// a block, i = 1 .. offsets - 1.
  std::vector<Eigen::MatrixXd> cv_shifted;
  double cv_error = 0.0;     ///< held-out relative error (blocked CV; rms over the grid offsets)
  double train_error = 0.0;  ///< relative error of the full fit on all samples
  /// With CvOptions::effect_of: how much each fold's held-out squared error grows when those
  /// parameters go to their nominal value 0 in the fold's fit, the nominal model's linear
  /// parameters re-solved on the fold's training samples and the rest kept as fitted; the mean over
  /// the held-out rows of every grid (the units of cv_error²). NaN: not sized.
  double held_out_effect = std::numeric_limits<double>::quiet_NaN();
  double bic = 0.0, aic = 0.0;     ///< n ln(rss/n) + k ln(n) | + 2k, n weighted rows, k = rank
  double min_extension_pnr = 0.0;  ///< smallest PNR over the identifiable extension parameters
  double max_extension_pnr = 0.0;
  bool identifiable = false;  ///< some extension parameter has PNR >= 5 (G1+)
  /// Why the folds were skipped (CvOptions::screen); then cv_error is NaN and cv_prediction empty.
  std::string screened;
  bool held_out() const { return screened.empty(); }
  /// Per fold (in time_blocks order, empty blocks skipped, offset after offset): φ fitted without
  /// the block; a second step's folds start from these of the model they extend.
  std::vector<Eigen::VectorXd> fold_phi;
  /// The names of each fold's φ: a fold's own model (ModelFamily::restricted) may have other parameters
  /// than the full one (e.g. rest-pose events located from the training blocks alone).
  std::vector<std::vector<std::string>> fold_phi_names;
  /// The alternative assumptions the intervals account for (ModelFamily::model_forms).
  std::vector<std::string> model_forms;
  /// The alternatives the run rejects (ModelForm::decided_by_fit), each with its excess RSS in
  /// long-run residual variances: they widen nothing.
  std::vector<std::string> model_forms_rejected;
  /// The form whose values are reported (ModelForm::taken_when_preferred), with its RSS margin; empty: the model's own.
  /// For weighted forms (ModelForm::weighted): the one preferred beyond kFormRejection, if any.
  std::string model_form_taken;
  /// The weights the values were averaged with (ModelForm::weighted): "<assumption>: <weight>", the
  /// model's own first as "the model's own form: <weight>". Empty: the family has no weighted form
  /// (or one not weighted was taken).
  std::vector<std::string> model_form_weights;
  /// The measurements whose errors the reported values are corrected for (Reported::errors_in_variables).
  std::vector<std::string> errors_in_variables;
  double seconds = 0.0;
};

/// \param extends the score of a model `m` extends (e.g. the cause, in the second step): its full
/// fit's φ, by name, the others at 0, is one more start of the full fit, and each of its folds' φ
/// one more start of the same fold.
Score score(const ModelFamily& m, const Observations& obs, const CvOptions& o = {}, const Score* extends = nullptr);

/// The sample indices of the blocked cross-validation folds (contiguous blocks).
std::vector<std::vector<int>> time_blocks(std::size_t samples, int folds);
/// The same grid shifted by `offset` of a block (0 <= offset < 1): sample k is in block
/// floor(k folds / samples + offset) mod folds, so block 0 holds the run's end and its start.
/// \throws std::invalid_argument on an offset outside [0, 1).
std::vector<std::vector<int>> time_blocks(std::size_t samples, int folds, double offset);

}  // namespace hil::diagnose
