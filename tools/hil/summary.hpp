#pragma once
// Human-readable summaries of runs and rigs, shared by `hil validate` and `hil demo`.
#include <ostream>

#include "hil/format/run.hpp"

namespace hil::cli {
void print_samples_summary(std::ostream& os, const format::SampleTable& t);
void print_rig_summary(std::ostream& os, const format::RigSpec& rig);
void print_run_summary(std::ostream& os, const format::Run& run);
}  // namespace hil::cli
