// `hil fake-rig` as users run it: the fake robot controller replaying the example run, read by the
// driver over Modbus TCP on 127.0.0.1 (the force plate half runs in the vcan suite).
#include <gtest/gtest.h>

#include <hil/rig_service/drivers_from_rig.hpp>
#include <hil/test/drivers.hpp>
#include <hil/test/files.hpp>

using namespace hil;
using namespace hil::drivers;

namespace {
const std::string kHil = HIL_EXECUTABLE;
const std::string kRun = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";

/// "fake-rig: robot controller Modbus TCP 127.0.0.1:PORT map ur" -> PORT
int port_of(const std::string& line) {
  const auto colon = line.rfind(':');
  if (line.find("robot controller") == std::string::npos || colon == std::string::npos) return -1;
  return std::atoi(line.c_str() + colon + 1);
}
}  // namespace

TEST(HilFakeRig, ServesTheRunOverModbus) {
  // Speed ~0 freezes the replay at the run's first sample, so the check is exact.
  hil::test::Child fake({kHil, "--log-level", "warn", "fake-rig", "--run", kRun, "--no-plate", "--port", "0", "--speed", "1e-9",
                         "--duration", "60"});
  ASSERT_TRUE(fake.ok());
  const std::string line = fake.read_line();
  const int port = port_of(line);
  ASSERT_GT(port, 0) << "unexpected first line: " << line;

  const auto run = format::load_run(kRun);
  ModbusConfig mc = rig_service::robot_controller_config(*run.rig);
  mc.port = port;
  mc.timeout_s = 2.0;
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
  ASSERT_TRUE(s.has_pose);
  const Eigen::Isometry3d T_world_base = rig_service::world_to_base(*run.rig);
  EXPECT_LT((T_world_base * s.p_base_tcp_m - run.samples.samples[0].p_world_ee_m).norm(), 1e-4);
}

TEST(HilFakeRig, FaultOptionsAreChecked) {
  hil::test::Child fake({kHil, "fake-rig", "--run", kRun, "--no-plate", "--port", "0", "--modbus-silent", "3"});
  ASSERT_TRUE(fake.ok());
  EXPECT_NE(fake.wait(), 0);
}

// A rig whose plate is a Net F/T box: `hil fake-rig` serves the box's RDT stream on 127.0.0.1 and
// `hil acquire --check` finds it with nothing but the rig file (the box's settings in it).
TEST(HilFakeRig, ServesANetFtBoxThatAcquireChecks) {
  test::TempDir tmp;
  const auto rig_with_port = [&](int port) {
    return tmp.file("netft_" + std::to_string(port) + ".yaml",
                    "format_version: 1\nname: netft_bench\nframes:\n  - {name: force_plate, parent: world}\ndevices:\n  force_plate:\n"
                    "    protocol: ati_netft_rdt\n    host: 127.0.0.1\n    port: " +
                        std::to_string(port) + "\n    calibration_xml: " + std::string(HIL_SOURCE_DIR) +
                        "/examples/netft/netftapi2.xml\n    rate_hz: 500\n");
  };
  hil::test::Child fake({kHil, "--log-level", "warn", "fake-rig", "--rig", rig_with_port(49152), "--no-robot", "--netft-port", "0",
                         "--plate-status", "0x4@0:1000", "--duration", "60"});
  ASSERT_TRUE(fake.ok());
  const std::string line = fake.read_line();
  const auto colon = line.rfind(':');
  ASSERT_NE(line.find("Net F/T RDT on udp 127.0.0.1:"), std::string::npos) << line;
  const int port = std::atoi(line.c_str() + colon + 1);
  ASSERT_GT(port, 0) << line;
  hil::test::Child check({kHil, "--log-level", "warn", "acquire", "--rig", rig_with_port(port), "--check", "--no-robot"});
  ASSERT_TRUE(check.ok());
  std::string out, l;
  while (!(l = check.read_line()).empty()) out += l + "\n";
  EXPECT_EQ(check.wait(), 1) << "a box flagging its readings fails the check\n" << out;
  EXPECT_NE(out.find("force plate (ati_netft_rdt on udp 127.0.0.1:" + std::to_string(port) + ")"), std::string::npos) << out;
  EXPECT_NE(out.find("Net F/T status 0x80000004 (any error, bit 2)"), std::string::npos) << out;
  EXPECT_NE(out.find("counts_per_force"), std::string::npos) << out;
}

