#pragma once
/// \file `hil import` of a lab's calibration table into a calibration run (docs/import.md,
/// "Calibration runs"): which columns hold the joints, the measured point and orientation, in which
/// units and angle convention. The output is checked by the strict calibration-run reader.
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <hil/format/calibration_run.hpp>
#include <hil/format/csv.hpp>

namespace hil::import {

enum class OrientationForm { rpy, rotation_vector };

struct CalibrationImportConfig {
  std::string file;
  char delimiter = ',';
  bool header = true;
  std::vector<std::string> columns;  ///< header: false
  std::string posture_column;        ///< empty: postures numbered 1, 2, ... in file order
  std::string station_column;        ///< empty: every posture from `station_value`
  std::string station_value = "1";
  std::map<std::string, std::string> joint_columns;  ///< robot joint -> source column; others by their own name
  double joint_si_per_unit = 1.0;                    ///< rad (or m) per unit
  std::array<std::string, 3> point_columns;
  double point_m_per_unit = 1.0;
  std::optional<std::array<std::string, 3>> orientation_columns;
  OrientationForm orientation_form = OrientationForm::rpy;
  double orientation_rad_per_unit = 1.0;
  double sigma_m = 0.0;  ///< 0: none written
  double sigma_rad = 0.0;
  std::map<std::string, std::string> flags;  ///< flag name -> source column (0/1)
};

CalibrationImportConfig parse_calibration_import_config(const std::string& yaml_text, const std::string& display_name);
CalibrationImportConfig load_calibration_import_config(const std::string& path);

/// The calibration run's CSV text (docs/formats.md) for `robot`, from the source table.
/// \throws FormatError naming the source file, line and column.
std::string import_calibration_table(const format::CsvTable& table, const CalibrationImportConfig& cfg, const format::RobotSpec& robot);

}  // namespace hil::import
