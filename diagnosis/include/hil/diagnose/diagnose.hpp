#pragma once
/// \file Naming the cause: every candidate extension is fitted and scored on held-out data
/// (blocked cross-validation over time), by an information criterion (BIC) and by practical
/// identifiability (parameter-to-noise ratio >= 5, the stiffness paper's G1+). The named cause is
/// the best-supported extension; greedy forward selection then names a second cause when one
/// remains. When no extension beats the nominal model beyond the noise: `none` if its residual is
/// unstructured, `unexplained` (with the structure named) if it is not.
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <hil/diagnose/engine.hpp>

namespace hil::diagnose {

/// What a `none` must not hide (issue 32): the thresholds above which a residual's structure is
/// reported. Calibrated on clean runs of several motion families before any run with an effect
/// outside the library was diagnosed (docs/diagnosis.md, "Structure left in the residual").
struct StructureOptions {
  /// Not white: the residual's mean square beyond its white floor (von Neumann's first-difference
  /// noise estimate, which slow structure hardly reaches, plus the quantisation's q²/12), in floor
  /// variances, pooled over the weighted components.
  double max_excess = 0.25;
  /// A correlation with a run signal (the best lag within ±10 samples) or with time (a trend, lag
  /// 0): the part of one component's residual variance it explains linearly, r² var / noise², in
  /// that component's noise variances ...
  double max_explained = 0.1;
  /// ... and significant: |r| √n at least this (white noise's largest of the few hundred
  /// correlations looked at stays below about 4).
  double min_z = 5.0;
};

/// Where and how the nominal model's residuals concentrate.
struct ResidualAnalysis {
  Eigen::Matrix<double, 6, 1> rms = Eigen::Matrix<double, 6, 1>::Zero();           ///< physical units
  Eigen::Matrix<double, 6, 1> relative_rms = Eigen::Matrix<double, 6, 1>::Zero();  ///< weighted
  int worst_component = 0;
  /// Share of the squared (weighted) residual in each of 10 equal time windows.
  std::vector<double> window_start_s, window_share;
  /// Per state label (e.g. "2 contacts, sliding"): samples and relative error.
  struct State {
    std::string label;
    int samples = 0;
    double relative_error = 0.0;
    double share = 0.0;  ///< of the squared residual
  };
  std::vector<State> states;
  /// Ljung-Box test on the worst component's residual (20 lags): white when Q < its 99 % bound.
  double ljung_box_q = 0.0, ljung_box_bound = 0.0;
  bool white = true;
  std::vector<double> autocorrelation;  ///< lags 0..20 of the worst component
  /// Cross-correlation of each component's residual with each candidate signal (max over ±10 lags).
  struct Correlation {
    std::string signal, component;
    double correlation = 0.0;
    int lag = 0;             ///< samples; positive: the residual follows the signal
    double explained = 0.0;  ///< r² var / noise² of the component, in its noise variances
  };
  std::vector<Correlation> correlations;  ///< sorted by |correlation|, strongest first
  /// Per component: the residual's mean square over its white floor, minus 1; and pooled over the
  /// weighted components. The floor is the noise variance by von Neumann's first differences plus
  /// q²/12 of the quantisation step q the measured values show (0 when they show none).
  Eigen::Matrix<double, 6, 1> excess = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> quantisation = Eigen::Matrix<double, 6, 1>::Zero();
  double excess_variance = 0.0;
  /// Per component: the correlation with time (lag 0), a trend or a drift.
  std::vector<Correlation> trends;
  /// The structure found above StructureOptions' thresholds, strongest first; empty: the residual
  /// is unstructured (white, uncorrelated with the run's signals, without trend).
  struct Finding {
    std::string kind;   ///< "not white", "correlates", "trend"
    std::string text;   ///< e.g. "fy correlates with vx (r = 0.66, lag 0): 1.3 noise variances of fy"
    double size = 0.0;  ///< in noise variances
  };
  std::vector<Finding> structure;
  bool structured() const { return !structure.empty(); }
  /// The findings as one line ("" when unstructured).
  std::string structure_text() const;
};

/// Per-sample context for the analysis: state labels and candidate signals.
struct Context {
  std::vector<std::string> state;                      ///< per sample (may be empty)
  std::map<std::string, std::vector<double>> signals;  ///< per sample
};

ResidualAnalysis analyse_residuals(const Observations& obs, const Eigen::MatrixXd& prediction, const Context& ctx,
                                   const StructureOptions& so = {});

/// Two candidates that explain the run about equally (issue 32, item 2): the cause and a rival
/// whose held-out errors a paired test cannot tell apart and whose predicted effects are nearly
/// collinear on this run's motion.
struct Confounded {
  std::string cause, rival;
  double cause_gain_percent = 0.0, rival_gain_percent = 0.0;
  double z = 0.0;          ///< paired z of the cause's held-out errors against the rival's (> 0: the cause predicts better)
  double cosine = 0.0;     ///< of their held-out effects (prediction minus the nominal's), weighted
  std::string evidence;    ///< each one's gain, consistency and parameters
  std::string experiment;  ///< what run would separate them
};

/// When a rival counts as confounded with the cause (DiagnoseOptions::confounding).
struct ConfoundingOptions {
  double max_z = 2.0;       ///< |paired z| below this: the held-out errors are within their standard errors
  double min_cosine = 0.8;  ///< effects at least this collinear
};

struct DiagnoseOptions {
  CvOptions cv;
  double min_gain = 0.02;  ///< relative held-out error reduction an extension must bring (2 %)
  /// and its consistency: the paired, autocorrelation-robust z of the per-sample error reduction (a
  /// gain carried by a few large residuals alone, e.g. an extension absorbing outliers, has z < 1)
  double min_z = 1.0;
  double min_pnr = 5.0;  ///< practical identifiability (G1+)
  /// and its size: the held-out mean squared (weighted) error must fall by at least this fraction
  /// of the measurement noise variance (estimated from the nominal residual's first differences),
  /// so that effects far below the sensor's resolution are not named however precisely fitted.
  /// In the second step the size is the larger of that and the added candidate's held-out effect
  /// in the joint model (CandidateResult::effect_fraction): a second cause confounded with the
  /// first (a damping force looks to the normal force like a lead, which the fitted delay absorbs)
  /// shows only the part of its size the first cannot mimic as a held-out reduction.
  double min_noise_fraction = 0.25;
  StructureOptions structure;  ///< `none` only on an unstructured residual, else `unexplained`
  ConfoundingOptions confounding;
  int second_candidates = 8;  ///< greedy second step: the best single candidates tried with the cause
  /// Models scored side by side (the candidates of a step; 1: one after another), each with its
  /// folds on CvOptions::threads. Two by default: a model's full fit runs on one thread, and while
  /// it does, the other model's folds use the remaining cores; more would multiply the threads and
  /// design caches for little. The results do not depend on it.
  int model_threads = 2;
  /// Progress at fold granularity: `what` then reads "model, fold N of M; T s, ~L s left[; beside
  /// it: other models]" and the calls also come after each fold. Off: one call per step, `what` the
  /// model's name (the Python binding's contract). Either way the calls come one at a time, steps
  /// announced in order, from the thread that runs the step (the caller's or a model worker's); a
  /// callback that throws stops the steps not yet started and its exception leaves diagnose().
  bool progress_detail = false;
};

struct CandidateResult {
  std::string name;
  Score score;
  double gain_percent = 0.0;    ///< held-out error reduction against the model it extends
  double z = 0.0;               ///< significance of that reduction
  double noise_fraction = 0.0;  ///< held-out MSE reduction over the noise variance
  /// Second step: how much the held-out mean squared (weighted) error of the joint model grows
  /// when the added candidate's parameters go to their nominal value (0) in each fold's fit, the
  /// nominal model's linear parameters re-solved on the fold's training samples and the cause's
  /// kept as fitted (Score::held_out_effect), over the noise variance (NaN: not computed). Sized on
  /// held-out data only: an effect the joint fit makes up on its own samples predicts nothing.
  double effect_fraction = std::numeric_limits<double>::quiet_NaN();
  /// The same change of the full joint fit's prediction on its own samples (reported only: it
  /// counts what the fit made up as effect).
  double effect_fraction_in_sample = std::numeric_limits<double>::quiet_NaN();
  /// The largest PNR among the parameters this candidate adds (not those of the model it extends).
  double pnr = 0.0;
  bool supported = false;
  bool applicable = true;  ///< false: the model could not be built or fitted on this run
  std::string verdict;     ///< why (not)
};

struct Diagnosis {
  Score nominal;
  double noise_relative =
      0.0;  ///< the measurement noise (weighted rms): the least of the nominal's and the single candidates' held-out residual differences
  std::vector<CandidateResult> candidates;  ///< ranked: supported first, then by held-out error
  /// The named cause; "none" when no extension is supported and the nominal residual is
  /// unstructured; "unexplained" when none is supported but structure remains (named in
  /// nominal_residuals.structure). After a named cause, extended_residuals.structure says what
  /// its model still leaves.
  std::string cause = "none";
  std::string second_cause;  ///< empty: none
  std::vector<CandidateResult> second_step;
  std::optional<Score> extended;  ///< the nominal model with the cause (and second cause)
  double gain_percent = 0.0;      ///< held-out: 100 (1 - extended / nominal)
  ResidualAnalysis nominal_residuals, extended_residuals;
  /// The rivals the cause cannot be told from on this run (empty: none); the verdict is then "the
  /// cause or its rival", with the experiment that would separate them.
  std::vector<Confounded> confounded;
  double seconds = 0.0;
};

using ModelFactory = std::function<std::unique_ptr<ModelFamily>(const std::set<std::string>&)>;
/// Progress: (step, total, what).
using Progress = std::function<void(int, int, const std::string&)>;

Diagnosis diagnose(const ModelFactory& make, const std::vector<std::string>& candidates, const Observations& obs, const Context& ctx,
                   const DiagnoseOptions& o = {}, const Progress& progress = {});

/// The white-noise level of a residual (weighted rms): von Neumann's first-difference estimator,
/// insensitive to slowly varying model error.
double noise_level(const Observations& obs, const Eigen::MatrixXd& prediction);

/// Paired comparison of held-out predictions: the mean reduction of the per-sample squared weighted
/// error over its autocorrelation-robust (Newey-West) standard error.
double paired_z(const Observations& obs, const Eigen::MatrixXd& reference, const Eigen::MatrixXd& candidate);
/// The same on two scores' held-out predictions, the per-sample error norm averaged over the grid
/// offsets of repeated blocked CV (CvOptions::offsets).
/// \throws std::invalid_argument if the two were held out on different numbers of offsets.
double paired_z(const Observations& obs, const Score& reference, const Score& candidate);

}  // namespace hil::diagnose
