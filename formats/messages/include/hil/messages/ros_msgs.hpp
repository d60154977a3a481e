#pragma once
/// \file hil's data in the messages ROS 2 tools expect on their well-known topics: the rig's fixed
/// frames as a tf2 message (/tf_static), device health as diagnostics (/diagnostics, seen by
/// rqt_robot_monitor and diagnostic_aggregator), joints as sensor_msgs/JointState. Pure functions.
#include <cstdint>
#include <string>
#include <vector>

#include <hil/dds/types.hpp>
#include <hil/format/ros_frames.hpp>

namespace hil::messages {

/// All the rig's fixed frames in one TFMessage, each transform stamped `stamp` (tf2's static
/// broadcaster sends them together, so a late-joining listener gets the whole tree in one sample).
tf2_msgs::msg::TFMessage to_tf_message(const std::vector<format::StaticFrame>& frames, const builtin_interfaces::msg::Time& stamp);

/// The diagnostic level of a DeviceStatus state: ok -> OK, degraded -> WARN, fault and
/// disconnected -> ERROR; a state hil does not know -> STALE.
std::uint8_t diagnostic_level(std::uint8_t device_state);

/// One device's status as ROS diagnostics: name `hil/<device>`, the given hardware id, the message
/// "ok" when ok, else the reason (DeviceStatus.last_error) or the state's name; values rate_hz,
/// samples, frames_dropped, errors, last_sample_age_s (-1 before the first sample), connected,
/// state, and last_error when there is one.
diagnostic_msgs::msg::DiagnosticStatus to_diagnostic_status(const hil_msgs::msg::DeviceStatus& s, const std::string& hardware_id);

/// A JointState of the sample's joints under `names` (one per joint; missing names become jK).
sensor_msgs::msg::JointState to_joint_state(const hil_msgs::msg::PoseWrenchSample& m, const std::vector<std::string>& names);

}  // namespace hil::messages
