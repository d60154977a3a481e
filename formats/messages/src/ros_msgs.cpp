#include <hil/messages/ros_msgs.hpp>

#include <fmt/format.h>

namespace hil::messages {

tf2_msgs::msg::TFMessage to_tf_message(const std::vector<format::StaticFrame>& frames, const builtin_interfaces::msg::Time& stamp) {
  tf2_msgs::msg::TFMessage m;
  m.transforms().reserve(frames.size());
  for (const auto& f : frames) {
    geometry_msgs::msg::TransformStamped t;
    t.header().stamp(stamp);
    t.header().frame_id(f.parent);
    t.child_frame_id(f.child);
    const auto& p = f.T_parent_child.translation_m;
    t.transform().translation().x(p.x());
    t.transform().translation().y(p.y());
    t.transform().translation().z(p.z());
    const auto q = f.T_parent_child.rotation.normalized();
    t.transform().rotation().x(q.x());
    t.transform().rotation().y(q.y());
    t.transform().rotation().z(q.z());
    t.transform().rotation().w(q.w());
    m.transforms().push_back(std::move(t));
  }
  return m;
}

std::uint8_t diagnostic_level(std::uint8_t device_state) {
  namespace level = diagnostic_msgs::msg::DiagnosticStatus_Constants;
  switch (device_state) {
    case hil_msgs::msg::DEVICE_OK: return level::OK;
    case hil_msgs::msg::DEVICE_DEGRADED: return level::WARN;
    case hil_msgs::msg::DEVICE_FAULT:
    case hil_msgs::msg::DEVICE_DISCONNECTED: return level::ERROR;
    default: return level::STALE;
  }
}

namespace {
const char* state_name(std::uint8_t state) {
  switch (state) {
    case hil_msgs::msg::DEVICE_OK: return "ok";
    case hil_msgs::msg::DEVICE_DEGRADED: return "degraded";
    case hil_msgs::msg::DEVICE_FAULT: return "fault";
    case hil_msgs::msg::DEVICE_DISCONNECTED: return "disconnected";
    default: return "unknown";
  }
}

diagnostic_msgs::msg::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::msg::KeyValue v;
  v.key(key);
  v.value(value);
  return v;
}
}  // namespace

diagnostic_msgs::msg::DiagnosticStatus to_diagnostic_status(const hil_msgs::msg::DeviceStatus& s, const std::string& hardware_id) {
  diagnostic_msgs::msg::DiagnosticStatus d;
  d.level(diagnostic_level(s.state()));
  d.name("hil/" + s.device());
  d.hardware_id(hardware_id);
  // An ok device's last_error is history (kept in the values); a device in trouble says why.
  if (s.state() == hil_msgs::msg::DEVICE_OK) d.message("ok");
  else d.message(s.last_error().empty() ? std::string(state_name(s.state())) : s.last_error());
  // Numbers in their shortest exact form, so a monitor can parse them back.
  auto& v = d.values();
  v.push_back(kv("rate_hz", fmt::format("{}", s.rate_hz())));
  v.push_back(kv("samples", fmt::format("{}", s.samples())));
  v.push_back(kv("frames_dropped", fmt::format("{}", s.frames_dropped())));
  v.push_back(kv("errors", fmt::format("{}", s.errors())));
  v.push_back(kv("device_faults", fmt::format("{}", s.device_faults())));
  v.push_back(kv("last_sample_age_s", fmt::format("{}", s.last_sample_age_s())));
  v.push_back(kv("connected", s.connected() ? "true" : "false"));
  v.push_back(kv("state", state_name(s.state())));
  if (!s.last_error().empty()) v.push_back(kv("last_error", s.last_error()));
  return d;
}

sensor_msgs::msg::JointState to_joint_state(const hil_msgs::msg::PoseWrenchSample& m, const std::vector<std::string>& names) {
  sensor_msgs::msg::JointState j;
  j.header(m.header());
  j.header().frame_id("");  // joint states carry no frame
  const auto& q = m.joint_positions_rad();
  std::vector<std::string> n(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) n[i] = i < names.size() && !names[i].empty() ? names[i] : "j" + std::to_string(i + 1);
  j.name(std::move(n));
  j.position(q);
  return j;
}

}  // namespace hil::messages
