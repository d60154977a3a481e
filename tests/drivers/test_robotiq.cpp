// The Robotiq FT 300 on a serial line: the codec against the manual's example bytes, the driver
// against an independent Python sensor (tests/drivers/ft300_sensor.py, written with struct from
// Robotiq's manual) and against the fake on a pseudo-terminal with every fault it injects: nothing
// the sensor sent intact is lost, nothing corrupt is delivered, the only write is the allowed one.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/robotiq_driver.hpp>
#include <hil/drivers/robotiq_ft300.hpp>
#include <hil/test/drivers.hpp>
#include <hil/test/process.hpp>

using namespace hil::drivers;
namespace rq = hil::drivers::robotiq;

namespace {

ForcePlateConfig ft300_config(const std::string& device, bool stream, double rate_hz = 100.0) {
  ForcePlateConfig c;
  c.protocol = ForcePlateProtocol::robotiq_ft300;
  c.serial_device = device;
  c.robotiq_stream = stream;
  c.rate_hz = rate_hz;
  c.startup_timeout_s = 0.3;
  return c;
}

std::vector<std::uint8_t> frame_of(const rq::Reading& r) {
  std::vector<std::uint8_t> f(rq::kFrameBytes);
  rq::encode_frame(r, f.data());
  return f;
}

}  // namespace

TEST(Ft300Codec, CrcMatchesRobotiqsPublishedRtuExamples) {
  // Robotiq's Hand-E manual (Modbus RTU, slave 9, CRC low byte first):
  // "Request is: 09 04 07 D0 00 03 B1 CE" and "Response is: 09 10 03 E8 00 03 01 30".
  const std::uint8_t request[] = {0x09, 0x04, 0x07, 0xD0, 0x00, 0x03};
  EXPECT_EQ(rq::crc16(request), 0xCEB1);
  const std::uint8_t response[] = {0x09, 0x10, 0x03, 0xE8, 0x00, 0x03};
  EXPECT_EQ(rq::crc16(response), 0x3001);
}

TEST(Ft300Codec, FramesRoundTripAndTheFramerStepsOverNoiseAndCorruptFrames) {
  rq::Reading a, b, c;
  a.counts = {100, -200, 32767, -32768, 5, 0};
  b.counts = {1, 2, 3, 4, 5, 6};
  c.counts = {-7, 0x2020, 0x4E20, 0, 0, -1};  // values that contain the header bytes
  const auto fa = frame_of(a);
  EXPECT_EQ(fa[0], 0x20);
  EXPECT_EQ(fa[1], 0x4E);
  EXPECT_EQ(fa[2], 100);  // little-endian
  EXPECT_EQ(fa[3], 0);
  rq::Reading out;
  ASSERT_TRUE(rq::decode_frame(fa.data(), out));
  EXPECT_EQ(out.counts, a.counts);
  EXPECT_DOUBLE_EQ(out.si()[0], 1.0);
  EXPECT_DOUBLE_EQ(out.si()[3], -32.768);

  // noise, a, a corrupt copy of b, c cut in two pushes, b
  std::vector<std::uint8_t> line{0x01, 0x20, 0x33, 0xFF};
  line.insert(line.end(), fa.begin(), fa.end());
  auto bad = frame_of(b);
  bad[7] ^= 0x10;
  line.insert(line.end(), bad.begin(), bad.end());
  const auto fc = frame_of(c);
  line.insert(line.end(), fc.begin(), fc.end());
  const auto fb = frame_of(b);
  line.insert(line.end(), fb.begin(), fb.end());
  rq::StreamFramer framer;
  std::vector<rq::Reading> got;
  const std::size_t cut = 4 + 16 + 16 + 9;
  ASSERT_EQ(framer.push({line.data(), cut}), cut);
  while (framer.next(out)) got.push_back(out);
  ASSERT_EQ(framer.push({line.data() + cut, line.size() - cut}), line.size() - cut);
  while (framer.next(out)) got.push_back(out);
  ASSERT_EQ(got.size(), 3U);
  EXPECT_EQ(got[0].counts, a.counts);
  EXPECT_EQ(got[1].counts, c.counts);
  EXPECT_EQ(got[2].counts, b.counts);
  EXPECT_EQ(framer.bad_crc(), 1U);
  EXPECT_EQ(framer.resyncs(), 2U);  // the leading noise, the corrupt frame
}

