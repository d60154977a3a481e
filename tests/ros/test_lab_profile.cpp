// idl/profiles/dds_lab_network.xml, the example lab-network profile: it loads as shipped with the
// settings its comments promise, and with the lab address replaced by 127.0.0.1 (and discovery
// pinned to this host: a test never sends anything off 127.0.0.0/8) its transports make
// participants that exchange samples.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>

#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include <hil/test/files.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>

using namespace eprosima::fastdds::dds;

namespace {
const std::string kProfile = std::string(HIL_SOURCE_DIR) + "/idl/profiles/dds_lab_network.xml";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (auto pos = s.find(from); pos != std::string::npos; pos = s.find(from, pos + to.size())) s.replace(pos, from.size(), to);
  return s;
}

void replace_once(std::string& s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  ASSERT_NE(pos, std::string::npos) << "'" << from << "' not in the profile";
  s.replace(pos, from.size(), to);
}
}  // namespace

TEST(LabProfile, LoadsAsShippedWithWhatItsCommentsSay) {
  auto* factory = DomainParticipantFactory::get_instance();
  ASSERT_EQ(factory->load_XML_profiles_file(kProfile), ReturnCode_t::RETCODE_OK);
  DomainParticipantQos qos;
  ASSERT_EQ(factory->get_participant_qos_from_profile("hil_lab_network", qos), ReturnCode_t::RETCODE_OK);
  EXPECT_FALSE(qos.transport().use_builtin_transports);
  ASSERT_EQ(qos.transport().user_transports.size(), 2u);
  std::shared_ptr<eprosima::fastdds::rtps::UDPv4TransportDescriptor> udp;
  std::shared_ptr<eprosima::fastdds::rtps::SharedMemTransportDescriptor> shm;
  for (const auto& t : qos.transport().user_transports) {
    if (auto u = std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(t)) udp = u;
    if (auto s = std::dynamic_pointer_cast<eprosima::fastdds::rtps::SharedMemTransportDescriptor>(t)) shm = s;
  }
  ASSERT_TRUE(udp) << "no UDPv4 transport";
  ASSERT_TRUE(shm) << "no shared-memory transport";
  EXPECT_EQ(udp->interfaceWhiteList, (std::vector<std::string>{"192.168.10.42"})) << "the placeholder the user edits";
  EXPECT_EQ(udp->maxInitialPeersRange, 32u);
  EXPECT_EQ(shm->segment_size(), 4194304u);
  const auto& d = qos.wire_protocol().builtin.discovery_config;
  EXPECT_EQ(d.leaseDuration, eprosima::fastrtps::Duration_t(10, 0));
  EXPECT_EQ(d.leaseDuration_announcementperiod, eprosima::fastrtps::Duration_t(3, 0));
  EXPECT_EQ(d.initial_announcements.count, 5u);
  // Discovery is left to Fast DDS's defaults (multicast, as ROS 2 nodes use): no peers or
  // locators are fixed by the shipped file.
  EXPECT_EQ(qos.wire_protocol().builtin.initialPeersList.size(), 0u);
  EXPECT_EQ(qos.wire_protocol().builtin.metatrafficUnicastLocatorList.size(), 0u);
}

TEST(LabProfile, WithTheLoopbackAsTheLabAddressParticipantsExchangeSamples) {
  hil::test::TempDir tmp;
  std::string xml = read_file(kProfile);
  ASSERT_NE(xml.find("<address>192.168.10.42</address> <!-- EDIT"), std::string::npos);
  // What a user does (the address), under other names: profiles are global to the process.
  xml = replace_all(xml, "192.168.10.42", "127.0.0.1");
  xml = replace_all(xml, "hil_lab_", "hil_labtest_");
  // What the test adds: unicast discovery and data on 127.0.0.1 only, nothing multicast.
  replace_once(xml, "<builtin>",
               "<builtin><metatrafficUnicastLocatorList><locator><udpv4><address>127.0.0.1</address></udpv4></locator>"
               "</metatrafficUnicastLocatorList><initialPeersList><locator><udpv4><address>127.0.0.1</address></udpv4>"
               "</locator></initialPeersList>");
  replace_once(xml, "</rtps>",
               "<defaultUnicastLocatorList><locator><udpv4><address>127.0.0.1</address></udpv4></locator>"
               "</defaultUnicastLocatorList></rtps>");
  const auto file = tmp.path() + "/lab.xml";
  std::ofstream(file) << xml;

  const int domain = 10 + static_cast<int>(getpid() % 40);
  hil::dds::Participant sub(hil::dds::ParticipantOptions{domain, file, "hil_labtest_network", "lab-sub"});
  hil::dds::Participant pub(hil::dds::ParticipantOptions{domain, file, "hil_labtest_network", "lab-pub"});
  std::mutex m;
  std::vector<std::uint64_t> got;
  hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> reader(sub, hil::dds::topics::kPoseWrenchSample, [&](const auto& msg, const auto&) {
    std::lock_guard<std::mutex> lock(m);
    got.push_back(msg.sample_index());
  });
  hil::dds::Writer<hil_msgs::msg::PoseWrenchSample> writer(pub, hil::dds::topics::kPoseWrenchSample);
  ASSERT_TRUE(writer.wait_for_readers(1, std::chrono::seconds(10)));
  hil::format::Sample s;
  for (std::uint64_t i = 0; i < 20; ++i) {
    s.t_s = 0.01 * static_cast<double>(i);
    ASSERT_TRUE(writer.write(hil::messages::to_message(s, i, Eigen::RowVectorXd())));
  }
  ASSERT_TRUE(writer.wait_for_acknowledgments(std::chrono::seconds(10)));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::lock_guard<std::mutex> lock(m);
  ASSERT_EQ(got.size(), 20u);
  for (std::uint64_t i = 0; i < 20; ++i) EXPECT_EQ(got[i], i);
}
