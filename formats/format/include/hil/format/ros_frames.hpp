#pragma once
/// \file What a rig file says in ROS terms: the static transforms of its frames (for /tf_static)
/// and the names of its joints (for sensor_msgs/JointState). Shared by the DDS publisher and the
/// MCAP writer so both announce the same tree.
#include <string>
#include <vector>

#include <hil/format/rig.hpp>

namespace hil::format {

/// One edge of the frame tree: the pose of `child` in `parent` (tf's header.frame_id and
/// child_frame_id).
struct StaticFrame {
  std::string parent;
  std::string child;
  Pose T_parent_child;
};

/// The rig's fixed frames, parents before children: every entry of `frames`, then the robot's
/// base in world (`robot_base`) when the rig has a robot. The moving `world` -> `ee` transform
/// is not static and is not included (it is the sample's pose).
std::vector<StaticFrame> static_frames(const RigSpec& rig);

/// Joint names for `count` joints: the rig's `robot.joints[i].name` where given, else `j1..jN`
/// (the samples.csv column names). Joints beyond the rig's table are named `jK` as well.
std::vector<std::string> joint_names(const RigSpec& rig, std::size_t count);
std::vector<std::string> joint_names(const RigSpec* rig, std::size_t count);

}  // namespace hil::format
