// What a ROS 2 node sees of a running rig service, on the DDS level: the Acquirer runs in-process
// against the fake rig (ATI plate on an in-process CAN bus, a Modbus controller on 127.0.0.1) with
// a rig whose joints are named. A participant joining after the start still gets /tf_static
// (transient local) with the rig's frames; /diagnostics carries each device's status as
// diagnostic_msgs, the same as hil's DeviceStatus, and a Modbus fault turns the robot's entry
// ERROR; /hil/joint_states names the joints as the rig does; /tf carries the moving robot base ->
// ee with every sample, under the names of the rig's tf: section, and composed with /tf_static's
// map -> base_link it is the sample's pose: one tree.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include <hil/acquisition/acquirer.hpp>
#include <hil/messages/ros_msgs.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/qos.hpp>
#include <hil/dds/topics.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/drivers_from_rig.hpp>

using namespace hil;
namespace level = diagnostic_msgs::msg::DiagnosticStatus_Constants;

namespace {

const std::vector<std::string> kJointNames = {"shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"};

// The shipped bench with its joints named, as a lab's rig file would name them.
format::RigSpec named_rig() {
  std::ifstream in(std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml");
  std::ostringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  std::size_t pos = 0;
  for (const auto& name : kJointNames) {
    pos = text.find("    - {a_m:", pos);
    EXPECT_NE(pos, std::string::npos) << "the example rig's joint table changed";
    if (pos == std::string::npos) break;
    text.insert(pos + 7, "name: " + name + ", ");
    pos += 12;
  }
  text += "tf: {world: map, base: base_link, ee: tool0}\n";
  return format::parse_rig(text, "press_bench_named.yaml");
}

// What discovery says of every writer on the domain: its topic, reliability and durability, as a
// ROS 2 node (or `ros2 topic info -v`) learns them.
struct WriterAudit : eprosima::fastdds::dds::DomainParticipantListener {
  struct Seen {
    bool reliable;
    bool transient_local;
  };
  std::mutex m;
  std::map<std::string, std::vector<Seen>> writers;
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*, eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
    std::lock_guard<std::mutex> lock(m);
    writers[info.info.topicName().to_string()].push_back({info.info.m_qos.m_reliability.kind ==
                                                              eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS,
                                                          info.info.m_qos.m_durability.kind ==
                                                              eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS});
  }
};

struct Collected {
  std::mutex m;
  std::vector<hil_msgs::msg::DeviceStatus> status;
  std::vector<diagnostic_msgs::msg::DiagnosticArray> diagnostics;
  std::vector<sensor_msgs::msg::JointState> joints;
  std::vector<tf2_msgs::msg::TFMessage> tf;
  std::vector<geometry_msgs::msg::PoseStamped> poses;
};

}  // namespace

