// The pure mappings behind hil's ROS 2 topics: device health -> diagnostic_msgs, the rig's frames ->
// one tf2 message, joints -> sensor_msgs/JointState with the rig's names.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <string>

#include <hil/dds/qos.hpp>
#include <hil/messages/ros_msgs.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/format/rig.hpp>

using namespace hil;
namespace level = diagnostic_msgs::msg::DiagnosticStatus_Constants;

namespace {

hil_msgs::msg::DeviceStatus status(std::uint8_t state, const std::string& last_error) {
  hil_msgs::msg::DeviceStatus s;
  s.stamp(messages::to_time(1700000000.25));
  s.device("force_plate");
  s.state(state);
  s.connected(state != hil_msgs::msg::DEVICE_DISCONNECTED);
  s.rate_hz(999.5);
  s.last_sample_age_s(0.0012);
  s.samples(123456);
  s.frames_dropped(7);
  s.errors(2);
  s.device_faults(5);
  s.last_error(last_error);
  return s;
}

std::map<std::string, std::string> values(const diagnostic_msgs::msg::DiagnosticStatus& d) {
  std::map<std::string, std::string> out;
  for (const auto& kv : d.values()) {
    EXPECT_EQ(out.count(kv.key()), 0u) << "key " << kv.key() << " twice";
    out[kv.key()] = kv.value();
  }
  return out;
}

}  // namespace

TEST(RosDiagnostics, LevelFollowsTheDeviceState) {
  EXPECT_EQ(messages::diagnostic_level(hil_msgs::msg::DEVICE_OK), level::OK);
  EXPECT_EQ(messages::diagnostic_level(hil_msgs::msg::DEVICE_DEGRADED), level::WARN);
  EXPECT_EQ(messages::diagnostic_level(hil_msgs::msg::DEVICE_FAULT), level::ERROR);
  EXPECT_EQ(messages::diagnostic_level(hil_msgs::msg::DEVICE_DISCONNECTED), level::ERROR);
  EXPECT_EQ(messages::diagnostic_level(9), level::STALE);
  // The ROS 2 values (diagnostic_msgs/DiagnosticStatus.msg), so rqt_robot_monitor colours them right.
  EXPECT_EQ(level::OK, 0);
  EXPECT_EQ(level::WARN, 1);
  EXPECT_EQ(level::ERROR, 2);
  EXPECT_EQ(level::STALE, 3);
}

TEST(RosDiagnostics, AFaultyDeviceSaysWhyWithItsCountersAsValues) {
  const auto d = messages::to_diagnostic_status(status(hil_msgs::msg::DEVICE_FAULT, "bus_error: bus-off"), "ATI serial FT1 on can0");
  EXPECT_EQ(d.level(), level::ERROR);
  EXPECT_EQ(d.name(), "hil/force_plate");
  EXPECT_EQ(d.hardware_id(), "ATI serial FT1 on can0");
  EXPECT_EQ(d.message(), "bus_error: bus-off");
  const auto v = values(d);
  EXPECT_EQ(v.size(), 9u);
  EXPECT_DOUBLE_EQ(std::stod(v.at("rate_hz")), 999.5);
  EXPECT_EQ(v.at("samples"), "123456");
  EXPECT_EQ(v.at("frames_dropped"), "7");
  EXPECT_EQ(v.at("errors"), "2");
  EXPECT_EQ(v.at("device_faults"), "5");
  EXPECT_DOUBLE_EQ(std::stod(v.at("last_sample_age_s")), 0.0012);
  EXPECT_EQ(v.at("connected"), "true");
  EXPECT_EQ(v.at("state"), "fault");
  EXPECT_EQ(v.at("last_error"), "bus_error: bus-off");
}

TEST(RosDiagnostics, MessageIsOkWhenOkAndTheStateWhenNoReasonIsKnown) {
  // An ok device's last error is history: level OK, message "ok", the error kept among the values.
  auto d = messages::to_diagnostic_status(status(hil_msgs::msg::DEVICE_OK, "timeout: no answer"), "");
  EXPECT_EQ(d.level(), level::OK);
  EXPECT_EQ(d.message(), "ok");
  EXPECT_EQ(values(d).at("last_error"), "timeout: no answer");

  d = messages::to_diagnostic_status(status(hil_msgs::msg::DEVICE_OK, ""), "");
  EXPECT_EQ(values(d).count("last_error"), 0u);
  EXPECT_EQ(values(d).size(), 8u);

  d = messages::to_diagnostic_status(status(hil_msgs::msg::DEVICE_DEGRADED, "silent for 4.0 ms"), "x");
  EXPECT_EQ(d.level(), level::WARN);
  EXPECT_EQ(d.message(), "silent for 4.0 ms");
  EXPECT_EQ(values(d).at("state"), "degraded");

  d = messages::to_diagnostic_status(status(hil_msgs::msg::DEVICE_DISCONNECTED, ""), "x");
  EXPECT_EQ(d.level(), level::ERROR);
  EXPECT_EQ(d.message(), "disconnected");
  EXPECT_EQ(values(d).at("connected"), "false");
}

