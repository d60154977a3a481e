#pragma once
/// \file `hil import BAG`: a recording of standard ROS 2 topics (an MCAP file, or a ros2 bag folder
/// with metadata.yaml and MCAP storage) -> a run folder. The wrench (geometry_msgs/WrenchStamped),
/// pose (geometry_msgs/PoseStamped) and optionally joint (sensor_msgs/JointState) messages become
/// the readings the devices would give, stamped with their header.stamp, and go through the same
/// Synchronizer as a live acquisition: resampled, filtered, decimated and synchronised.
#include <cstdint>
#include <string>
#include <vector>

#include <hil/acquisition/bag_metadata.hpp>
#include <hil/acquisition/sync.hpp>
#include <hil/format/rig.hpp>
#include <hil/mcap/mcap.hpp>

namespace hil::acquisition {

struct RosImportOptions {
  std::string wrench_topic = "/hil/wrench";
  std::string pose_topic = "/hil/pose";
  std::string joints_topic;      ///< empty: no joints
  double output_rate_hz = 50.0;  ///< must divide the wrench rate
  double wrench_rate_hz = 0.0;   ///< 0: the median of the wrench stamps' steps, rounded to 1 Hz
};

/// What the import found and did.
struct RosImportReport {
  std::size_t wrenches = 0, poses = 0, joint_states = 0, samples = 0;
  double wrench_rate_hz = 0.0;
  std::uint64_t gaps = 0;
  std::vector<std::string> files;  ///< the MCAP files read (a bag folder's, in its order)
  std::vector<std::string> joint_names;
};

/// The messages of a recording: an .mcap file, or a ros2 bag folder (metadata.yaml naming MCAP files,
/// read in its order). \throws error::FormatError naming the file and what is wrong (sqlite3
/// storage, file compression, a damaged file).
std::vector<mcap::File> load_ros_recording(const std::string& path);

/// Writes the run folder `out_dir` (refused when it exists and is not empty) from `files`. The wrench
/// must be in the force plate's frame (`force_plate`) and the pose in world (the rig's tf name for
/// it); a message in another frame is an error naming topic, message and frame, an empty frame id is
/// taken as meant. JointState names are matched to the rig's joint names; messages that use none of
/// them (a rig with unnamed joints) are taken in their own order when the count agrees.
/// \throws error::FormatError (input) or std::runtime_error (output).
RosImportReport import_ros_recording(const std::vector<mcap::File>& files, const RosImportOptions& options, const format::RigSpec& rig,
                                     const std::string& rig_yaml_text, const std::string& out_dir);

}  // namespace hil::acquisition
