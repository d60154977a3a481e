#include <hil/acquisition/ros_import.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <hil/acquisition/recorder.hpp>
#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>
#include <hil/mcap/recording.hpp>

namespace hil::acquisition {
namespace fs = std::filesystem;

std::vector<mcap::File> load_ros_recording(const std::string& path) {
  if (!fs::is_directory(path)) return {mcap::read_file(path)};
  const auto meta_path = (fs::path(path) / "metadata.yaml").string();
  if (!fs::exists(meta_path))
    throw error::FormatError({path, 0, 0, ""}, "a folder without metadata.yaml: not a ros2 bag (give the bag folder or an .mcap file)");
  std::ifstream in(meta_path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<mcap::File> files;
  for (const auto& name : parse_bag_metadata(text, meta_path)) {
    const auto file = (fs::path(path) / name).string();
    if (!fs::exists(file)) throw error::FormatError({meta_path, 0, 0, "relative_file_paths"}, "no such file: " + file);
    files.push_back(mcap::read_file(file));
  }
  return files;
}

namespace {

std::int64_t stamp_ns(const builtin_interfaces::msg::Time& t) { return static_cast<std::int64_t>(t.sec()) * 1'000'000'000 + t.nanosec(); }

/// Every message of `topic` over the files, decoded, with where it is for errors.
template <class Msg>
std::vector<std::pair<Msg, std::string>> decode_all(const std::vector<mcap::File>& files, const std::string& topic,
                                                    const std::string& type) {
  std::vector<std::pair<Msg, std::string>> out;
  bool found = false;
  for (const auto& f : files) {
    const auto* ch = f.channel(topic);
    if (!ch) continue;
    found = true;
    const auto* schema = f.schema(ch->schema_id);
    if (ch->message_encoding != "cdr" || !schema || schema->name != type)
      throw error::FormatError({f.path, 0, 0, topic},
                               fmt::format("{} is {} ({}), expected {} (cdr)", topic, schema ? schema->name : std::string("schemaless"),
                                           ch->message_encoding, type));
    std::size_t i = 0;
    for (const auto* m : f.messages_on(topic)) {
      const auto where = fmt::format("{}: {} message {}", f.path, topic, i++);
      Msg msg;
      mcap::from_cdr(m->data, msg, where);
      out.emplace_back(std::move(msg), where);
    }
  }
  if (!found) {
    std::string topics;
    for (const auto& f : files)
      for (const auto& c : f.channels) topics += (topics.empty() ? "" : ", ") + c.topic;
    throw error::FormatError({files.front().path, 0, 0, topic}, fmt::format("no topic {} (the recording has: {})", topic, topics));
  }
  return out;
}

void check_frame(const std::string& where, const std::string& frame, const std::string& expected) {
  if (!frame.empty() && frame != expected)
    throw error::FormatError({where, 0, 0, "header.frame_id"},
                             fmt::format("frame '{}', expected '{}' (hil transforms nothing on import)", frame, expected));
}

}  // namespace

RosImportReport import_ros_recording(const std::vector<mcap::File>& files, const RosImportOptions& o, const format::RigSpec& rig,
                                     const std::string& rig_yaml_text, const std::string& out_dir) {
  RosImportReport rep;
  for (const auto& f : files) rep.files.push_back(f.path);
  if (files.empty()) throw error::FormatError({out_dir, 0, 0, ""}, "no recording to import");
  const auto wrenches = decode_all<geometry_msgs::msg::WrenchStamped>(files, o.wrench_topic, "geometry_msgs/msg/WrenchStamped");
  const auto poses = decode_all<geometry_msgs::msg::PoseStamped>(files, o.pose_topic, "geometry_msgs/msg/PoseStamped");
  std::vector<std::pair<sensor_msgs::msg::JointState, std::string>> joints;
  if (!o.joints_topic.empty()) joints = decode_all<sensor_msgs::msg::JointState>(files, o.joints_topic, "sensor_msgs/msg/JointState");
  if (wrenches.size() < 2 || poses.size() < 2)
    throw error::FormatError({files.front().path, 0, 0, ""},
                             fmt::format("{} wrench and {} pose messages: at least two of each are needed", wrenches.size(), poses.size()));

  // Readings, each stream in stamp order (a bag keeps arrival order; stamps are the sensor's).
  std::vector<WrenchReading> w;
  for (const auto& [m, where] : wrenches) {
    check_frame(where, m.header().frame_id(), "force_plate");
    WrenchReading r;
    r.t_ns = stamp_ns(m.header().stamp());
    r.seq = w.size();
    const auto& f = m.wrench().force();
    const auto& t = m.wrench().torque();
    r.wrench_fp << f.x(), f.y(), f.z(), t.x(), t.y(), t.z();
    if (!r.wrench_fp.allFinite()) throw error::FormatError({where, 0, 0, "wrench"}, "a value that is not finite");
    w.push_back(r);
  }
  std::stable_sort(w.begin(), w.end(), [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });

  // Joints: the rig's names where it names them, else the first message's order; each pose takes
  // the last joint state at or before its stamp (robot drivers publish both from one poll).
  std::vector<std::pair<std::int64_t, Eigen::VectorXd>> q;
  if (!joints.empty()) {
    // The rig's names when the messages use them; when they use none of them (a rig whose joints
    // are unnamed, j1..jN), the messages' own order if the count agrees.
    const auto& first = joints.front().first.name();
    std::vector<std::string> names;
    if (rig.robot)
      for (const auto& j : rig.robot->joints) names.push_back(j.name);
    const auto known = std::count_if(names.begin(), names.end(),
                                     [&](const auto& n) { return std::find(first.begin(), first.end(), n) != first.end(); });
    if (names.empty() || known == 0) {
      if (rig.robot && first.size() != names.size())
        throw error::FormatError({joints.front().second, 0, 0, "name"},
                                 fmt::format("{} joints, the rig's robot has {}", first.size(), names.size()));
      names = first;
    }
    rep.joint_names = names;
    for (const auto& [m, where] : joints) {
      if (m.position().size() != m.name().size())
        throw error::FormatError({where, 0, 0, "position"}, fmt::format("{} positions for {} names", m.position().size(), m.name().size()));
      Eigen::VectorXd v(static_cast<Eigen::Index>(names.size()));
      for (std::size_t k = 0; k < names.size(); ++k) {
        const auto it = std::find(m.name().begin(), m.name().end(), names[k]);
        if (it == m.name().end()) throw error::FormatError({where, 0, 0, "name"}, fmt::format("no joint '{}' in this message", names[k]));
        v[static_cast<Eigen::Index>(k)] = m.position()[static_cast<std::size_t>(it - m.name().begin())];
      }
      q.emplace_back(stamp_ns(m.header().stamp()), v);
    }
    std::stable_sort(q.begin(), q.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  const auto world = rig.tf.world;
  std::vector<PoseReading> p;
  for (const auto& [m, where] : poses) {
    check_frame(where, m.header().frame_id(), world);
    PoseReading r;
    r.t_ns = stamp_ns(m.header().stamp());
    r.seq = p.size();
    const auto& pos = m.pose().position();
    const auto& ori = m.pose().orientation();
    r.p_world_ee_m = {pos.x(), pos.y(), pos.z()};
    r.q_world_ee = Eigen::Quaterniond(ori.w(), ori.x(), ori.y(), ori.z());
    const double norm = r.q_world_ee.norm();
    if (!r.p_world_ee_m.allFinite() || !std::isfinite(norm) || std::abs(norm - 1.0) > 1e-6)
      throw error::FormatError({where, 0, 0, "pose"}, fmt::format("not a pose: position finite, unit quaternion (norm {:.9g})", norm));
    r.q_world_ee.normalize();
    if (!q.empty()) {
      auto it = std::upper_bound(q.begin(), q.end(), r.t_ns, [](std::int64_t t, const auto& e) { return t < e.first; });
      r.joints_rad = it == q.begin() ? q.front().second : std::prev(it)->second;
    }
    p.push_back(r);
  }
  std::stable_sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });

  // The nominal wrench rate: the median step, to the nearest Hz, unless given.
  double rate = o.wrench_rate_hz;
  if (rate <= 0) {
    std::vector<std::int64_t> steps;
    for (std::size_t i = 1; i < w.size(); ++i) steps.push_back(w[i].t_ns - w[i - 1].t_ns);
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    const auto median = steps[steps.size() / 2];
    if (median <= 0) throw error::FormatError({o.wrench_topic, 0, 0, "header.stamp"}, "most wrench messages share one stamp");
    rate = std::round(1e9 / static_cast<double>(median));
  }
  rep.wrench_rate_hz = rate;
  SyncConfig sc;
  sc.wrench_rate_hz = rate;
  sc.output_rate_hz = o.output_rate_hz;
  const double ratio = rate / o.output_rate_hz;
  if (ratio < 1 || std::abs(ratio - std::round(ratio)) > 1e-9)
    throw error::FormatError({"command line", 0, 0, "--rate"},
                             fmt::format("the output rate {} Hz does not divide the wrench rate {} Hz{}", o.output_rate_hz, rate,
                                         o.wrench_rate_hz > 0 ? "" : " (measured; give --wrench-rate if that is wrong)"));

  format::RunInfo info;
  info.rig = rig.name;
  info.output_rate_hz = o.output_rate_hz;
  info.sources = {{o.wrench_topic, "import", rate, "", {}}, {o.pose_topic, "import", 0.0, "", {}}};
  const std::int64_t start_ns = std::min(w.front().t_ns, p.front().t_ns);
  RunRecorder rec(out_dir, info, rig_yaml_text, start_ns, rep.joint_names.size());
  Synchronizer sync(sc, [&](const SyncedSample& s) { rec.append(s); });
  // Both streams in stamp order, as a live acquisition would see them arrive.
  std::size_t i = 0, k = 0;
  while (i < w.size() || k < p.size()) {
    if (k == p.size() || (i < w.size() && w[i].t_ns <= p[k].t_ns)) sync.push_wrench(w[i++]);
    else sync.push_pose(p[k++]);
  }
  sync.flush();
  rep.wrenches = w.size();
  rep.poses = p.size();
  rep.joint_states = joints.size();
  rep.samples = rec.rows();
  rep.gaps = rec.gaps();
  std::string files_text;
  for (const auto& f : rep.files) files_text += (files_text.empty() ? "" : ", ") + f;
  rec.close(fmt::format("imported from {}: {} wrench ({} Hz), {} pose{} messages -> {} samples at {} Hz", files_text, rep.wrenches, rate,
                        rep.poses, joints.empty() ? "" : fmt::format(", {} joint state", joints.size()), rep.samples, o.output_rate_hz));
  return rep;
}

}  // namespace hil::acquisition
