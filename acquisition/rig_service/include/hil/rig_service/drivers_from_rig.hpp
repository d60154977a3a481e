#pragma once
/// \file From the rig file's device sections (hil::format) to the drivers' configurations
/// (hil::drivers). Errors name the rig file and the field, as hil::error::FormatError.
#include <Eigen/Geometry>

#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/robot_controller.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/run.hpp>

namespace hil::rig_service {

/// devices.force_plate → ForcePlateConfig (protocol, base id, rate, T_fp_sensor, signals, limits).
/// \throws error::FormatError naming `devices.force_plate.<field>` in `rig.source`.
drivers::ForcePlateConfig force_plate_config(const format::RigSpec& rig);

/// devices.robot → ModbusConfig (transport, address, unit, serial settings, rate, timeout, map;
/// the robot's DH chain as `kinematics` when the map reads joints but no tool pose).
/// \throws error::FormatError naming `devices.robot.<field>`.
drivers::ModbusConfig robot_controller_config(const format::RigSpec& rig);

/// The register map a robot spec asks for (built-in ur/float32, or its custom registers).
drivers::RegisterMap register_map(const format::RobotControllerSpec& spec, const std::string& rig_source);

/// The robot's forward kinematics for the driver: its DH table through hil::models's robot adapter and
/// calibration's kinematics (the one DH implementation), T_base_tool with tool = T_flange_ee.
drivers::ForwardKinematics forward_kinematics(const format::RobotSpec& robot);

/// T_world_base of the rig's robot (identity without a robot section).
Eigen::Isometry3d world_to_base(const format::RigSpec& rig);

/// A recorded run as the fake rig's scenario: the wrench on the plate, the joints, and the tool
/// (ee) pose in the robot base frame, T_base_ee = T_world_base⁻¹ · T_world_ee.
drivers::Scenario scenario_from_run(const format::Run& run, const Eigen::Isometry3d& T_world_base, bool loop);

}  // namespace hil::rig_service
