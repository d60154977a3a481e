#pragma once
/// \file The outputs of a run's diagnosis (diagnose_run.hpp): the text summary, the JSON
/// (hil.diagnosis, docs/schemas) and the self-contained HTML report.
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include <hil/services/diagnose_run.hpp>

namespace hil::services::diagnose {

void print_summary(std::ostream& out, const RunDiagnosis& r);
nlohmann::json to_json(const RunDiagnosis& r);
/// The HTML report: `dir`/index.html and its figures in `dir`/figures (the folder is created).
void write_report(const std::string& dir, const RunDiagnosis& r);

}  // namespace hil::services::diagnose
