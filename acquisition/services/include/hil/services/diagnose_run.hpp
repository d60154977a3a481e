#pragma once
/// \file `hil diagnose` on a run: the model family from the rig (contact scene -> contact family;
/// no contact model -> deflection family), the diagnosis, and its outputs (text, JSON, HTML).
#include <nlohmann/json.hpp>
#include <memory>
#include <ostream>
#include <string>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/deflection_family.hpp>
#include <hil/diagnose/stiffness_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/format/run.hpp>

namespace hil::services::diagnose {

struct Options {
  std::vector<std::string> candidates;  ///< empty: all that apply
  int folds = 5;
  /// Offsets of the block grid the cross-validation is repeated over (CvOptions::offsets); 0: 8 when
  /// rest_change is among the candidates (its held-out error depends on where the blocks cut its
  /// events), else 1.
  int cv_offsets = 0;
  /// Where contact_damping's penetration rates come from (contact runs).
  hil::diagnose::RateSource damping_rates = hil::diagnose::RateSource::automatic;
  hil::diagnose::Progress progress;
};

struct RunDiagnosis {
  std::string run_name, mode;  ///< mode: "contact", "deflection" or "stiffness" (a stiffness table)
  std::unique_ptr<hil::diagnose::ContactData> contact;
  std::unique_ptr<hil::diagnose::DeflectionData> deflection;
  std::unique_ptr<hil::diagnose::StiffnessData> stiffness;
  hil::diagnose::Context context;
  hil::diagnose::Diagnosis result;
  std::vector<std::string> notes;
  const hil::diagnose::Observations& obs() const {
    return contact ? contact->obs : deflection ? deflection->obs : stiffness->obs;
  }
};

/// \throws format::FormatError / std::runtime_error naming the run on bad input.
RunDiagnosis diagnose_run(const format::Run& run, const Options& o);
/// A stiffness-experiment table (docs/calibration.md) of the robot in `rig_path`, against the
/// joint-compliance model. \throws format::FormatError / std::runtime_error naming the file.
RunDiagnosis diagnose_table(const std::string& table_path, const std::string& rig_path, const Options& o);

void print_summary(std::ostream& out, const RunDiagnosis& r);
nlohmann::json to_json(const RunDiagnosis& r);
void write_report(const std::string& dir, const RunDiagnosis& r);

}  // namespace hil::services::diagnose
