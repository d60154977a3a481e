// hil samples -> ROS 2 channels of an MCAP file.
#include <hil/mcap/recording.hpp>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <ctime>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>

#include <hil/dds/qos.hpp>
#include <hil/messages/ros_msgs.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/error/error.hpp>
#include "hil_msgs_schemas.hpp"

namespace hil::mcap {
namespace {

// ROS 2 (Humble) message definitions, field lines as in their .msg files (comments shortened).
struct MsgDef {
  const char* text;
  std::vector<std::string> uses;  // types this one refers to, "pkg/msg/Type"
};

const std::map<std::string, MsgDef>& definitions() {
  static const std::map<std::string, MsgDef> defs = {
      {"builtin_interfaces/msg/Time",
       {"# This message communicates ROS Time defined here:\n"
        "# https://design.ros2.org/articles/clock_and_time.html\n\n"
        "# The seconds component, valid over all int32 values.\n"
        "int32 sec\n\n"
        "# The nanoseconds component, valid in the range [0, 10e9).\n"
        "uint32 nanosec\n",
        {}}},
      {"std_msgs/msg/Header",
       {"# Standard metadata for higher-level stamped data types.\n\n"
        "# Two-integer timestamp that is expressed as seconds and nanoseconds.\n"
        "builtin_interfaces/Time stamp\n\n"
        "# Transform frame with which this data is associated.\n"
        "string frame_id\n",
        {"builtin_interfaces/msg/Time"}}},
      {"geometry_msgs/msg/Vector3",
       {"# This represents a vector in free space.\n\n"
        "float64 x\nfloat64 y\nfloat64 z\n",
        {}}},
      {"geometry_msgs/msg/Point",
       {"# This contains the position of a point in free space\n"
        "float64 x\nfloat64 y\nfloat64 z\n",
        {}}},
      {"geometry_msgs/msg/Quaternion",
       {"# This represents an orientation in free space in quaternion form.\n\n"
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
        {}}},
      {"geometry_msgs/msg/Pose",
       {"# A representation of pose in free space, composed of position and orientation.\n\n"
        "Point position\nQuaternion orientation\n",
        {"geometry_msgs/msg/Point", "geometry_msgs/msg/Quaternion"}}},
      {"geometry_msgs/msg/PoseStamped",
       {"# A Pose with reference coordinate frame and timestamp\n\n"
        "std_msgs/Header header\nPose pose\n",
        {"std_msgs/msg/Header", "geometry_msgs/msg/Pose"}}},
      {"geometry_msgs/msg/Twist",
       {"# This expresses velocity in free space broken into its linear and angular parts.\n\n"
        "Vector3  linear\nVector3  angular\n",
        {"geometry_msgs/msg/Vector3"}}},
      {"geometry_msgs/msg/Wrench",
       {"# This represents force in free space, separated into its linear and angular parts.\n\n"
        "Vector3  force\nVector3  torque\n",
        {"geometry_msgs/msg/Vector3"}}},
      {"geometry_msgs/msg/WrenchStamped",
       {"# A wrench with reference coordinate frame and timestamp\n\n"
        "std_msgs/Header header\nWrench wrench\n",
        {"std_msgs/msg/Header", "geometry_msgs/msg/Wrench"}}},
      {"geometry_msgs/msg/Transform",
       {"# This represents the transform between two coordinate frames in free space.\n\n"
        "Vector3 translation\nQuaternion rotation\n",
        {"geometry_msgs/msg/Vector3", "geometry_msgs/msg/Quaternion"}}},
      {"geometry_msgs/msg/TransformStamped",
       {"# This expresses a transform from coordinate frame header.frame_id\n"
        "# to the coordinate frame child_frame_id at the time of header.stamp\n\n"
        "std_msgs/Header header\n\n"
        "# The frame id of the child frame to which this transform points.\n"
        "string child_frame_id\n\n"
        "# Translation and rotation in 3-dimensions of child_frame_id from header.frame_id.\n"
        "Transform transform\n",
        {"std_msgs/msg/Header", "geometry_msgs/msg/Transform"}}},
      {"tf2_msgs/msg/TFMessage", {"geometry_msgs/TransformStamped[] transforms\n", {"geometry_msgs/msg/TransformStamped"}}},
      {"sensor_msgs/msg/JointState",
       {"# This is a message that holds data to describe the state of a set of torque controlled joints.\n"
        "# Units: position in rad or m, velocity in rad/s or m/s, effort in Nm or N.\n"
        "# All arrays in this message should have the same size, or be empty.\n\n"
        "std_msgs/Header header\n\n"
        "string[] name\n"
        "float64[] position\n"
        "float64[] velocity\n"
        "float64[] effort\n",
        {"std_msgs/msg/Header"}}},
      {"hil_msgs/msg/PoseWrenchSample",
       {generated::kPoseWrenchSampleMsg,
        {"std_msgs/msg/Header", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Twist", "geometry_msgs/msg/Wrench"}}},
      {"hil_msgs/msg/DeviceStatus", {generated::kDeviceStatusMsg, {"builtin_interfaces/msg/Time"}}},
  };
  return defs;
}

const MsgDef& definition(const std::string& type) {
  const auto& defs = definitions();
  const auto it = defs.find(type);
  if (it == defs.end()) throw std::invalid_argument("mcap: no ros2msg definition for " + type);
  return it->second;
}

// ---- CDR -------------------------------------------------------------------------------------

template <class T>
std::string encode(const T& m) {
  eprosima::fastcdr::FastBuffer buf;  // grows as needed
  eprosima::fastcdr::Cdr cdr(buf, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR);
  cdr.serialize_encapsulation();  // 00 01 00 00: CDR, little endian
  m.serialize(cdr);
  return std::string(buf.getBuffer(), cdr.getSerializedDataLength());
}

template <class T>
void decode(const std::string& data, T& m, const std::string& where) {
  std::string copy = data;  // FastBuffer wants a mutable buffer
  eprosima::fastcdr::FastBuffer buf(copy.data(), copy.size());
  eprosima::fastcdr::Cdr cdr(buf, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.read_encapsulation();
    m.deserialize(cdr);
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    throw error::FormatError({where, 0, 0, ""}, fmt::format("CDR payload of {} bytes does not decode: {}", data.size(), e.what()));
  }
}

/// The ros2 profile's required channel metadata: the publisher's QoS as rosbag2 records it
/// (YAML, Humble's numeric enums, which later distributions still read): reliable, and
/// transient_local for /tf_static so that `ros2 bag play` latches it as tf2 expects.
/// rosbag2's offered_qos_profiles (Humble's YAML) of the live writer of `topic` (/x -> rt/x in
/// dds::qos_table()): history 1 keep last, 2 keep all; reliability 1 reliable, 2 best effort;
/// durability 1 transient local, 2 volatile (rmw's enums).
std::string offered_qos(const std::string& topic) {
  const auto q = dds::qos_of("rt" + topic);
  constexpr const char* kForever = "    sec: 2147483647\n    nsec: 4294967295\n";
  return fmt::format("- history: {}\n  depth: {}\n  reliability: {}\n  durability: {}\n  deadline:\n{}  lifespan:\n{}"
                     "  liveliness: 1\n  liveliness_lease_duration:\n{}  avoid_ros_namespace_conventions: false",
                     q.history_depth > 0 ? 1 : 2, q.history_depth, q.reliable ? 1 : 2, q.durable_depth > 0 ? 1 : 2, kForever, kForever,
                     kForever);
}

}  // namespace

std::string ros2msg_schema(const std::string& type) {
  std::string out = definition(type).text;
  // Dependencies depth first, each once, as rosbag2 writes them.
  std::set<std::string> seen{type};
  std::function<void(const std::string&)> add = [&](const std::string& t) {
    for (const auto& dep : definition(t).uses) {
      if (!seen.insert(dep).second) continue;
      const auto slash = dep.find("/msg/");
      out += "\n================================================================================\n";
      out += "MSG: " + dep.substr(0, slash) + "/" + dep.substr(slash + 5) + "\n";
      out += definition(dep).text;
      add(dep);
    }
  };
  add(type);
  return out;
}

std::string to_cdr(const geometry_msgs::msg::WrenchStamped& m) { return encode(m); }
std::string to_cdr(const geometry_msgs::msg::PoseStamped& m) { return encode(m); }
std::string to_cdr(const sensor_msgs::msg::JointState& m) { return encode(m); }
std::string to_cdr(const hil_msgs::msg::PoseWrenchSample& m) { return encode(m); }
std::string to_cdr(const hil_msgs::msg::DeviceStatus& m) { return encode(m); }
void from_cdr(const std::string& d, hil_msgs::msg::PoseWrenchSample& m, const std::string& w) { decode(d, m, w); }
void from_cdr(const std::string& d, hil_msgs::msg::DeviceStatus& m, const std::string& w) { decode(d, m, w); }
void from_cdr(const std::string& d, geometry_msgs::msg::WrenchStamped& m, const std::string& w) { decode(d, m, w); }
void from_cdr(const std::string& d, sensor_msgs::msg::JointState& m, const std::string& w) { decode(d, m, w); }
void from_cdr(const std::string& d, geometry_msgs::msg::PoseStamped& m, const std::string& w) { decode(d, m, w); }
void from_cdr(const std::string& d, tf2_msgs::msg::TFMessage& m, const std::string& w) { decode(d, m, w); }

std::string tf_message_cdr(const std::vector<format::StaticFrame>& frames, std::int64_t stamp_ns) {
  return encode(messages::to_tf_message(frames, to_ros_time(stamp_ns)));  // the messages /tf_static and /tf carry on DDS
}

std::vector<format::StaticFrame> tf_message_from_cdr(const std::string& data, const std::string& where) {
  tf2_msgs::msg::TFMessage m;
  decode(data, m, where);
  std::vector<format::StaticFrame> out;
  out.reserve(m.transforms().size());
  for (const auto& t : m.transforms()) {
    format::StaticFrame f;
    f.parent = t.header().frame_id();
    f.child = t.child_frame_id();
    const auto& p = t.transform().translation();
    const auto& q = t.transform().rotation();
    f.T_parent_child.translation_m = {p.x(), p.y(), p.z()};
    f.T_parent_child.rotation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
    out.push_back(std::move(f));
  }
  return out;
}

builtin_interfaces::msg::Time to_ros_time(std::int64_t t_ns) { return messages::to_time_ns(t_ns); }

std::int64_t parse_utc_ns(const std::string& s) {
  std::tm tm{};
  int consumed = 0;
  if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour, &tm.tm_min, &tm.tm_sec,
                  &consumed) != 6 ||
      consumed != 19)
    throw std::invalid_argument("not an ISO 8601 UTC time: '" + s + "'");
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  std::int64_t frac_ns = 0;
  std::size_t i = 19;
  if (i < s.size() && s[i] == '.') {
    std::int64_t scale = 100'000'000;
    for (++i; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); ++i, scale /= 10) frac_ns += (s[i] - '0') * scale;
  }
  if (i + 1 != s.size() || s[i] != 'Z') throw std::invalid_argument("not an ISO 8601 UTC time (ends with Z): '" + s + "'");
  return static_cast<std::int64_t>(timegm(&tm)) * 1'000'000'000 + frac_ns;
}

// ---- RunMcapWriter ---------------------------------------------------------------------------

RunMcapWriter::RunMcapWriter(const std::string& path, const format::RigSpec* rig, std::size_t joint_count, std::int64_t start_ns,
                             RecordingOptions options)
    : start_ns_(start_ns), joint_names_(format::joint_names(rig, joint_count)), world_frame_(rig ? rig->tf.world : "world") {
  if (options.tf) tf_moving_ = format::moving_frame(rig);
  WriterOptions wo;
  wo.compression = options.compression;
  wo.chunk_size_bytes = options.chunk_size_bytes;
  wo.chunk_messages = options.chunk_messages;
  wo.profile = "ros2";  // ros2 bag's profile: ros2msg schemas, cdr messages
  wo.library = "hil " HIL_MCAP_VERSION;
  w_ = std::make_unique<Writer>(path, wo);
  auto channel = [&](const char* type, const char* topic) {
    return w_->add_channel(w_->add_schema(type, "ros2msg", ros2msg_schema(type)), topic, "cdr",
                           {{"offered_qos_profiles", offered_qos(topic)}});
  };
  ch_wrench_ = channel("geometry_msgs/msg/WrenchStamped", topic::kWrench);
  ch_pose_ = channel("geometry_msgs/msg/PoseStamped", topic::kPose);
  ch_joints_ = channel("sensor_msgs/msg/JointState", topic::kJointStates);
  ch_sample_ = channel("hil_msgs/msg/PoseWrenchSample", topic::kPoseWrench);
  ch_status_ = channel("hil_msgs/msg/DeviceStatus", topic::kDeviceStatus);
  ch_tf_ = channel("tf2_msgs/msg/TFMessage", topic::kTfStatic);
  if (tf_moving_) ch_tf_moving_ = channel("tf2_msgs/msg/TFMessage", topic::kTf);
  if (rig) {
    const auto frames = format::static_frames(*rig);
    const auto t = static_cast<std::uint64_t>(start_ns_);
    w_->write({ch_tf_, seq_++, t, t, tf_message_cdr(frames, start_ns_)});
  }
}

RunMcapWriter::~RunMcapWriter() = default;  // the Writer closes the file

std::int64_t RunMcapWriter::stamp_ns(double t_s) const { return start_ns_ + static_cast<std::int64_t>(std::llround(t_s * 1e9)); }

void RunMcapWriter::write_sample(const format::Sample& s, std::uint64_t index, const double* joints_rad, const SampleExtras& x) {
  const auto t_ns = stamp_ns(s.t_s);
  const auto stamp = to_ros_time(t_ns);
  const auto t = static_cast<std::uint64_t>(t_ns);
  // The same messages the rig service publishes on DDS (acquisition's conversions), stamped with
  // the sample's absolute time.
  const Eigen::Index n_joints = joints_rad ? static_cast<Eigen::Index>(joint_names_.size()) : 0;
  auto m = messages::to_message(s, index, Eigen::Map<const Eigen::RowVectorXd>(joints_rad, n_joints));
  m.header().stamp(stamp);
  m.wrench_seq(x.wrench_seq);
  m.pose_seq(x.pose_seq);
  m.wrench_age_s(x.wrench_age_s);
  m.pose_age_s(x.pose_age_s);
  m.quality_flags(x.quality);

  geometry_msgs::msg::WrenchStamped ws;
  ws.header().stamp(stamp);
  ws.header().frame_id("force_plate");
  ws.wrench(m.wrench_fp());
  w_->write({ch_wrench_, seq_++, t, t, to_cdr(ws)});

  geometry_msgs::msg::PoseStamped ps;
  ps.header(m.header());
  ps.header().frame_id(world_frame_);
  ps.pose(m.pose_world_ee());
  w_->write({ch_pose_, seq_++, t, t, to_cdr(ps)});
  if (tf_moving_) {
    format::Pose T_world_ee;
    T_world_ee.translation_m = s.p_world_ee_m;
    T_world_ee.rotation = s.q_world_ee;
    w_->write({ch_tf_moving_, seq_++, t, t, tf_message_cdr({tf_moving_->at(T_world_ee)}, t_ns)});
  }

  if (n_joints > 0) w_->write({ch_joints_, seq_++, t, t, to_cdr(messages::to_joint_state(m, joint_names_))});
  w_->write({ch_sample_, seq_++, t, t, to_cdr(m)});
}

void RunMcapWriter::write_status(const hil_msgs::msg::DeviceStatus& status) {
  const auto t = static_cast<std::uint64_t>(static_cast<std::int64_t>(status.stamp().sec()) * 1'000'000'000 + status.stamp().nanosec());
  w_->write({ch_status_, seq_++, t, t, to_cdr(status)});
}

void RunMcapWriter::flush() { w_->flush(); }
void RunMcapWriter::close() { w_->close(); }
std::uint64_t RunMcapWriter::messages() const { return w_->messages(); }

void export_run(const format::Run& run, const std::string& out, RecordingOptions options) {
  std::int64_t start_ns = 0;
  try {
    start_ns = parse_utc_ns(run.info.start_time_utc);
  } catch (const std::invalid_argument& e) {
    throw error::FormatError({run.dir + "/run.yaml", 0, 0, "start_time"}, e.what());
  }
  const auto& t = run.samples;
  RunMcapWriter w(out, run.rig ? &*run.rig : nullptr, t.joint_count(), start_ns, options);
  std::vector<double> joints(t.joint_count());
  for (std::size_t i = 0; i < t.size(); ++i) {
    for (std::size_t j = 0; j < joints.size(); ++j) joints[j] = t.joints_rad(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    w.write_sample(t.samples[i], i, joints.empty() ? nullptr : joints.data());
  }
  w.close();
}

std::uint64_t rewrite(const File& file, const std::string& out, Compression compression) {
  WriterOptions wo;
  wo.compression = compression;
  wo.profile = file.header.profile;
  wo.library = file.header.library.empty() ? "hil " HIL_MCAP_VERSION : file.header.library;
  Writer w(out, wo);
  // Ids are the writer's own (1, 2, ... and 0, 1, ...): map the file's onto them.
  std::map<std::uint16_t, std::uint16_t> schema_id, channel_id;
  for (const auto& s : file.schemas) schema_id[s.id] = w.add_schema(s.name, s.encoding, s.data);
  for (const auto& c : file.channels)
    channel_id[c.id] = w.add_channel(c.schema_id == 0 ? 0 : schema_id.at(c.schema_id), c.topic, c.message_encoding, c.metadata);
  for (const auto& m : file.messages) {
    auto copy = m;
    copy.channel_id = channel_id.at(m.channel_id);
    w.write(copy);
  }
  w.close();
  return w.messages();
}

std::vector<hil_msgs::msg::PoseWrenchSample> read_pose_wrench(const File& file) {
  const auto* ch = file.channel(topic::kPoseWrench);
  if (!ch) throw error::FormatError({file.path, 0, 0, ""}, fmt::format("no {} channel: not a hil recording", topic::kPoseWrench));
  const auto* schema = file.schema(ch->schema_id);
  if (ch->message_encoding != "cdr" || !schema || schema->name != "hil_msgs/msg/PoseWrenchSample")
    throw error::FormatError({file.path, 0, 0, ""},
                             fmt::format("{} is not hil_msgs/msg/PoseWrenchSample in cdr (schema '{}', encoding '{}')", topic::kPoseWrench,
                                         schema ? schema->name : std::string("none"), ch->message_encoding));
  std::vector<hil_msgs::msg::PoseWrenchSample> out;
  for (const auto* m : file.messages_on(topic::kPoseWrench)) {
    out.emplace_back();
    from_cdr(m->data, out.back(), fmt::format("{}: {} message {}", file.path, topic::kPoseWrench, out.size() - 1));
  }
  return out;
}

}  // namespace hil::mcap
