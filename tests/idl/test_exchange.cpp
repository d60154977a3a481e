// Two processes exchange 1,000 PoseWrenchSamples over the default host-only profile: none lost,
// none altered, and every locator the peer announces is shared memory or 127.0.0.1.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fastdds/rtps/participant/ParticipantDiscoveryInfo.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include <hil/messages/sample_msg.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/qos.hpp>
#include <hil/dds/topics.hpp>
#include <hil/messages/ros_msgs.hpp>

namespace {

constexpr int kSamples = 1000;

hil::format::Sample make_sample(int i) {
  hil::format::Sample s;
  s.t_s = 0.001 * i;
  s.p_world_ee_m = {0.1 + 1e-6 * i, 0.2, 0.3};
  s.f_fp_n = {0.0, 0.0, -1.0 * i};
  return s;
}

struct LocatorAudit : eprosima::fastdds::dds::DomainParticipantListener {
  std::mutex m;
  std::vector<std::string> bad;
  int discovered = 0;
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using eprosima::fastrtps::rtps::Locator_t;
    std::lock_guard<std::mutex> lock(m);
    if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) return;
    ++discovered;
    auto check = [&](const auto& list) {
      for (const auto& l : list) {
        if (l.kind == LOCATOR_KIND_SHM) continue;
        const bool loopback = l.kind == LOCATOR_KIND_UDPv4 && l.address[12] == 127;
        if (!loopback) bad.push_back(eprosima::fastrtps::rtps::IPLocator::toIPv4string(l));
      }
    };
    check(info.info.metatraffic_locators.unicast);
    check(info.info.default_locators.unicast);
    for (const auto& l : info.info.metatraffic_locators.multicast)
      bad.push_back("multicast " + eprosima::fastrtps::rtps::IPLocator::toIPv4string(l));
    for (const auto& l : info.info.default_locators.multicast)
      bad.push_back("multicast " + eprosima::fastrtps::rtps::IPLocator::toIPv4string(l));
  }
};

int publisher_process(int domain) {
  hil::dds::Participant p({domain, "", "hil_localhost", "test-publisher"});
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> w(p, hil::dds::topics::kPoseWrenchSample);
  if (!w.wait_for_readers(1, std::chrono::seconds(20))) return 3;
  Eigen::RowVectorXd q(2);
  for (int i = 0; i < kSamples; ++i) {
    q << 0.1 * i, -0.1 * i;
    if (!w.write(hil::messages::to_message(make_sample(i), static_cast<std::uint64_t>(i), q))) return 4;
  }
  return w.wait_for_acknowledgments(std::chrono::seconds(20)) ? 0 : 5;
}

}  // namespace

TEST(DdsExchange, ThousandSamplesBetweenProcessesNoneLost) {
  const int domain = 100 + static_cast<int>(getpid() % 100);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(publisher_process(domain));

  LocatorAudit audit;
  std::vector<hil_msgs::msg::PoseWrenchSample> got;
  std::mutex m;
  {
    hil::dds::ParticipantOptions o{domain, "", "hil_localhost", "test-subscriber", &audit};
    hil::dds::Participant p(o);
    hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> r(p, hil::dds::topics::kPoseWrenchSample, [&](const auto& msg, const auto&) {
      std::lock_guard<std::mutex> lock(m);
      got.push_back(msg);
    });
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(40);
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(m);
        if (got.size() >= static_cast<std::size_t>(kSamples)) break;
      }
      if (std::chrono::steady_clock::now() > deadline) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "publisher failed (3: no match, 4: write refused, 5: not acknowledged)";
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kSamples));
  for (int i = 0; i < kSamples; ++i) {
    ASSERT_EQ(got[i].sample_index(), static_cast<std::uint64_t>(i)) << "out of order or lost";
    Eigen::VectorXd q;
    const auto s = hil::messages::from_message(got[i], &q);
    EXPECT_EQ(s.f_fp_n, make_sample(i).f_fp_n);
    EXPECT_EQ(s.p_world_ee_m, make_sample(i).p_world_ee_m);
    ASSERT_EQ(q.size(), 2);
    EXPECT_EQ(q(1), -0.1 * i);
  }
  std::lock_guard<std::mutex> lock(audit.m);
  EXPECT_GE(audit.discovered, 1);
  EXPECT_TRUE(audit.bad.empty()) << "non-loopback locator announced: " << (audit.bad.empty() ? "" : audit.bad.front());
}

