#pragma once
// What `hil stiffness identify|predict|simulate|table1` do, as library calls: the identification
// report, the predicted deflections and compensation, a simulated experiment table and the
// counting of the paper's Table I. Files are hil::models' (the rig's robot, the experiment table,
// the model JSON); the numerics hil::calibration's; the online worker is services/workers'.
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/online.hpp>
#include <hil/calibration/reduction.hpp>
#include <hil/models/stiffness.hpp>
#include <hil/models/stiffness_model.hpp>

namespace hil::services::stiffness {

/// The text report: reduction table beside the paper's, parameters, rank, residuals, SPD checks.
void print_report(std::ostream& os, const calibration::VjmModel& model, const calibration::CalibrationResult& r);
/// The reduction table beside Table I of the paper.
void print_reduction_table(std::ostream& os, const std::vector<calibration::ReductionLine>& lines);

/// Rows whose joint-space compensation did not converge: near a singular configuration the
/// Newton steps on the rigid Jacobian's pseudo-inverse do not settle (VjmModel::compensate).
struct CompensationFailure {
  int config = 0;
  double residual = 0.0;                 ///< the pose error left, m and rad mixed as compensate reports it
  double smallest_singular_value = 0.0;  ///< of the rigid tool Jacobian at the target joints
};

/// The largest pose error (m, rad) a compensated row may keep; converged rows keep ~1e-15.
inline constexpr double kCompensationResidual = 1e-8;

/// The predicted deflection of every row of `table` as CSV (docs/calibration.md); with
/// `compensate`, also the target pose, the compensated pose and the compensated joints. Returns
/// the rows whose compensation left more than kCompensationResidual (each also logged as a warning).
std::vector<CompensationFailure> write_predictions(std::ostream& os, const models::ModelFile& mf, const models::StiffnessTable& table,
                                                   bool compensate);

/// A simulated stiffness-experiment table (CSV with a comment line naming `origin`).
void write_simulated_table(std::ostream& os, const calibration::VjmModel& model, const calibration::ComplianceSet& truth,
                           const calibration::ExperimentPlan& plan, const calibration::NoiseModel& noise, const std::string& origin);

/// The counting of the paper's Table I on noise-free simulated data for `model`: the reduction
/// table, ranks, the identifiable groups and the kept parameters. `measure`: pose6, point3,
/// point3-forces or markers.
void print_table1(std::ostream& os, const calibration::VjmModel& model, int configs, const std::string& measure, std::uint64_t seed,
                  bool complete_ranks);

/// The online identifier of the stiffness worker: the reduced model of an identify --json file
/// (`reduced_model_path`), or the physical reduction of `model` done online when it is empty.
std::unique_ptr<calibration::OnlineIdentifier> make_online_identifier(const calibration::VjmModel& model,
                                                                      const std::string& reduced_model_path,
                                                                      const calibration::NoiseModel& noise,
                                                                      const calibration::PipelineOptions& options);

}  // namespace hil::services::stiffness