TEST(RosTf, TheRigsFramesInOneMessage) {
  const auto rig = format::parse_rig(R"(format_version: 1
name: t
frames:
  - {name: object2, parent: force_plate, translation_m: [0, 0, 0.05], rpy_rad: [0, 0, 1.5707963267948966]}
  - {name: force_plate, parent: world, translation_m: [0.1, -0.2, 0.3]}
robot:
  name: arm
  base: {translation_m: [-0.45, 0, 0]}
  joints:
    - {a_m: 0, alpha_rad: 0, d_m: 0.1}
)",
                                     "rig.yaml");
  const auto stamp = messages::to_time(12.5);
  const auto m = messages::to_tf_message(format::static_frames(rig), stamp);
  ASSERT_EQ(m.transforms().size(), 3u);
  const auto& fp = m.transforms()[0];
  EXPECT_EQ(fp.header().frame_id(), "world");
  EXPECT_EQ(fp.child_frame_id(), "force_plate");
  EXPECT_EQ(fp.header().stamp(), stamp);
  EXPECT_DOUBLE_EQ(fp.transform().translation().x(), 0.1);
  EXPECT_DOUBLE_EQ(fp.transform().translation().y(), -0.2);
  EXPECT_DOUBLE_EQ(fp.transform().translation().z(), 0.3);
  EXPECT_DOUBLE_EQ(fp.transform().rotation().w(), 1.0);
  const auto& o2 = m.transforms()[1];
  EXPECT_EQ(o2.header().frame_id(), "force_plate");
  EXPECT_EQ(o2.child_frame_id(), "object2");
  // 90 degrees about z: (x, y, z, w) = (0, 0, sin 45, cos 45)
  EXPECT_NEAR(o2.transform().rotation().z(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(o2.transform().rotation().w(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(o2.transform().rotation().x(), 0.0, 1e-12);
  EXPECT_EQ(m.transforms()[2].child_frame_id(), "robot_base");
  EXPECT_DOUBLE_EQ(m.transforms()[2].transform().translation().x(), -0.45);
}

TEST(RosJointState, NamesFromTheRigPositionsFromTheSample) {
  format::Sample s;
  s.t_s = 3.25;
  Eigen::RowVectorXd q(3);
  q << 0.1, -0.2, 0.3;
  const auto m = messages::to_message(s, 4, q);
  const auto j = messages::to_joint_state(m, {"shoulder", "elbow"});
  EXPECT_EQ(j.name(), (std::vector<std::string>{"shoulder", "elbow", "j3"}));
  EXPECT_EQ(j.position(), (std::vector<double>{0.1, -0.2, 0.3}));
  EXPECT_EQ(j.header().stamp(), m.header().stamp());
  EXPECT_EQ(j.header().frame_id(), "");
  EXPECT_EQ(messages::to_joint_state(m, {}).name(), (std::vector<std::string>{"j1", "j2", "j3"}));
}

// docs/ros.md's topic table states the QoS of hil::dds::qos_table(), row for row: the type, the
// reliability, the durability, the depth and whether it is a sensor stream.
TEST(RosDocs, TheTopicTableIsTheQosTable) {
  std::ifstream in(std::string(HIL_SOURCE_DIR) + "/docs/ros.md");
  ASSERT_TRUE(in) << "docs/ros.md";
  std::map<std::string, std::string> rows;  // ROS 2 topic -> the whole row
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| `/", 0) != 0) continue;
    const auto end = line.find('`', 3);
    rows[line.substr(3, end - 3)] = line;
  }
  for (const auto& t : hil::dds::qos_table()) {
    const std::string ros_topic = std::string(t.topic).substr(2);  // rt/x -> /x
    ASSERT_TRUE(rows.count(ros_topic)) << ros_topic << ": no row in docs/ros.md's table";
    const auto& row = rows[ros_topic];
    const auto want = std::string(t.qos.reliable ? "reliable" : "best effort") + ", " +
                      (t.qos.durable_depth > 0 ? "transient local" : "volatile") + ", keep last " + std::to_string(t.qos.history_depth) +
                      (t.sensor ? "; sensor stream" : "") + " |";
    EXPECT_NE(row.find("`" + std::string(t.type) + "`"), std::string::npos) << row;
    EXPECT_TRUE(row.size() >= want.size() && row.compare(row.size() - want.size(), want.size(), want) == 0)
        << ros_topic << ": the table says\n  " << row << "\nthe code: " << want;
  }
}