TEST(DdsExchange, BadProfileIsAClearError) {
  try {
    hil::dds::Participant p({0, "/nonexistent/profile.xml", "x", "t"});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profile.xml"), std::string::npos);
  }
}

// A partition keeps a run apart on a shared domain (hil demo): a reader gets the samples of writers
// in its own partition only, and a reader without one (a ROS 2 node) none of a partitioned writer's.
TEST(DdsExchange, APartitionKeepsARunApartOnASharedDomain) {
  const int domain = 100 + static_cast<int>((getpid() + 53) % 100);
  auto opts = [&](const char* name, const char* partition) {
    hil::dds::ParticipantOptions o;
    o.domain_id = domain;
    o.name = name;
    o.partition = partition;
    return o;
  };
  hil::dds::Participant run_a(opts("test-run-a", "hil-demo-a")), run_b(opts("test-run-b", "hil-demo-b")), open(opts("test-open", ""));
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> wa(run_a, hil::dds::topics::kPoseWrenchSample);
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> wb(run_b, hil::dds::topics::kPoseWrenchSample);
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> wo(open, hil::dds::topics::kPoseWrenchSample);
  std::mutex m;
  std::map<std::string, std::vector<std::uint64_t>> got;
  auto reader = [&](hil::dds::Participant& p, const std::string& who) {
    return std::make_unique<hil::dds::Reader<hil_msgs::msg::PoseWrenchSample>>(p, hil::dds::topics::kPoseWrenchSample,
                                                                               [&, who](const auto& msg, const auto&) {
                                                                                 std::lock_guard<std::mutex> lock(m);
                                                                                 got[who].push_back(msg.sample_index());
                                                                               });
  };
  hil::dds::Participant sub_a(opts("test-sub-a", "hil-demo-a")), sub_open(opts("test-sub-open", ""));
  auto ra = reader(sub_a, "a");
  auto ro = reader(sub_open, "open");
  ASSERT_TRUE(wa.wait_for_readers(1, std::chrono::seconds(20)));
  ASSERT_TRUE(wo.wait_for_readers(1, std::chrono::seconds(20)));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // time for b to be discovered, were it to match
  Eigen::RowVectorXd q(2);
  q << 0.0, 0.0;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(wa.write(hil::messages::to_message(make_sample(i), 100 + static_cast<std::uint64_t>(i), q)));
    ASSERT_TRUE(wb.write(hil::messages::to_message(make_sample(i), 200 + static_cast<std::uint64_t>(i), q)));
    ASSERT_TRUE(wo.write(hil::messages::to_message(make_sample(i), 300 + static_cast<std::uint64_t>(i), q)));
  }
  ASSERT_TRUE(wa.wait_for_acknowledgments(std::chrono::seconds(10)));
  ASSERT_TRUE(wo.wait_for_acknowledgments(std::chrono::seconds(10)));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  std::lock_guard<std::mutex> lock(m);
  std::vector<std::uint64_t> want_a, want_open;
  for (std::uint64_t i = 0; i < 10; ++i) want_a.push_back(100 + i), want_open.push_back(300 + i);
  EXPECT_EQ(got["a"], want_a) << "the partition's reader: its own run's samples, none of b's or of the open writer's";
  EXPECT_EQ(got["open"], want_open) << "a reader without a partition: the open writer's samples only";
}