TEST(RosTopics, TfStaticForLateJoinersDiagnosticsAndNamedJoints) {
  const auto rig = named_rig();
  const Eigen::Isometry3d T_world_base = rig_service::world_to_base(rig);
  const auto played = format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  auto scenario = std::make_shared<const drivers::Scenario>(rig_service::scenario_from_run(played, T_world_base, true));
  auto pcfg = rig_service::force_plate_config(rig);
  auto mcfg = rig_service::robot_controller_config(rig);
  auto bus = drivers::CanLoopbackBus::create("loop0");
  drivers::FakeNetCanOemConfig fc;
  fc.base_id = pcfg.base_id;
  fc.T_fp_sensor = pcfg.T_fp_sensor;
  drivers::FakeNetCanOemBoard fake_plate(fc, bus->open(), scenario);
  drivers::FakeRobotConfig rc;
  rc.map = mcfg.map;
  rc.port = 0;
  drivers::FakeRobotController fake_robot(rc, scenario);
  mcfg.host = "127.0.0.1";
  mcfg.port = fake_robot.port();
  mcfg.timeout_s = 0.05;

  const int domain = 10 + static_cast<int>(getpid() % 40);
  hil::dds::Participant participant({domain, "", "hil_localhost", "ros-topics"});
  WriterAudit audit;
  hil::dds::ParticipantOptions audit_options;
  audit_options.domain_id = domain;
  audit_options.name = "ros-topics-audit";
  audit_options.listener = &audit;
  hil::dds::Participant auditor(audit_options);
  Collected got;
  hil::dds::Reader<hil_msgs::msg::DeviceStatus> status_reader(participant, hil::dds::topics::kDeviceStatus,
                                                              [&](const auto& m, const auto&) {
                                                                std::lock_guard<std::mutex> lock(got.m);
                                                                got.status.push_back(m);
                                                              });
  hil::dds::Reader<diagnostic_msgs::msg::DiagnosticArray> diag_reader(participant, hil::dds::topics::kDiagnostics,
                                                                      [&](const auto& m, const auto&) {
                                                                        std::lock_guard<std::mutex> lock(got.m);
                                                                        got.diagnostics.push_back(m);
                                                                      });
  hil::dds::Reader<sensor_msgs::msg::JointState> joint_reader(participant, hil::dds::topics::kJointStates, [&](const auto& m, const auto&) {
    std::lock_guard<std::mutex> lock(got.m);
    got.joints.push_back(m);
  });

  // tf2's TransformListener QoS for /tf: reliable, volatile, keep last 100.
  hil::dds::Reader<tf2_msgs::msg::TFMessage> moving_tf_reader(
      participant, hil::dds::topics::kTf,
      [&](const auto& m, const auto&) {
        std::lock_guard<std::mutex> lock(got.m);
        got.tf.push_back(m);
      },
      hil::dds::StreamQos{true, 100, 0});
  hil::dds::Reader<geometry_msgs::msg::PoseStamped> pose_reader(participant, hil::dds::topics::kPose, [&](const auto& m, const auto&) {
    std::lock_guard<std::mutex> lock(got.m);
    got.poses.push_back(m);
  });

  acquisition::AcquirerOptions ao;
  ao.sync.wrench_rate_hz = pcfg.rate_hz;
  ao.sync.output_rate_hz = 50;
  ao.T_world_base = T_world_base;
  ao.static_frames = format::static_frames(rig);
  ao.tf_moving = format::moving_frame(&rig);
  ao.world_frame = rig.tf.world;
  ao.joint_names = format::joint_names(rig, mcfg.map.joint_count());
  ao.status_period_s = 0.5;
  ASSERT_EQ(ao.static_frames.size(), 4u) << "force_plate, object2, object1 and robot_base";
  const auto expected_tf = messages::to_tf_message(ao.static_frames, messages::to_time(0));

  std::vector<tf2_msgs::msg::TFMessage> tf_late;
  std::mutex tf_m;
  std::string plate_serial;
  {
    acquisition::Acquirer acq(ao, drivers::make_force_plate(pcfg, bus->open()), std::make_unique<drivers::RobotControllerDriver>(mcfg),
                              &participant, nullptr);
    fake_plate.start();
    fake_robot.start();
    acq.start();
    plate_serial = acq.plate_info().serial;
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));

    // A listener started well after the frames were sent, in its own participant (as another
    // process would be), with tf2's static listener QoS.
    {
      hil::dds::Participant late({domain, "", "hil_localhost", "ros-late-listener"});
      hil::dds::Reader<tf2_msgs::msg::TFMessage> tf_reader(
          late, hil::dds::topics::kTfStatic,
          [&](const auto& m, const auto&) {
            std::lock_guard<std::mutex> lock(tf_m);
            tf_late.push_back(m);
          },
          hil::dds::StreamQos{true, 1, 1});
      for (int i = 0; i < 100; ++i) {
        {
          std::lock_guard<std::mutex> lock(tf_m);
          if (!tf_late.empty()) break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));  // anything more would be a second send
    }

    // A Modbus fault: every request answered with an exception for 0.4 s.
    drivers::ModbusFaults busy;
    busy.exception_fraction = 1.0;
    fake_robot.set_faults(busy);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    fake_robot.set_faults({});
    std::this_thread::sleep_for(std::chrono::milliseconds(800));
    acq.stop();
    fake_plate.stop();
    fake_robot.stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }

  // /tf_static: one message, the whole tree, to the late joiner.
  {
    std::lock_guard<std::mutex> lock(tf_m);
    ASSERT_EQ(tf_late.size(), 1u) << "the late listener must get the frames once";
    const auto& tf = tf_late[0];
    ASSERT_EQ(tf.transforms().size(), expected_tf.transforms().size());
    for (std::size_t i = 0; i < tf.transforms().size(); ++i) {
      const auto& a = tf.transforms()[i];
      const auto& e = expected_tf.transforms()[i];
      EXPECT_EQ(a.header().frame_id(), e.header().frame_id()) << i;
      EXPECT_EQ(a.child_frame_id(), e.child_frame_id()) << i;
      EXPECT_EQ(a.transform(), e.transform()) << a.child_frame_id();
      EXPECT_GT(a.header().stamp().sec(), 1'600'000'000) << "stamped with the time it was sent";
    }
    EXPECT_EQ(tf.transforms()[0].header().frame_id(), "map") << "world under its tf: name";
    EXPECT_EQ(tf.transforms()[3].header().frame_id(), "map");
    EXPECT_EQ(tf.transforms()[3].child_frame_id(), "base_link");
    EXPECT_DOUBLE_EQ(tf.transforms()[3].transform().translation().x(), -0.45);
  }

  // On the wire: every writer the acquirer made, as discovery announces it, has the QoS of the one
  // table (idl/src/qos.cpp) that docs/ros.md and the MCAP metadata follow; and it made one of each.
  {
    std::lock_guard<std::mutex> lock(audit.m);
    for (const char* topic :
         {hil::dds::topics::kPoseWrenchSample, hil::dds::topics::kDeviceStatus, hil::dds::topics::kWrench, hil::dds::topics::kPose,
          hil::dds::topics::kJointStates, hil::dds::topics::kTfStatic, hil::dds::topics::kTf, hil::dds::topics::kDiagnostics}) {
      const auto it = audit.writers.find(topic);
      ASSERT_NE(it, audit.writers.end()) << topic << ": no writer discovered";
      ASSERT_EQ(it->second.size(), 1u) << topic;
      const auto want = hil::dds::qos_of(topic);
      EXPECT_EQ(it->second[0].reliable, want.reliable) << topic;
      EXPECT_EQ(it->second[0].transient_local, want.durable_depth > 0) << topic;
    }
    EXPECT_TRUE(audit.writers.at(hil::dds::topics::kTfStatic)[0].transient_local) << "the table itself: /tf_static latched";
    EXPECT_FALSE(audit.writers.at(hil::dds::topics::kWrench)[0].transient_local) << "the table itself: a sensor stream is volatile";
  }

  std::lock_guard<std::mutex> lock(got.m);
  // /diagnostics: every entry is the mapping of the DeviceStatus sent at the same time.
  ASSERT_GE(got.diagnostics.size(), 3u);
  bool plate_ok = false, robot_ok = false, robot_error = false;
  for (const auto& array : got.diagnostics) {
    ASSERT_FALSE(array.status().empty());
    for (const auto& d : array.status()) {
      const hil_msgs::msg::DeviceStatus* same = nullptr;
      for (const auto& s : got.status)
        if ("hil/" + s.device() == d.name() && s.stamp() == array.header().stamp()) same = &s;
      ASSERT_NE(same, nullptr) << d.name() << ": no DeviceStatus with the array's stamp";
      // Who the device is: the plate's protocol, serial and CAN interface; the controller's address.
      const std::string hw = same->device() == "robot" ? mcfg.describe() : "ati_netcanoem serial " + plate_serial + " on loop0";
      EXPECT_EQ(d, messages::to_diagnostic_status(*same, hw)) << d.name() << " '" << d.hardware_id() << "' " << d.message();
      if (d.name() == "hil/force_plate" && d.level() == level::OK) plate_ok = true;
      if (d.name() == "hil/robot" && d.level() == level::OK) robot_ok = true;
      // (the robot is also ERROR "not connected" before its first poll)
      if (d.name() == "hil/robot" && d.level() == level::ERROR && d.message().find("exception") != std::string::npos) robot_error = true;
    }
  }
  EXPECT_TRUE(plate_ok) << "the force plate was never OK on /diagnostics";
  EXPECT_TRUE(robot_ok) << "the robot was never OK on /diagnostics";
  EXPECT_TRUE(robot_error) << "the Modbus fault never reached /diagnostics as ERROR naming the exception";

  // /tf: one base_link -> tool0 per sample, stamped as the pose; map -> base_link (-0.45 m in x,
  // /tf_static) composed with it is the pose on /hil/pose, which is in map.
  ASSERT_GT(got.tf.size(), 20u);
  ASSERT_EQ(got.tf.size(), got.poses.size()) << "one /tf message per sample";
  const auto to_iso = [](const geometry_msgs::msg::Vector3& p, const geometry_msgs::msg::Quaternion& q) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(p.x(), p.y(), p.z());
    return T;
  };
  const Eigen::Isometry3d T_map_base = Eigen::Translation3d(-0.45, 0, 0) * Eigen::Isometry3d::Identity();
  EXPECT_TRUE(T_map_base.isApprox(T_world_base, 1e-12)) << "the rig's robot base moved; the check below assumes it";
  for (std::size_t i = 0; i < got.tf.size(); ++i) {
    ASSERT_EQ(got.tf[i].transforms().size(), 1u) << i;
    const auto& x = got.tf[i].transforms()[0];
    const auto& pose = got.poses[i];
    ASSERT_EQ(x.header().frame_id(), "base_link") << i;
    ASSERT_EQ(x.child_frame_id(), "tool0") << i;
    ASSERT_EQ(x.header().stamp(), pose.header().stamp()) << i;
    ASSERT_EQ(pose.header().frame_id(), "map") << i;
    geometry_msgs::msg::Vector3 p;
    p.x(pose.pose().position().x()), p.y(pose.pose().position().y()), p.z(pose.pose().position().z());
    const Eigen::Isometry3d T_map_tool = T_map_base * to_iso(x.transform().translation(), x.transform().rotation());
    const Eigen::Isometry3d T_map_pose = to_iso(p, pose.pose().orientation());
    ASSERT_TRUE(T_map_tool.isApprox(T_map_pose, 1e-12)) << i << ":\n" << T_map_tool.matrix() << "\nvs\n" << T_map_pose.matrix();
  }

  // /hil/joint_states: the rig's names.
  ASSERT_GT(got.joints.size(), 20u);
  for (const auto& j : got.joints) {
    ASSERT_EQ(j.name(), kJointNames);
    ASSERT_EQ(j.position().size(), kJointNames.size());
  }
}
