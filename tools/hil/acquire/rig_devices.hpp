#pragma once
// From the rig file to device configurations, fakes, scenarios and the robot model: the glue
// between hil::runformat (plain data) and the drivers and numerics, which know nothing of files.
#include <memory>

#include "hil/calibration/robot.hpp"
#include "hil/drivers/fake_rig.hpp"
#include "hil/drivers/force_plate.hpp"
#include "hil/drivers/robot_controller.hpp"
#include "hil/format/run.hpp"

namespace hil::cli {

drivers::ForcePlateConfig plate_config(const format::ForcePlateDeviceSpec& spec);
drivers::ModbusConfig modbus_config(const format::RobotControllerSpec& spec);
drivers::RegisterMap register_map(const format::RobotControllerSpec& spec);
calibration::SerialRobot robot_model(const format::RobotSpec& spec);

/// The rig's recorded (or simulated) states as a scenario for the fake devices: the wrench on
/// the plate and the tool pose in the robot base frame (T_world_base from the rig's robot).
std::shared_ptr<const drivers::Scenario> scenario_from_run(const format::Run& run, const Eigen::Isometry3d& T_world_base);

}  // namespace hil::cli
