// SocketCAN on a real kernel bus (vcan0, or $HIL_VCAN_IFACE). Skips when the kernel has no PF_CAN
// or the interface does not exist; tests/vm runs it in a QEMU guest with vcan0 up.
// Peers: can-utils' candump -L and cansend, when installed.
#include <gtest/gtest.h>
#include <net/if.h>
#include <sys/socket.h>

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <hil/drivers/candump.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/socketcan.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;
using namespace std::chrono_literals;

namespace {

std::string can_iface() {
  const char* e = std::getenv("HIL_VCAN_IFACE");
  return e != nullptr && *e != '\0' ? e : "vcan0";
}

class SocketCan : public ::testing::Test {
 protected:
  void SetUp() override {
    // Under the harness (HIL_VCAN_MODE=vm|host) a missing bus is a failure, not a skip.
    const bool harness = std::getenv("HIL_VCAN_MODE") != nullptr;
    if (!SocketCanChannel::kernel_supports_can()) {
      if (harness) FAIL() << "HIL_VCAN_MODE is set but this kernel has no PF_CAN";
      GTEST_SKIP() << "this kernel has no PF_CAN (run in the tests/vm guest)";
    }
    if (if_nametoindex(can_iface().c_str()) == 0) {
      if (harness) FAIL() << "HIL_VCAN_MODE is set but there is no interface " << can_iface();
      GTEST_SKIP() << "no interface " << can_iface();
    }
  }
  std::unique_ptr<SocketCanChannel> open(CanChannelOptions ch = {}) {
    SocketCanOptions o;
    o.interface = can_iface();
    o.channel = std::move(ch);
    return SocketCanChannel::open(o);
  }
  /// Sends 7FE# until `dump` (candump on the bus) prints it: from then on candump sees every
  /// frame. \returns that first line (empty if candump never printed one).
  std::string candump_listening(hil::test::Child& dump) {
    auto tx = open();
    CanFrame marker;
    EXPECT_EQ(parse_frame_text("7FE#", marker), "");
    std::atomic<bool> printed{false};
    std::thread t([&] {
      for (int i = 0; i < 200 && !printed; ++i) {
        tx->send(marker, 100ms);
        std::this_thread::sleep_for(20ms);
      }
    });
    std::string line = dump.read_line();
    printed = true;
    t.join();
    return line;
  }
  /// Reads until a frame with this id arrives (other traffic on the bus is skipped).
  static bool receive_id(CanChannel& c, std::uint32_t id, CanFrame& out) {
    for (int i = 0; i < 1000; ++i) {
      if (c.receive(out, 2s) != IoStatus::ok) return false;
      if (!out.error && out.id == id) return true;
    }
    return false;
  }
};

bool have_tool(const char* name) {
  for (const char* dir : {"/usr/bin/", "/bin/", "/usr/local/bin/"})
    if (std::filesystem::exists(std::string(dir) + name)) return true;
  return false;
}
std::string tool(const char* name) {
  for (const char* dir : {"/usr/bin/", "/bin/", "/usr/local/bin/"})
    if (std::filesystem::exists(std::string(dir) + name)) return std::string(dir) + name;
  return name;
}

/// Linux ≥ 6.0 sets CANFD_FDF (0x04) in the flags of every received CAN FD frame; compare without it.
bool same_but_fdf(CanFrame a, CanFrame b) {
  a.fd_flags &= 0x0B;
  b.fd_flags &= 0x0B;
  return same_frame(a, b);
}

CanFrame text(const std::string& t) {
  CanFrame f;
  EXPECT_EQ(parse_frame_text(t, f), "") << t;
  return f;
}

}  // namespace

TEST_F(SocketCan, ClassicAndFdFramesWithKernelTimestamps) {
  auto a = open();
  auto b = open();
  for (const char* t : {"123#DEADBEEF", "1F334455#0102", "321#R4",
                        "456##3"
                        "00112233445566778899AABB"}) {
    const CanFrame f = text(t);
    ASSERT_EQ(a->send(f, 100ms), IoStatus::ok) << a->last_error();
    CanFrame got;
    ASSERT_TRUE(receive_id(*b, f.id, got)) << t;
    EXPECT_TRUE(same_but_fdf(f, got)) << t << " vs " << format_frame_text(got);
    EXPECT_NE(got.stamp, StampSource::none) << "no kernel timestamp";
    EXPECT_GT(got.t_ns, 0);
  }
  EXPECT_EQ(a->stats().tx_frames, 4U);
}