TEST(HilFakeRig, StatusWindowsAreChecked) {
  test::TempDir tmp;
  const auto rig = tmp.file("netft.yaml", "format_version: 1\nname: n\nframes:\n  - {name: force_plate, parent: world}\ndevices:\n"
                                          "  force_plate: {protocol: ati_netft_rdt, host: 127.0.0.1, counts_per_force: 1e6, "
                                          "counts_per_torque: 1e6}\n");
  for (const char* bad : {"0x0@1:1", "0x4@1", "4@-1:1", "x@1:1", "0x4@1:0"}) {
    hil::test::Child fake({kHil, "--log-level", "warn", "fake-rig", "--rig", rig, "--no-robot", "--netft-port", "0", "--plate-status", bad,
                           "--duration", "0.2"});
    ASSERT_TRUE(fake.ok());
    EXPECT_NE(fake.wait(), 0) << "--plate-status " << bad << " was accepted";
  }
  hil::test::Child good({kHil, "--log-level", "warn", "fake-rig", "--rig", rig, "--no-robot", "--netft-port", "0", "--plate-status",
                         "0x4@1:1", "--duration", "0.2"});
  ASSERT_TRUE(good.ok());
  EXPECT_EQ(good.wait(), 0) << "a well-formed status window";
}

// A rig whose plate is a Robotiq FT 300: `hil fake-rig --serial-link` plays the sensor on a
// pseudo-terminal linked where the rig's serial_device says, and `hil acquire --check` reads its
// identity and a wrench through it; the link is gone when the fake stops.
TEST(HilFakeRig, ServesAnFt300ThatAcquireChecks) {
  test::TempDir tmp;
  const std::string link = tmp.path() + "/ft300";
  const auto rig = tmp.file("ft300.yaml", "format_version: 1\nname: ft300_bench\nframes:\n  - {name: force_plate, parent: world}\n"
                                          "devices:\n  force_plate:\n    protocol: robotiq_ft300\n    serial_device: " +
                                              link + "\n    allowed_writes: [stream_start]\n");
  hil::test::Child fake({kHil, "--log-level", "warn", "fake-rig", "--rig", rig, "--no-robot", "--serial-link", link, "--duration", "60"});
  ASSERT_TRUE(fake.ok());
  const std::string line = fake.read_line();
  ASSERT_NE(line.find("Robotiq FT 300 on /dev/pts/"), std::string::npos) << line;
  ASSERT_NE(line.find(" as " + link), std::string::npos) << line;
  hil::test::Child check({kHil, "--log-level", "warn", "acquire", "--rig", rig, "--check", "--no-robot"});
  ASSERT_TRUE(check.ok());
  std::string out, l;
  while (!(l = check.read_line()).empty()) out += l + "\n";
  EXPECT_EQ(check.wait(), 0) << out;
  EXPECT_NE(out.find("force plate (robotiq_ft300 on " + link + ")"), std::string::npos) << out;
  EXPECT_NE(out.find("FTS-3.1.4"), std::string::npos) << out;
  EXPECT_NE(out.find("FAK-0300 (2026)"), std::string::npos) << out;
  EXPECT_NE(out.find("wrench"), std::string::npos) << out;
  // Options that do not apply to a serial sensor are refused, by name.
  hil::test::Child wrong({kHil, "--log-level", "warn", "fake-rig", "--rig", rig, "--no-robot", "--plate-status", "0x4@0:1", "--duration",
                          "0.2"});
  ASSERT_TRUE(wrong.ok());
  EXPECT_NE(wrong.wait(), 0);
}