TEST(Ft300Codec, IdentityRegistersDecodeAsRobotiqsDriverPrintsThem) {
  const std::uint16_t fw[3] = {0x4654, 0x5302, 0x0007};  // 'F' 'T' 'S' 2 0 7
  EXPECT_EQ(rq::decode_firmware(std::span<const std::uint16_t, 3>(fw, 3)), "FTS-2.0.7");
  const std::uint16_t not_fw[3] = {0x4154, 0, 0};
  EXPECT_EQ(rq::decode_firmware(std::span<const std::uint16_t, 3>(not_fw, 3)), "");
  const std::uint16_t sn[4] = {0x5059, 0x5400, 0x0001, 0x0002};  // "PYT", low word first: 0x00020001
  EXPECT_EQ(rq::decode_serial(std::span<const std::uint16_t, 4>(sn, 4)), "PYT-131073");
  const std::uint16_t none[4] = {0x5059, 0x5400, 0, 0};
  EXPECT_EQ(rq::decode_serial(std::span<const std::uint16_t, 4>(none, 4)), "UNKNOWN");
  // A corrupt register (a NUL, a control byte) shows as '?', never cuts the text (fuzz_robotiq found it).
  const std::uint16_t nul[4] = {0x0041, 0x0700, 0x0001, 0x0000};
  EXPECT_EQ(rq::decode_serial(std::span<const std::uint16_t, 4>(nul, 4)), "?A?-0001");
  const auto enc = rq::encode_serial("ABC", 42);
  EXPECT_EQ(rq::decode_serial(enc), "ABC-0042");
  EXPECT_EQ(rq::decode_firmware(rq::encode_firmware("FTS", 3, 1, 4)), "FTS-3.1.4");
}

TEST(Ft300Driver, ReadsAnIndependentPythonSensorAndWritesOnlyTheStreamStart) {
  // 6 frames: Fx = (250 + k) / 100 N, Fy -1.5 N, Fz 300 N, Mx 2 N·m, My -0.001 N·m, Mz 0.
  hil::test::Child sensor({HIL_PYTHON3, std::string(HIL_SOURCE_DIR) + "/tests/drivers/ft300_sensor.py", "6", "250", "-150", "30000", "2000",
                           "-1", "0"});
  ASSERT_TRUE(sensor.ok());
  const std::string path = sensor.read_line();
  ASSERT_EQ(path.rfind("/dev/pts/", 0), 0U) << "the Python sensor did not start: '" << path << "'";
  RobotiqFt300Driver drv(ft300_config(path, true));
  const auto info = drv.start();
  EXPECT_EQ(info.firmware, "FTS-2.0.7");
  EXPECT_EQ(info.serial, "PYT-4242 (2024)");
  // The requests on the wire, in order: identity reads, then the one write.
  EXPECT_EQ(sensor.read_line(), "request 9 3 500 3");
  EXPECT_EQ(sensor.read_line(), "request 9 3 510 4");
  EXPECT_EQ(sensor.read_line(), "request 9 3 514 1");
  EXPECT_EQ(sensor.read_line(), "request 9 16 410 1");
  WrenchSample s;
  for (int k = 1; k <= 6; ++k) {
    ASSERT_EQ(drv.poll(s), PollStatus::ok) << "frame " << k << ": " << drv.last_problem();
    EXPECT_NEAR(s.w_sensor[0], (250 + k) / 100.0, 1e-12);
    EXPECT_NEAR(s.w_sensor[1], -1.5, 1e-12);
    EXPECT_NEAR(s.w_sensor[2], 300.0, 1e-12);
    EXPECT_NEAR(s.w_sensor[3], 2.0, 1e-12);
    EXPECT_NEAR(s.w_sensor[4], -0.001, 1e-12);
    EXPECT_FALSE(s.device_fault);
    EXPECT_GT(s.t_ns, 0);
  }
  EXPECT_EQ(drv.poll(s), PollStatus::timeout) << "the sensor sent 6 frames";
  EXPECT_EQ(drv.counters().bad_frames, 0U);
}