TEST_F(SocketCan, KernelFiltersAndErrorMask) {
  auto tx = open();
  CanChannelOptions only;
  only.filters = {CanFilter::masked(0x200, 0x7F0)};
  only.error_mask = 0;
  auto rx = open(only);
  tx->send(text("105#01"), 100ms);
  tx->send(text("20A#02"), 100ms);
  tx->send(text("0000020A#03"), 100ms);
  CanFrame got;
  ASSERT_EQ(rx->receive(got, 2s), IoStatus::ok);
  EXPECT_EQ(format_frame_text(got), "20A#02");
  EXPECT_EQ(rx->receive(got, 50ms), IoStatus::timeout);
}

TEST_F(SocketCan, ErrorFramesFollowTheErrorMask) {
  auto tx = open();
  CanChannelOptions all;
  auto rx_all = open(all);
  CanChannelOptions none;
  none.error_mask = 0;
  auto rx_none = open(none);
  ASSERT_EQ(tx->send(make_error_frame(kErrBusOff), 100ms), IoStatus::ok) << tx->last_error();
  ASSERT_EQ(tx->send(text("123#01"), 100ms), IoStatus::ok);
  CanFrame got;
  ASSERT_EQ(rx_all->receive(got, 2s), IoStatus::ok);
  EXPECT_TRUE(got.error);
  EXPECT_TRUE(decode_error_frame(got).bus_off);
  EXPECT_EQ(rx_all->stats().error_frames, 1U);
  ASSERT_EQ(rx_none->receive(got, 2s), IoStatus::ok);
  EXPECT_FALSE(got.error);  // the error frame was filtered by the kernel
  EXPECT_EQ(got.id, 0x123U);
}

TEST_F(SocketCan, AtiBusOffAndRecovery) {
  FakeNetCanOemConfig fc;
  fc.base_id = 0x22;
  FakeNetCanOemBoard fake(fc, open());
  fake.start();
  ForcePlateConfig pc;
  pc.base_id = 0x22;
  pc.response_timeout_s = 0.2;
  pc.startup_timeout_s = 0.5;
  auto plate = make_force_plate(pc, open());
  plate->start();
  WrenchSample s;
  ASSERT_EQ(plate->poll(s), PollStatus::ok) << plate->last_problem();
  CanFaults f;
  f.bus_off = {TimeWindow{0.0, 1e6}};
  fake.set_faults(f);
  ASSERT_TRUE(hil::test::eventually([&] { return plate->poll(s) == PollStatus::bus_error; }, 20s));
  EXPECT_TRUE(plate->counters().bus_off);
  fake.set_faults(CanFaults{});
  ASSERT_TRUE(hil::test::eventually([&] { return plate->poll(s) == PollStatus::ok; }, 20s));
  EXPECT_FALSE(plate->counters().bus_off);
}

