#pragma once
/// \file `hil diagnose` on a run: the model family from the rig (contact scene -> contact family;
/// no contact model -> deflection family) and the diagnosis; its outputs are diagnose_output.hpp's.
#include <nlohmann/json.hpp>
#include <limits>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/deflection_family.hpp>
#include <hil/diagnose/stiffness_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/format/run.hpp>
#include <hil/services/stability_grid.hpp>

namespace hil::services::diagnose {

struct Options {
  std::vector<std::string> candidates;  ///< empty: all that apply
  int folds = 5;
  /// Offsets of the block grid the cross-validation is repeated over (CvOptions::offsets); 0: the
  /// most any candidate asks for (Effect::cv_offsets: 8 with rest_change, whose held-out error
  /// depends on where the blocks cut its events), else 1.
  int cv_offsets = 0;
  /// Threads the cross-validation folds run on (CvOptions::threads; 0: one per core); 1 also scores
  /// the models one after another (DiagnoseOptions::model_threads, else two side by side), so that
  /// the diagnosis keeps to one core. The result does not depend on it.
  int threads = 0;
  /// The most samples a run is diagnosed on (0: all). A longer run is diagnosed on every k-th
  /// sample, k = ⌈samples / max_samples⌉ (RunDiagnosis::every): the cost grows with the samples
  /// diagnosed, so a 10-minute run at 1 kHz is diagnosed in about two minutes on two cores rather
  /// than in an hour and a half (docs/diagnosis.md, "Long runs"). Windows (diagnose_windows) are
  /// held to it each on its own.
  std::size_t max_samples = 10000;
  /// Where contact_damping's penetration rates come from (contact runs).
  hil::diagnose::RateSource damping_rates = hil::diagnose::RateSource::automatic;
  hil::diagnose::Progress progress;
  bool progress_detail = false;  ///< DiagnoseOptions::progress_detail (the CLI's fold-level lines)
};

/// The verdict of one time window of a run (diagnose_windows): when a cause appears or drifts.
struct WindowVerdict {
  double start_s = 0.0, end_s = 0.0;  ///< the window's span, the run's time
  std::size_t samples = 0;
  std::string cause;                                                ///< the named cause, "none", or empty when the window was not diagnosed
  std::string second_cause;                                         ///< empty: none
  double nominal_error = std::numeric_limits<double>::quiet_NaN();  ///< held-out relative error
  double extended_error = std::numeric_limits<double>::quiet_NaN();
  double gain_percent = std::numeric_limits<double>::quiet_NaN();
  bool white = true;  ///< the nominal residual's whiteness (Ljung-Box)
  std::string error;  ///< why the window was not diagnosed (e.g. no contact in it)
};

/// The verdict of the run under one cross-validation setting (verdict_stability).
struct StabilityRow {
  int folds = 5;
  int cv_offsets = 1;
  std::string cause;         ///< "none", "unexplained" or a candidate; empty when not diagnosed
  std::string second_cause;  ///< empty: none
  double gain_percent = std::numeric_limits<double>::quiet_NaN();
  std::string error;  ///< why this setting could not be diagnosed
};

struct RunDiagnosis {
  std::string run_name, mode;  ///< mode: "contact", "deflection" or "stiffness" (a stiffness table)
  int folds = 5;               ///< the cross-validation's blocks (Options::folds)
  std::unique_ptr<hil::diagnose::ContactData> contact;
  std::unique_ptr<hil::diagnose::DeflectionData> deflection;
  std::unique_ptr<hil::diagnose::StiffnessData> stiffness;
  hil::diagnose::Context context;
  /// The run's model family for a set of extensions (what the diagnosis fitted; the outputs ask it
  /// for what an effect locates rather than fits).
  hil::diagnose::ModelFactory make;
  hil::diagnose::Diagnosis result;
  std::vector<std::string> notes;
  std::size_t samples_in_run = 0;       ///< the run's samples, before Options::max_samples
  std::size_t every = 1;                ///< the diagnosis took every `every`-th of them
  std::vector<WindowVerdict> windows;   ///< diagnose_windows' verdicts, when asked for
  std::vector<StabilityRow> stability;  ///< verdict_stability's rows, when asked for
  /// Every stability row names the same causes (cause and second cause, as a set) as `result`.
  bool stable() const;
  const hil::diagnose::Observations& obs() const { return contact ? contact->obs : deflection ? deflection->obs : stiffness->obs; }
};

/// \throws error::FormatError / std::runtime_error naming the run on bad input.
RunDiagnosis diagnose_run(const format::Run& run, const Options& o);
/// Every `every`-th sample of `run` (from the first), the rest of the run as it is.
format::Run every_nth(const format::Run& run, std::size_t every);
/// The run cut into consecutive windows of `window_s` (a last window shorter than half of one
/// joins the one before), each diagnosed on its own with the same options: a cause that appears,
/// drifts or goes in a long recording shows where. A window that cannot be diagnosed (no contact,
/// too few samples) keeps why in WindowVerdict::error. \throws std::invalid_argument if
/// window_s <= 0.
std::vector<WindowVerdict> diagnose_windows(const format::Run& run, double window_s, const Options& o);
/// The run diagnosed again under each (folds, cv offsets) of `grid`, every other option as in `o`
/// (issue 32, item 5): a verdict that changes with the cross-validation's settings is not one to
/// act on. A setting that cannot be diagnosed keeps why in StabilityRow::error.
/// \throws std::invalid_argument on an empty grid or a setting outside stability_grid.hpp's bounds.
std::vector<StabilityRow> verdict_stability(const format::Run& run, const Options& o, const std::vector<std::pair<int, int>>& grid);
/// A stiffness-experiment table (docs/calibration.md) of the robot in `rig_path`, against the
/// joint-compliance model. \throws error::FormatError / std::runtime_error naming the file.
RunDiagnosis diagnose_table(const std::string& table_path, const std::string& rig_path, const Options& o);

}  // namespace hil::services::diagnose