TEST(Ft300Driver, WithoutTheRigsPermissionItOnlyReadsRegisters) {
  FakeFt300Config fc;
  FakeRobotiqFt300 fake(fc);
  fake.set_wrench((Vector6d() << 1.25, -2.5, 100.0, 0.5, -0.25, 0.125).finished());
  fake.start();
  RobotiqFt300Driver drv(ft300_config(fake.device_path(), false, 20.0));
  EXPECT_TRUE(drv.paced()) << "register polling is paced by the caller";
  const auto info = drv.start();
  EXPECT_EQ(info.firmware, "FTS-3.1.4");
  EXPECT_EQ(info.serial, "FAK-0300 (2026)");
  WrenchSample s;
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
    EXPECT_NEAR(s.w_fp[0], 1.25, 1e-9);
    EXPECT_NEAR(s.w_fp[1], -2.5, 1e-9);
    EXPECT_NEAR(s.w_fp[2], 100.0, 1e-9);
    EXPECT_NEAR(s.w_fp[3], 0.5, 1e-9);
    EXPECT_NEAR(s.w_fp[5], 0.125, 1e-9);
  }
  const auto st = fake.stats();
  EXPECT_EQ(st.stream_starts, 0U) << "the driver wrote without the rig's permission";
  EXPECT_FALSE(fake.streaming());
  EXPECT_EQ(st.exceptions, 0U);
  EXPECT_EQ(st.replies, 3U + 5U);
  // 19200 baud does not carry 100 register reads a second: the configuration says so.
  EXPECT_THROW(RobotiqFt300Driver(ft300_config(fake.device_path(), false, 100.0)), ConfigError);
}

TEST(Ft300Driver, AStreamLeftRunningIsStoppedBeforeTheIdentityIsRead) {
  FakeFt300Config fc;
  fc.streaming_at_start = true;
  FakeRobotiqFt300 fake(fc);
  fake.start();
  RobotiqFt300Driver drv(ft300_config(fake.device_path(), false, 10.0));
  const auto info = drv.start();
  EXPECT_EQ(info.firmware, "FTS-3.1.4");
  EXPECT_GE(fake.stats().stream_stops, 1U);
  EXPECT_FALSE(fake.streaming());
}

TEST(Ft300Driver, TheStreamUnderFaultsLosesNothingTheSensorSentIntact) {
  FakeFt300Config fc;
  fc.stream_rate_hz = 400.0;  // faster than the product, for a short test with many frames
  fc.stream.drop_fraction = 0.04;
  fc.stream.corrupt_fraction = 0.04;
  fc.noise_fraction = 0.1;
  fc.seed = 77;
  FakeRobotiqFt300 fake(fc);
  fake.set_wrench((Vector6d() << 3.0, 0.0, -50.0, 0.0, 1.5, 0.0).finished());
  fake.start();
  RobotiqFt300Driver drv(ft300_config(fake.device_path(), true, fc.stream_rate_hz));
  drv.start();
  EXPECT_FALSE(drv.paced());
  WrenchSample s;
  std::uint64_t ok = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(1500);
  while (std::chrono::steady_clock::now() < end) {
    if (drv.poll(s) != PollStatus::ok) continue;
    ++ok;
    ASSERT_NEAR(s.w_fp[2], -50.0, 1e-9) << "a corrupt frame was delivered";
    ASSERT_NEAR(s.w_fp[4], 1.5, 1e-9);
  }
  fake.stop();
  for (int k = 0; k < 20; ++k)
    if (drv.poll(s) == PollStatus::ok) ++ok;
  const auto st = fake.stats();
  ASSERT_GT(st.frames_sent, 300U);
  EXPECT_GT(st.frames_dropped, 5U);
  EXPECT_GT(st.frames_corrupted, 5U);
  EXPECT_EQ(st.overruns, 0U);
  EXPECT_EQ(ok, st.frames_sent) << "every intact frame is delivered, each once";
  EXPECT_EQ(drv.counters().bad_frames, st.frames_corrupted) << "every corrupt frame is counted";
  // Lost frames are estimated from arrival gaps (no sequence numbers on the line); a corrupt
  // frame is a gap too. Within a third of the truth on a loaded machine.
  const double lost = static_cast<double>(st.frames_dropped + st.frames_corrupted);
  EXPECT_NEAR(static_cast<double>(drv.counters().dropped_frames), lost, lost / 3.0 + 2.0);
}

