#pragma once
// I/O of the `hil stiffness` commands: the model/truth JSON files and the reports (formats in
// docs/calibration.md; the rig adapter and the experiment table are hil::rig's). Bad input throws
// hil::format::FormatError naming the file and JSON field.
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include <hil/calibration/reduction.hpp>
#include <hil/format/rig.hpp>
#include <hil/rig/stiffness.hpp>

namespace hil::services::stiffness {

using rig::load_robot;
using rig::read_stiffness_table;
using rig::parse_stiffness_table;
using rig::StiffnessTable;
using rig::to_serial_robot;
using rig::write_stiffness_table;

/// Compliance of each spring from a model or truth file ("springs" object). Springs not listed
/// are rigid. \throws FormatError naming the file and field.
calibration::ComplianceSet read_springs(const nlohmann::json& springs, const calibration::VjmModel& model, const std::string& file);
nlohmann::json springs_to_json(const calibration::VjmModel& model, const calibration::ComplianceSet& k);
nlohmann::json robot_to_json(const calibration::SerialRobot& robot);
calibration::SerialRobot robot_from_json(const nlohmann::json& j, const std::string& file);
/// Parses a JSON file. \throws FormatError on syntax errors (with the byte offset).
nlohmann::json load_json(const std::string& path);

/// Refuses a JSON file of another kind than a stiffness model ("format": "hil.stiffness_model",
/// or the earlier "hil-stiffness-model"), naming the file and what it is. A file without a
/// "format" is accepted unless `required` (hand-written truth files need not carry one).
void check_model_format(const nlohmann::json& j, const std::string& file, bool required);

/// The identify report as JSON (also a model file for predict and worker).
nlohmann::json result_to_json(const calibration::VjmModel& model, const calibration::CalibrationResult& r);
/// The text report: reduction table beside the paper's, parameters, rank, residuals, SPD checks.
void print_report(std::ostream& os, const calibration::VjmModel& model, const calibration::CalibrationResult& r);
/// The reduction table beside Table I of the paper.
void print_reduction_table(std::ostream& os, const std::vector<calibration::ReductionLine>& lines);

}  // namespace hil::services::stiffness
