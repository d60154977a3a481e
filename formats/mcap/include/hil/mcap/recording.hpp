#pragma once
/// \file hil's samples as an MCAP recording in ROS 2 terms (ros2 bag's own layout): ros2msg
/// schemas, CDR payloads, one channel per topic. See docs/mcap.md.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <hil/format/ros_frames.hpp>
#include <hil/format/run.hpp>
#include <hil/mcap/mcap.hpp>

// Generated bus types (hil::idl): the payloads are their CDR.
#include <optional>

#include "geometry_msgs.h"
#include "hil_msgs.h"
#include "sensor_msgs.h"
#include "tf2_msgs.h"

namespace hil::mcap {

namespace topic {
inline constexpr const char* kWrench = "/hil/wrench";               ///< geometry_msgs/msg/WrenchStamped
inline constexpr const char* kPose = "/hil/pose";                   ///< geometry_msgs/msg/PoseStamped
inline constexpr const char* kJointStates = "/hil/joint_states";    ///< sensor_msgs/msg/JointState
inline constexpr const char* kPoseWrench = "/hil/pose_wrench";      ///< hil_msgs/msg/PoseWrenchSample
inline constexpr const char* kDeviceStatus = "/hil/device_status";  ///< hil_msgs/msg/DeviceStatus
inline constexpr const char* kTfStatic = "/tf_static";              ///< tf2_msgs/msg/TFMessage
inline constexpr const char* kTf = "/tf";                           ///< tf2_msgs/msg/TFMessage: the moving edge
}  // namespace topic

/// The ros2msg schema of `type` ("geometry_msgs/msg/WrenchStamped", ...) as ROS 2 bags store
/// it: the type's definition, then each type it uses once, each after a line of 80 '=' and
/// "MSG: pkg/Type". The hil_msgs texts are ros/hil_msgs/msg/*.msg, embedded at build time.
/// \throws std::invalid_argument for a type this module does not know.
std::string ros2msg_schema(const std::string& type);

/// ROS 2 CDR (encapsulation 00 01 00 00, little endian) of the generated types, and back.
std::string to_cdr(const geometry_msgs::msg::WrenchStamped& m);
std::string to_cdr(const geometry_msgs::msg::PoseStamped& m);
std::string to_cdr(const sensor_msgs::msg::JointState& m);
std::string to_cdr(const hil_msgs::msg::PoseWrenchSample& m);
std::string to_cdr(const hil_msgs::msg::DeviceStatus& m);
/// \throws error::FormatError (naming `where`) on a payload that does not decode.
void from_cdr(const std::string& data, hil_msgs::msg::PoseWrenchSample& m, const std::string& where);
void from_cdr(const std::string& data, hil_msgs::msg::DeviceStatus& m, const std::string& where);
void from_cdr(const std::string& data, geometry_msgs::msg::WrenchStamped& m, const std::string& where);
void from_cdr(const std::string& data, sensor_msgs::msg::JointState& m, const std::string& where);
void from_cdr(const std::string& data, geometry_msgs::msg::PoseStamped& m, const std::string& where);
void from_cdr(const std::string& data, tf2_msgs::msg::TFMessage& m, const std::string& where);

/// tf2_msgs/msg/TFMessage of the rig's static frames, stamped `stamp_ns`.
std::string tf_message_cdr(const std::vector<format::StaticFrame>& frames, std::int64_t stamp_ns);
/// Back (frame poses and their stamps). \throws error::FormatError naming `where`.
std::vector<format::StaticFrame> tf_message_from_cdr(const std::string& data, const std::string& where);

/// builtin_interfaces/Time of a time since the epoch in ns.
builtin_interfaces::msg::Time to_ros_time(std::int64_t t_ns);
/// "2026-11-21T10:00:00.000Z" -> ns since the epoch. \throws std::invalid_argument.
std::int64_t parse_utc_ns(const std::string& iso8601);

/// What the recorder adds to a sample (the extra columns of samples.csv and the sync's bookkeeping).
struct SampleExtras {
  std::uint64_t wrench_seq = 0, pose_seq = 0;
  double wrench_age_s = 0.0, pose_age_s = 0.0;
  std::uint32_t quality = 0;
};

struct RecordingOptions {
  Compression compression = Compression::zstd;
  std::size_t chunk_size_bytes = 1 << 20;
  std::size_t chunk_messages = 0;  ///< 0: chunks close on size only
  bool tf = true;                  ///< the moving edge (format::moving_frame) on /tf with every sample
};

/// Writes the hil channels of one run. The channels are declared at construction (a channel with
/// no messages is still listed: six, and /tf unless RecordingOptions::tf is off) and /tf_static is
/// written once, stamped with the run's start, when a rig is given.
class RunMcapWriter {
 public:
  /// \param rig  may be null: no /tf_static, joints named j1..jN.
  /// \param start_ns  the run's t = 0 (ns since the epoch).
  RunMcapWriter(const std::string& path, const format::RigSpec* rig, std::size_t joint_count, std::int64_t start_ns,
                RecordingOptions options = {});
  ~RunMcapWriter();
  RunMcapWriter(const RunMcapWriter&) = delete;
  RunMcapWriter& operator=(const RunMcapWriter&) = delete;

  /// One sample: /hil/wrench, /hil/pose, /hil/pose_wrench, (with joints) /hil/joint_states and
  /// (RecordingOptions::tf) /tf, all stamped (log and publish time) start + s.t_s. `joints_rad` may be null when the run has none.
  void write_sample(const format::Sample& s, std::uint64_t index, const double* joints_rad, const SampleExtras& extras = {});
  /// One DeviceStatus, logged at its own stamp.
  void write_status(const hil_msgs::msg::DeviceStatus& status);
  /// Closes the open chunk and hands it to the kernel (what a crash would otherwise lose).
  void flush();
  void close();
  std::uint64_t messages() const;

 private:
  std::int64_t stamp_ns(double t_s) const;
  std::unique_ptr<Writer> w_;
  std::int64_t start_ns_;
  std::vector<std::string> joint_names_;
  std::string world_frame_;                       ///< /hil/pose's header.frame_id
  std::optional<format::MovingFrame> tf_moving_;  ///< what /tf carries; none: no /tf channel
  std::uint16_t ch_wrench_ = 0, ch_pose_ = 0, ch_joints_ = 0, ch_sample_ = 0, ch_status_ = 0, ch_tf_ = 0, ch_tf_moving_ = 0;
  std::uint32_t seq_ = 0;
};

/// `hil export RUN --mcap OUT`: the whole run into one file. Device status: the run format keeps
/// none, so the channel is declared with no messages.
void export_run(const format::Run& run, const std::string& out, RecordingOptions options = {});

/// `hil export --recover`: what `file` holds (recover_file's part of a damaged recording) as a
/// complete MCAP file at `out`: its schemas, channels (with their metadata) and messages, in order.
/// \returns the number of messages written.
std::uint64_t rewrite(const File& file, const std::string& out, Compression compression = Compression::zstd);

/// The samples of a recording (its /hil/pose_wrench channel), in file order.
/// \throws error::FormatError when the file has no such channel or a payload does not decode.
std::vector<hil_msgs::msg::PoseWrenchSample> read_pose_wrench(const File& file);

}  // namespace hil::mcap
