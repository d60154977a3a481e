#pragma once
// The rig file's robot and the stiffness-experiment table (docs/calibration.md) as the calibration
// numerics' types. Bad input throws hil::error::FormatError naming the file, line and column.
#include <ostream>
#include <string>
#include <vector>

#include <hil/calibration/observation.hpp>
#include <hil/calibration/robot.hpp>
#include <hil/format/rig.hpp>

namespace hil::models {

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

}  // namespace hil::models