// QoS by intent (docs/ros.md): a sensor stream is volatile, so a reader that joins late gets no
// old samples as new, even a transient-local one (a recorder adapting to the publisher); the
// latched /tf_static gives a late reader its last message.
TEST(DdsExchange, ALateReaderGetsNoStaleSensorSamplesButTheLatchedFrames) {
  const int domain = 100 + static_cast<int>((getpid() + 37) % 100);
  hil::dds::Participant pub({domain, "", "hil_localhost", "test-late-publisher"});
  const hil::dds::StreamQos sensor{true, 5000, 0};  // the acquirer's pose_wrench
  EXPECT_EQ(hil::dds::detail::writer_qos(pub, sensor).durability().kind, eprosima::fastdds::dds::VOLATILE_DURABILITY_QOS);
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> w(pub, hil::dds::topics::kPoseWrenchSample, sensor);
  hil::dds::Writer<tf2_msgs::msg::TFMessage> tf(pub, hil::dds::topics::kTfStatic, hil::dds::StreamQos{true, 1, 1});
  Eigen::RowVectorXd q(2);
  q << 0.0, 0.0;
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(w.write(hil::messages::to_message(make_sample(i), static_cast<std::uint64_t>(i), q)));
  tf2_msgs::msg::TFMessage frames;
  frames.transforms().resize(1);
  frames.transforms()[0].child_frame_id("force_plate");
  ASSERT_TRUE(tf.write(frames));

  std::mutex m;
  std::vector<std::uint64_t> latched_reader, volatile_reader;
  int tf_got = 0;
  {
    hil::dds::Participant sub({domain, "", "hil_localhost", "test-late-subscriber"});
    hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> durable(
        sub, hil::dds::topics::kPoseWrenchSample,
        [&](const auto& msg, const auto&) {
          std::lock_guard<std::mutex> lock(m);
          latched_reader.push_back(msg.sample_index());
        },
        hil::dds::StreamQos{true, 1000, 1000});
    hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> plain(sub, hil::dds::topics::kPoseWrenchSample, [&](const auto& msg, const auto&) {
      std::lock_guard<std::mutex> lock(m);
      volatile_reader.push_back(msg.sample_index());
    });
    hil::dds::Reader<tf2_msgs::msg::TFMessage> tf_reader(
        sub, hil::dds::topics::kTfStatic,
        [&](const auto& msg, const auto&) {
          std::lock_guard<std::mutex> lock(m);
          tf_got += msg.transforms().size() == 1 && msg.transforms()[0].child_frame_id() == "force_plate" ? 1 : 0;
        },
        hil::dds::StreamQos{true, 1, 1});
    ASSERT_TRUE(w.wait_for_readers(1, std::chrono::seconds(20)));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    for (int i = 50; i < 60; ++i) ASSERT_TRUE(w.write(hil::messages::to_message(make_sample(i), static_cast<std::uint64_t>(i), q)));
    ASSERT_TRUE(w.wait_for_acknowledgments(std::chrono::seconds(10)));
    for (int k = 0; k < 100; ++k) {
      {
        std::lock_guard<std::mutex> lock(m);
        if (volatile_reader.size() >= 10 && tf_got >= 1) break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  std::lock_guard<std::mutex> lock(m);
  // The live samples reach the volatile reader; nothing written before it joined does.
  ASSERT_EQ(volatile_reader.size(), 10u);
  EXPECT_EQ(volatile_reader.front(), 50u);
  // A transient-local reader does not match a volatile writer: no burst of history.
  for (const auto i : latched_reader) EXPECT_GE(i, 50u) << "a stale sample reached the transient-local reader";
  EXPECT_EQ(tf_got, 1);
}

// The QoS table: sensor streams switch to ROS 2's SensorDataQoS on request, nothing else does;
// what is latched stays latched.
TEST(QosTable, SensorStreamsAloneGoBestEffortAndOnlyTfStaticIsLatched) {
  for (const auto& t : hil::dds::qos_table()) {
    const auto reliable = hil::dds::qos_of(t.topic), chosen = hil::dds::qos_of(t.topic, true);
    if (t.sensor) {
      EXPECT_TRUE(reliable.reliable) << t.topic;
      EXPECT_FALSE(chosen.reliable) << t.topic;
      EXPECT_EQ(chosen.history_depth, 5) << t.topic;
    } else {
      EXPECT_EQ(chosen.reliable, reliable.reliable) << t.topic;
      EXPECT_EQ(chosen.history_depth, reliable.history_depth) << t.topic;
    }
    const std::string topic = t.topic;
    EXPECT_EQ(reliable.durable_depth > 0, topic == hil::dds::topics::kTfStatic || topic == hil::dds::topics::kDeviceStatus) << t.topic;
  }
  EXPECT_FALSE(hil::dds::qos_of(hil::dds::topics::kClock).reliable) << "rclcpp's ClockQoS";
  EXPECT_TRUE(hil::dds::qos_of(hil::dds::topics::kPoseWrenchSample, true).reliable) << "the workers' stream stays lossless";
  EXPECT_THROW(hil::dds::qos_of("rt/nowhere"), std::invalid_argument);
}
