#pragma once
/// \file `hil contact identify`: the whole identification of one run, as data, printable, JSON and HTML.
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include <hil/contact_id/identification.hpp>
#include <hil/format/run.hpp>

namespace hil::services::contact {

struct IdentifyOptions {
  bool geometric = false;
  std::string lambda = "auto";             ///< a number or "auto" (L-curve corner)
  std::string solver = "lm";               ///< lm | nm
  std::string jacobian = "golub-pereyra";  ///< golub-pereyra | kaufman
  int window = 25;                         ///< sliding window (used samples) for the smoothed instantaneous estimates
  int lcurve_points = 30;
  /// Also fit the weakly observable uncertainties (by default they stay at their design value:
  /// the paper's Ockham's razor, and the regularisation cannot make them informative).
  bool include_weak = false;
};

struct IdentifyResult {
  contact_id::LinearEstimate nominal;  ///< at x_u = x_u^d
  std::vector<contact_id::InstantEstimate> inst_nominal, window_nominal;
  std::optional<contact_id::Observability> observability;
  std::optional<contact_id::GeometricEstimate> geometric;
  std::vector<contact_id::InstantEstimate> inst_geometric, window_geometric;
  std::optional<contact_id::LCurve> lcurve;
  double seconds_geometric = 0.0;
  std::vector<std::string> notes;
};

IdentifyResult identify(const contact_id::ContactProblem& p, const IdentifyOptions& o);
/// The identification problem of a run against its rig (the run's rig.yaml or the one given).
/// \throws error::FormatError or std::runtime_error naming the run on bad input.
contact_id::ContactProblem problem_from_run(const format::Run& run);
/// The model's plate wrench (Φ θ at geometry x, mapped to the force-plate frame; N, N m) for every
/// sample the problem uses, with each sample's contact count in `counts`.
std::vector<contact_id::Vector6d> model_plate_wrenches(const contact_id::ContactProblem& p, const Eigen::VectorXd& x,
                                                       const Eigen::Vector2d& theta, std::vector<int>& counts);
void print(std::ostream& out, const contact_id::ContactProblem& p, const IdentifyResult& r);
nlohmann::json to_json(const contact_id::ContactProblem& p, const IdentifyResult& r);
/// Writes DIR/index.html with the paper-like figures.
void write_report(const std::string& dir, const std::string& run_name, const contact_id::ContactProblem& p, const IdentifyResult& r);

}  // namespace hil::services::contact
