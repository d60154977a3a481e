#pragma once
/// \file The outputs of a run's diagnosis (diagnose_run.hpp): the text summary, the JSON
/// (hil.diagnosis, docs/schemas) and the self-contained HTML report.
#include <nlohmann/json.hpp>
#include <map>
#include <ostream>
#include <string>

#include <hil/services/diagnose_run.hpp>

namespace hil::services::diagnose {

void print_summary(std::ostream& out, const RunDiagnosis& r);
/// What print_summary says beside a value whose interval the residuals cannot measure
/// (Reported::model_based) or which a group of components contradicts (Reported::std_components);
/// empty for any other.
std::string one_event_text(const hil::diagnose::Reported& q);
nlohmann::json to_json(const RunDiagnosis& r);
/// True values by the reported parameters' names (bias_fz, time_offset_s, an uncertainty's name).
using TruthValues = std::map<std::string, double>;

/// The true values a hidden-effects file (`hil contact simulate --truth-out`) gives for `r`'s
/// parameters: its numbers by key, its per-channel arrays per component, its geometric values.
/// \throws error::FormatError if the file is not a hidden-effects file.
TruthValues read_truth(const std::string& path, const RunDiagnosis& r);

/// The HTML report: `dir`/index.html and its figures in `dir`/figures (the folder is created).
/// The verdict first (cause, held-out error before → after, the gain's interval, its stability
/// over the held-out blocks and grid offsets, what to do next), then the candidates, parameters
/// with intervals (and `truth` where given, e.g. a hidden-effect simulation's), the residual's
/// structure, per-configuration residual vectors for a stiffness table, the predictions.
void write_report(const std::string& dir, const RunDiagnosis& r, const TruthValues& truth = {});

}  // namespace hil::services::diagnose
