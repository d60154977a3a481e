#pragma once
// I/O of the `hil stiffness` commands: the rig adapter, the stiffness-experiment table and the
// model/truth JSON files (formats in docs/calibration.md). Bad input throws hil::format::FormatError
// naming the file, line and column or JSON field.
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "hil/calibration/reduction.hpp"
#include "hil/format/rig.hpp"

namespace hil::cli::stiffness {

/// The calibration robot model of a rig's robot (DH table, base and tool poses, joint limits).
calibration::SerialRobot to_serial_robot(const format::RobotSpec& spec);
/// Loads the rig and adapts its robot. \throws FormatError if the rig has no robot.
calibration::SerialRobot load_robot(const std::string& rig_path);

/// A stiffness-experiment table. `require_measured`: identify needs dx dy dz (or marker columns);
/// predict reads the same table without them.
struct StiffnessTable {
  std::vector<calibration::Measurement> rows;
  std::vector<std::size_t> lines;  ///< file line of each row
  bool has_measured = false;
};
StiffnessTable read_stiffness_table(const std::string& path, int dof, bool require_measured);
StiffnessTable parse_stiffness_table(const std::string& text, const std::string& display_name, int dof, bool require_measured);
void write_stiffness_table(std::ostream& os, const std::vector<calibration::Measurement>& rows, int dof);

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

}  // namespace hil::cli::stiffness
