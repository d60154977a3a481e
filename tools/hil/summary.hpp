#pragma once
// Summaries of runs and rigs, shared by `hil validate` and `hil demo`: as text, and as the
// "summary" of `hil validate --json` (docs/schemas/hil.validation.schema.json).
#include <nlohmann/json.hpp>
#include <ostream>

#include <hil/format/run.hpp>

namespace hil::cli {
void print_samples_summary(std::ostream& os, const format::SampleTable& t);
void print_rig_summary(std::ostream& os, const format::RigSpec& rig);
void print_run_summary(std::ostream& os, const format::Run& run);

nlohmann::json samples_summary_json(const format::SampleTable& t);
nlohmann::json rig_summary_json(const format::RigSpec& rig);
nlohmann::json run_info_json(const format::RunInfo& info);
nlohmann::json run_summary_json(const format::Run& run);
}  // namespace hil::cli