TEST(Ft300Driver, ASilentStreamIsCountedAndResumes) {
  FakeFt300Config fc;
  fc.stream.silent = {{0.3, 0.4}};
  FakeRobotiqFt300 fake(fc);
  fake.start();
  RobotiqFt300Driver drv(ft300_config(fake.device_path(), true));
  drv.start();
  WrenchSample s;
  std::uint64_t before = 0, after = 0;
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(1100)) {
    const bool got = drv.poll(s) == PollStatus::ok;
    if (!got) continue;
    if (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(300)) ++before;
    else ++after;
  }
  EXPECT_GT(before, 10U);
  EXPECT_GT(after, 20U) << "the stream resumed";
  EXPECT_GE(drv.counters().timeouts, 5U) << "0.4 s of silence at 100 Hz";
  EXPECT_GT(fake.stats().frames_silenced, 30U);
}

TEST(Ft300Driver, ModbusExceptionsAreDeviceFaultsAndTheReadingsResume) {
  FakeFt300Config fc;
  FakeRobotiqFt300 fake(fc);
  fake.start();
  RobotiqFt300Driver drv(ft300_config(fake.device_path(), false, 20.0));
  drv.start();
  ModbusFaults burst;
  burst.exception_fraction = 1.0;
  fake.set_faults({}, burst);
  WrenchSample s;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(drv.poll(s), PollStatus::exception);
  EXPECT_EQ(drv.counters().exceptions, 4U);
  EXPECT_EQ(drv.counters().device_faults, 4U);
  EXPECT_NE(drv.last_problem().find("180-185"), std::string::npos) << drv.last_problem();
  fake.set_faults({}, {});
  EXPECT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
}

TEST(Ft300Driver, WhatIsWrongIsNamed) {
  const auto message = [](const ForcePlateConfig& c) {
    try {
      RobotiqFt300Driver drv(c);
      drv.start();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("started");
  };
  EXPECT_NE(message(ft300_config("/dev/no-such-port", false, 10.0)).find("/dev/no-such-port: cannot open the port"), std::string::npos);
  FakeFt300Config other;
  other.firmware_prefix = "XYZ";
  FakeRobotiqFt300 not_ft(other);
  not_ft.start();
  EXPECT_NE(message(ft300_config(not_ft.device_path(), false, 10.0)).find("not an FT 300"), std::string::npos);
  FakeFt300Config nine;
  nine.slave = 10;
  FakeRobotiqFt300 wrong_slave(nine);
  wrong_slave.start();
  auto c = ft300_config(wrong_slave.device_path(), false, 10.0);
  c.startup_tries = 1;
  c.startup_timeout_s = 0.1;
  EXPECT_NE(message(c).find("no answer to a read of registers 500-502 from slave 9"), std::string::npos) << message(c);
  auto baud = ft300_config("/dev/ttyUSB0", false, 10.0);
  baud.serial_baud = 115200;
  EXPECT_NE(message(baud).find("19200"), std::string::npos);
  FakeFt300Config dup;
  dup.stream.duplicate_fraction = 0.1;
  EXPECT_THROW(FakeRobotiqFt300{dup}, ConfigError);
}
