// hil's host-only profile discovers by unicast on 127.0.0.1 (no multicast), announcing itself to
// the first participant ids of the host's port range. A lab host runs more than four DDS processes
// (hil acquire, workers, hil echo, ROS 2 nodes): the last ones must still find each other.
#include <gtest/gtest.h>
#include <unistd.h>

#include <memory>
#include <vector>

#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>

TEST(LocalhostDiscovery, TheSeventhAndEighthParticipantsOfAHostFindEachOther) {
  const int domain = 10 + static_cast<int>(getpid() % 40);
  std::vector<std::unique_ptr<hil::dds::Participant>> others;
  for (int i = 0; i < 6; ++i)
    others.push_back(std::make_unique<hil::dds::Participant>(hil::dds::ParticipantOptions{domain, "", "hil_localhost", "filler"}));
  hil::dds::Participant a({domain, "", "hil_localhost", "seventh"});
  hil::dds::Participant b({domain, "", "hil_localhost", "eighth"});
  hil::dds::Writer<diagnostic_msgs::msg::DiagnosticArray> w(a, hil::dds::topics::kDiagnostics);
  hil::dds::Reader<diagnostic_msgs::msg::DiagnosticArray> r(b, hil::dds::topics::kDiagnostics, [](const auto&, const auto&) {});
  EXPECT_TRUE(w.wait_for_readers(1, std::chrono::seconds(8))) << "participants 7 and 8 of the host never discovered each other";
}