TEST_F(SocketCan, KernelDropCounter) {
  auto tx = open();
  auto rx = open();
  const int small = 1;  // the kernel rounds up to its minimum
  ::setsockopt(rx->fd(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  for (int i = 0; i < 2000; ++i) tx->send(text("111#01"), 100ms);
  CanFrame got;
  while (rx->receive(got, 50ms) == IoStatus::ok) {
  }
  // The kernel reports the drop count with the frames queued after the drops.
  ASSERT_EQ(tx->send(text("112#02"), 100ms), IoStatus::ok);
  ASSERT_TRUE(receive_id(*rx, 0x112, got));
  EXPECT_GT(rx->stats().rx_dropped, 0U);
}

TEST_F(SocketCan, AtiDriverAgainstTheFakePlate) {
  FakeNetCanOemConfig fc;
  fc.base_id = 0x21;
  FakeNetCanOemBoard fake(fc, open());
  Vector6d w;
  w << 5, -6, 400, 1, -2, 0.5;
  fake.set_wrench(w);
  fake.start();
  ForcePlateConfig pc;
  pc.base_id = 0x21;
  pc.response_timeout_s = 0.5;
  pc.startup_timeout_s = 0.5;
  CanChannelOptions ch;
  ch.filters = {CanFilter::masked(0x21 << 4, 0x7F0)};
  auto plate = make_force_plate(pc, open(ch));
  const ForcePlateInfo info = plate->start();
  EXPECT_EQ(info.serial, "FT-FAKE1");
  for (int i = 0; i < 100; ++i) {
    WrenchSample s;
    ASSERT_EQ(plate->poll(s), PollStatus::ok) << plate->last_problem();
    EXPECT_NEAR((s.w_fp - w).head<3>().norm(), 0.0, 0.2);
    EXPECT_NEAR((s.w_fp - w).tail<3>().norm(), 0.0, 0.01);
    EXPECT_NE(s.stamp, StampSource::none);
  }
}

TEST_F(SocketCan, CandumpCapturesTrafficThatOurReaderParsesBitExact) {
  if (!have_tool("candump")) GTEST_SKIP() << "can-utils not installed";
  hil::test::Child dump({tool("candump"), "-L", can_iface()});
  ASSERT_TRUE(dump.ok());
  auto tx = open();
  // Wait until candump is listening: send a marker until it shows up.
  std::string line;
  CanFrame marker = text("7FE#");
  std::thread t([&] {
    for (int i = 0; i < 200 && line.empty(); ++i) {
      tx->send(marker, 100ms);
      std::this_thread::sleep_for(20ms);
    }
  });
  line = dump.read_line();
  t.join();
  ASSERT_FALSE(line.empty());
  const std::vector<std::string> frames{"123#DEADBEEF",
                                        "1F334455#1122334455667788",
                                        "123#R",
                                        "123#R3",
                                        "00000123#R8",
                                        "7FF#",
                                        "456##1112233",
                                        "456##F" + std::string(128, 'A'),
                                        "1ABCDEF0##50011223344556677"};
  auto sender = open();
  for (const auto& f : frames) ASSERT_EQ(sender->send(text(f), 100ms), IoStatus::ok) << f;
  std::size_t k = 0;
  while (k < frames.size()) {
    line = dump.read_line();
    ASSERT_FALSE(line.empty());
    CanFrame got;
    std::string name;
    ASSERT_EQ(parse_candump_line(line, got, name), "") << line;
    if (got.id == 0x7FE) continue;  // a late marker
    EXPECT_EQ(name, can_iface());
    EXPECT_TRUE(same_but_fdf(got, text(frames[k]))) << line;
    EXPECT_EQ(format_candump_line(got, name), line);  // our writer writes what candump writes
    ++k;
  }
}

TEST_F(SocketCan, FramesFromCansendAreDecoded) {
  if (!have_tool("cansend")) GTEST_SKIP() << "can-utils not installed";
  auto rx = open();
  for (const std::string t : {"123#DEADBEEF", "1F334455#R", "5A1#11.22.33", "213##1112233", "00000001#"}) {
    hil::test::Child send({tool("cansend"), can_iface(), t});
    ASSERT_EQ(send.wait(), 0) << t;
    const CanFrame want = text(t);
    CanFrame got;
    ASSERT_TRUE(receive_id(*rx, want.id, got)) << t;
    EXPECT_TRUE(same_but_fdf(got, want)) << t << " decoded as " << format_frame_text(got);
  }
}

TEST(SocketCanOpen, ClearErrorWithoutCan) {
  if (SocketCanChannel::kernel_supports_can()) {
    SocketCanOptions o;
    o.interface = "hil-nonexistent";
    try {
      SocketCanChannel::open(o);
      FAIL() << "no error";
    } catch (const DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("hil-nonexistent"), std::string::npos) << e.what();
    }
  } else {
    try {
      SocketCanChannel::open(SocketCanOptions{});
      FAIL() << "no error";
    } catch (const DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("this kernel has no CAN support"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(hil::test::config_error(
      [] {
        SocketCanOptions o;
        o.interface = std::string(40, 'x');
        SocketCanChannel::open(o);
      },
      "interface", "not a valid interface name"));
}

// `hil fake-rig` answering on the bus, the driver reading it, and candump -L capturing the
// fake's traffic, which our log reader parses bit-exact.
TEST_F(SocketCan, HilFakeRigPlateCapturedByCandump) {
  if (!have_tool("candump")) GTEST_SKIP() << "can-utils not installed";
  const std::string hil = HIL_EXECUTABLE;
  ASSERT_TRUE(std::filesystem::exists(hil)) << hil;
  hil::test::Child dump({tool("candump"), "-L", can_iface()});
  std::string line = candump_listening(dump);
  ASSERT_FALSE(line.empty()) << "candump never printed a frame";

  // Speed ~0 holds the first sample of the example run.
  hil::test::Child fake({hil, "--log-level", "warn", "fake-rig", "--run", std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide",
                         "--no-robot", "--can", can_iface(), "--base-id", "0x33", "--speed", "1e-9", "--duration", "120"});
  ASSERT_TRUE(fake.ok());
  ASSERT_NE(fake.read_line().find("base 0x33"), std::string::npos);
  ForcePlateConfig pc;
  pc.base_id = 0x33;
  pc.response_timeout_s = 0.5;
  pc.startup_timeout_s = 1.0;
  CanChannelOptions ch;
  ch.filters = {CanFilter::masked(0x33 << 4, 0x7F0)};
  auto plate = make_force_plate(pc, open(ch));
  plate->start();
  Vector6d first;
  first << 0.1, -0.1, 0.05, 0.007, -0.008, -0.004;  // examples/runs/press_slide/samples.csv, t = 0
  const int polls = 20;
  for (int i = 0; i < polls; ++i) {
    WrenchSample s;
    ASSERT_EQ(plate->poll(s), PollStatus::ok) << plate->last_problem();
    EXPECT_LT((s.w_fp - first).head<3>().norm(), 0.2);
    EXPECT_LT((s.w_fp - first).tail<3>().norm(), 0.01);
  }
  int gauge_answers = 0;
  while (gauge_answers < polls) {
    line = dump.read_line();
    ASSERT_FALSE(line.empty());
    CanFrame f;
    std::string name;
    ASSERT_EQ(parse_candump_line(line, f, name), "") << line;
    EXPECT_EQ(format_candump_line(f, name), line);
    if (!f.error && f.id == ati::frame_id(0x33, ati::kOpReadGauges) && f.len == 8) ++gauge_answers;
  }
}

// `hil fake-rig` playing a Net F/T box in CAN mode: can-utils' cansend (an independent peer) asks
// for short data and candump sees the two little-endian answers on base+5 and base+6; then the
// driver reads the same box through SocketCAN.
TEST_F(SocketCan, HilFakeRigNetFtBoxAnswersCansend) {
  if (!have_tool("candump") || !have_tool("cansend")) GTEST_SKIP() << "can-utils not installed";
  const std::string hil = HIL_EXECUTABLE;
  const std::string dir = std::filesystem::temp_directory_path() / ("hil-netft-can-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string rig = dir + "/box.yaml";
  {
    std::FILE* f = std::fopen(rig.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f,
                 "format_version: 1\nname: press_bench\nframes:\n  - {name: force_plate, parent: world}\ndevices:\n  force_plate:\n"
                 "    protocol: ati_netft_can\n    interface: %s\n    base_id: 0x120\n    counts_per_force: 100\n"
                 "    counts_per_torque: 1000\n    rate_hz: 100\n",
                 can_iface().c_str());
    std::fclose(f);
  }
  hil::test::Child dump({tool("candump"), "-L", can_iface()});
  std::string line = candump_listening(dump);
  ASSERT_FALSE(line.empty()) << "candump never printed a frame";
  // Speed ~0 holds the first sample of the example run: fx 0.1 N, fz 0.05 N (10 and 5 counts).
  hil::test::Child fake({hil, "--log-level", "warn", "fake-rig", "--rig", rig, "--run",
                         std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide", "--no-robot", "--speed", "1e-9", "--duration", "120"});
  ASSERT_TRUE(fake.ok());
  ASSERT_NE(fake.read_line().find("Net F/T CAN base address 0x120"), std::string::npos);
  hil::test::Child send({tool("cansend"), can_iface(), "120#02"});
  ASSERT_EQ(send.wait(), 0);
  CanFrame first, second;
  std::string name;
  bool have_first = false, have_second = false;
  while (!(have_first && have_second)) {
    line = dump.read_line();
    ASSERT_FALSE(line.empty()) << "candump ended before the box answered";
    CanFrame f;
    ASSERT_EQ(parse_candump_line(line, f, name), "") << line;
    if (f.id == 0x125) first = f, have_first = true;
    if (f.id == 0x126) second = f, have_second = true;
  }
  ASSERT_EQ(first.len, 8U);
  ASSERT_EQ(second.len, 8U);
  EXPECT_EQ(first.data[0] | (first.data[1] << 8), 10) << "Fx, least significant byte first";
  EXPECT_EQ(second.data[0] | (second.data[1] << 8), 5) << "Fz";
  EXPECT_EQ(second.data[4] | (second.data[5] << 8), 0) << "status";
  ForcePlateConfig pc;
  pc.protocol = ForcePlateProtocol::ati_netft_can;
  pc.base_id = 0x120;
  pc.netft_calibration = {100.0, 1000.0, "N", "Nm"};
  pc.rate_hz = 100.0;
  pc.response_timeout_s = 0.5;
  pc.startup_timeout_s = 1.0;
  auto plate = make_force_plate(pc, open());
  plate->start();
  WrenchSample s;
  ASSERT_EQ(plate->poll(s), PollStatus::ok) << plate->last_problem();
  EXPECT_NEAR(s.w_fp[0], 0.1, 1e-9);
  EXPECT_NEAR(s.w_fp[2], 0.05, 1e-9);
  EXPECT_NE(s.stamp, StampSource::none) << "kernel receive stamps";
  std::filesystem::remove_all(dir);
}
