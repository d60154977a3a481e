#pragma once
// The stiffness model and truth files (JSON, docs/calibration.md): a robot's compliances, the
// identified model `hil stiffness identify --json` writes (hil.stiffness_model) and what predict,
// simulate and the worker read back. Bad input throws hil::error::FormatError naming the file and
// the JSON field.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include <hil/calibration/identification.hpp>
#include <hil/calibration/reduction.hpp>
#include <hil/calibration/vjm.hpp>

namespace hil::models {

/// Parses a JSON file. \throws FormatError on syntax errors (with the byte offset).
nlohmann::json load_json(const std::string& path);

/// Compliance of each spring from a model or truth file ("springs" object). Springs not listed
/// are rigid. \throws FormatError naming the file and field.
calibration::ComplianceSet read_springs(const nlohmann::json& springs, const calibration::VjmModel& model, const std::string& file);
nlohmann::json springs_to_json(const calibration::VjmModel& model, const calibration::ComplianceSet& k);
nlohmann::json robot_to_json(const calibration::SerialRobot& robot);
calibration::SerialRobot robot_from_json(const nlohmann::json& j, const std::string& file);

/// Refuses a JSON file of another kind than a stiffness model ("format": "hil.stiffness_model",
/// or the earlier "hil-stiffness-model"), naming the file and what it is. A file without a
/// "format" is accepted unless `required` (hand-written truth files need not carry one).
void check_model_format(const nlohmann::json& j, const std::string& file, bool required);

/// The identify result as a model file (hil.stiffness_model): kept and fixed parameters with
/// their intervals, the reduction, ranks, singular values, residuals, SPD checks, springs, robot.
nlohmann::json result_to_json(const calibration::VjmModel& model, const calibration::CalibrationResult& r);

/// A model file's robot and compliances.
struct ModelFile {
  calibration::VjmModel model;
  calibration::ComplianceSet k;
};
/// A model or truth file; the robot is `robot` when given, else the file's ("robot").
ModelFile read_model_file(const std::string& path, const calibration::SerialRobot* robot);
/// A truth file's compliances ("springs") for `model`.
calibration::ComplianceSet read_truth_file(const std::string& path, const calibration::VjmModel& model);

/// The reduced model of an identify --json file: its kept parameters are estimated online, its
/// fixed ones stay at their values.
struct ReducedModel {
  calibration::ParameterSet free;
  calibration::ParameterSet fixed;
  Eigen::VectorXd fixed_values;
};
ReducedModel read_reduced_model(const std::string& path, const calibration::VjmModel& model);

}  // namespace hil::models
