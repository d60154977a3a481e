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

/// The rig's fixed frames, parents before children, named as on ROS topics (RigSpec::tf): every
/// entry of `frames`, then the robot's base in world when the rig has a robot. The moving edge
/// (moving_frame) is not included.
std::vector<StaticFrame> static_frames(const RigSpec& rig);

/// The moving edge of the tree, one transform per sample on /tf: robot base -> ee when the rig has a
/// robot (the static tree holds world -> base), else world -> ee. Without a rig: `world` -> `ee`.
struct MovingFrame {
  std::string parent;
  std::string child;
  Eigen::Isometry3d T_parent_world = Eigen::Isometry3d::Identity();
  /// The edge for a sample whose pose is `T_world_ee`.
  StaticFrame at(const Pose& T_world_ee) const;
};
MovingFrame moving_frame(const RigSpec* rig);

/// Joint names for `count` joints: the rig's `robot.joints[i].name` where given, else `j1..jN`
/// (the samples.csv column names). Joints beyond the rig's table are named `jK` as well.
std::vector<std::string> joint_names(const RigSpec& rig, std::size_t count);
std::vector<std::string> joint_names(const RigSpec* rig, std::size_t count);

}  // namespace hil::format
