// The Net F/T box's RDT over UDP: the codec byte for byte, the calibration page, the driver against
// an independent Python peer (tests/drivers/netft_box.py, written with struct from ATI's layout)
// and against the fake box with every fault it injects; nothing the driver hands out is lost and
// every record the box sent is either handed out or counted as lost.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/netft_driver.hpp>
#include <hil/drivers/netft_rdt.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;
using hil::test::eventually;

namespace {

ForcePlateConfig rdt_config(int port, double rate_hz = 1000.0) {
  ForcePlateConfig c;
  c.protocol = ForcePlateProtocol::ati_netft_rdt;
  c.host = "127.0.0.1";
  c.port = port;
  c.rate_hz = rate_hz;
  c.netft_calibration = {1'000'000.0, 1'000'000.0, "N", "Nm"};
  c.startup_timeout_s = 0.5;
  return c;
}

/// The fake box streaming and a started driver on it.
struct BoxAndDriver {
  FakeNetFtRdt box;
  NetFtRdtDriver drv;
  explicit BoxAndDriver(const FakeNetFtConfig& fc) : box(fc), drv(rdt_config(box.port(), fc.rate_hz)) {
    box.start();
    drv.start();
  }
};

}  // namespace

TEST(NetFtRdt, RequestsAreEightBigEndianBytes) {
  const auto r = netft::encode_request(netft::RdtCommand::start_realtime, 0x01020304);
  const std::array<std::uint8_t, 8> expected{0x12, 0x34, 0x00, 0x02, 0x01, 0x02, 0x03, 0x04};
  EXPECT_EQ(r, expected);
  EXPECT_EQ(netft::encode_request(netft::RdtCommand::set_bias)[3], 0x42);
  EXPECT_EQ(netft::encode_request(netft::RdtCommand::reset_latch)[3], 0x41);
  EXPECT_EQ(netft::encode_request(netft::RdtCommand::stop)[3], 0x00);
  EXPECT_EQ(netft::encode_request(netft::RdtCommand::start_buffered)[3], 0x03);
  netft::RdtRequest q;
  ASSERT_TRUE(netft::decode_request(r, q));
  EXPECT_EQ(q.command, 0x0002);
  EXPECT_EQ(q.sample_count, 0x01020304U);
  EXPECT_FALSE(netft::decode_request(std::span<const std::uint8_t>(r.data(), 7), q));
  auto bad = r;
  bad[0] = 0x34;
  EXPECT_FALSE(netft::decode_request(bad, q)) << "a wrong header is not a request";
}

TEST(NetFtRdt, RecordsAreThirtySixBigEndianBytesWithSignedCounts) {
  // Written by hand from the layout: rdt 1, ft 0x0A0B0C0D, status 0x80010000, Fx -2, Tz 0x7FFFFFFF.
  const std::uint8_t bytes[36] = {0, 0, 0, 1, 0x0A, 0x0B, 0x0C, 0x0D, 0x80, 0x01, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0,    0,
                                  0, 0, 0, 0, 0,    5,    0,    0,    0,    0,    0, 0, 0,    0,    0x7F, 0xFF, 0xFF, 0xFF};
  netft::RdtRecord r;
  netft::decode_record(bytes, r);
  EXPECT_EQ(r.rdt_sequence, 1U);
  EXPECT_EQ(r.ft_sequence, 0x0A0B0C0DU);
  EXPECT_EQ(r.status, 0x80010000U);
  EXPECT_EQ(r.counts[0], -2);
  EXPECT_EQ(r.counts[2], 5);
  EXPECT_EQ(r.counts[5], 0x7FFFFFFF);
  std::uint8_t back[36];
  netft::encode_record(r, back);
  for (int i = 0; i < 36; ++i) EXPECT_EQ(back[i], bytes[i]) << "byte " << i;
  EXPECT_EQ(netft::records_in(36), 1U);
  EXPECT_EQ(netft::records_in(108), 3U);
  EXPECT_EQ(netft::records_in(35), 0U);
  EXPECT_EQ(netft::records_in(0), 0U);
  EXPECT_EQ(netft::records_in(37), 0U);
}

TEST(NetFtRdt, StatusWordsNameTheBitsTheSourcesAgreeOn) {
  EXPECT_EQ(netft::describe_status(0), "0x00000000 (ok)");
  EXPECT_EQ(netft::describe_status(0x80010000U), "0x80010000 (any error, monitor condition latched)");
  EXPECT_EQ(netft::describe_status(0x80000004U), "0x80000004 (any error, bit 2)");
}

TEST(NetFtCalibration, TheBoxsPageGivesCountsAndUnits) {
  const char* xml = R"(<?xml version="1.0"?>
<netft><prodname>Net F/T</prodname><cfgcpf>1000000</cfgcpf><cfgcpt>1000</cfgcpt><scfgfu>N</scfgfu><scfgtu>N-mm</scfgtu></netft>)";
  const auto c = netft::parse_calibration_xml(xml, "netftapi2.xml");
  EXPECT_EQ(c.counts_per_force, 1e6);
  EXPECT_EQ(c.counts_per_torque, 1e3);
  EXPECT_DOUBLE_EQ(c.newtons_per_count(), 1e-6);
  EXPECT_DOUBLE_EQ(c.newton_metres_per_count(), 1e-6);  // 1/1000 N·mm per count
  netft::Calibration lbf{1000.0, 1000.0, "lbf", "lbf-in"};
  EXPECT_NEAR(lbf.newtons_per_count(), 4.4482216152605e-3, 1e-15);
  EXPECT_NEAR(lbf.newton_metres_per_count(), 0.1129848290276167e-3, 1e-15);
}

TEST(NetFtCalibration, BadPagesAreNamedWithWhereAndWhat) {
  const auto message = [](const char* xml) {
    try {
      netft::parse_calibration_xml(xml, "box.xml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("<netft><cfgcpf>1</cfgcpf>").find("box.xml: not XML"), std::string::npos) << message("<netft><cfgcpf>1</cfgcpf>");
  EXPECT_NE(message("<html/>").find("no <netft>"), std::string::npos);
  EXPECT_NE(message("<netft><cfgcpf>1e6</cfgcpf><scfgfu>N</scfgfu><scfgtu>Nm</scfgtu></netft>").find("no <cfgcpt>"), std::string::npos);
  EXPECT_NE(message("<netft><cfgcpf>-3</cfgcpf><cfgcpt>1</cfgcpt><scfgfu>N</scfgfu><scfgtu>Nm</scfgtu></netft>").find("'-3'"),
            std::string::npos);
  EXPECT_NE(message("<netft><cfgcpf>1</cfgcpf><cfgcpt>1</cfgcpt><scfgfu>stone</scfgfu><scfgtu>Nm</scfgtu></netft>").find("'stone'"),
            std::string::npos);
}

TEST(NetFtDriver, ReadsAnIndependentPeerRecordByRecordAcrossBufferedDatagrams) {
  // 7 records in datagrams of 3 (3 + 3 + 1), status 0, counts Fx 1000+seq, Fy -2e6, Fz 5e5, T 1000, -7, 0.
  hil::test::Child box({HIL_PYTHON3, std::string(HIL_SOURCE_DIR) + "/tests/drivers/netft_box.py", "7", "3", "0", "1000", "-2000000",
                        "500000", "1000", "-7", "0"});
  ASSERT_TRUE(box.ok());
  const std::string port = box.read_line();
  ASSERT_FALSE(port.empty()) << "the Python box did not start";
  NetFtRdtDriver drv(rdt_config(std::stoi(port)));
  drv.start();
  EXPECT_EQ(box.read_line(), "request 0x1234 0x0002 0") << "the start request on the wire";
  WrenchSample s;
  for (std::uint32_t k = 1; k <= 7; ++k) {
    ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
    EXPECT_EQ(drv.last_rdt_sequence(), k);
    EXPECT_NEAR(s.w_sensor[0], (1000.0 + k) * 1e-6, 1e-12);
    EXPECT_NEAR(s.w_sensor[1], -2.0, 1e-12);
    EXPECT_NEAR(s.w_sensor[2], 0.5, 1e-12);
    EXPECT_NEAR(s.w_sensor[3], 1e-3, 1e-12);
    EXPECT_NEAR(s.w_sensor[4], -7e-6, 1e-12);
    EXPECT_FALSE(s.device_fault);
    EXPECT_GT(s.t_ns, 0);
  }
  EXPECT_EQ(drv.counters().dropped_frames, 0U);
  EXPECT_EQ(drv.counters().samples, 7U);
  ASSERT_TRUE(drv.bias_on_device());
  EXPECT_EQ(box.read_line(), "request 0x1234 0x0042 0");
  ASSERT_TRUE(drv.reset_latch());
  EXPECT_EQ(box.read_line(), "request 0x1234 0x0041 0");
}

TEST(NetFtDriver, APeerStatusWordMarksEverySampleAsADeviceFault) {
  hil::test::Child box({HIL_PYTHON3, std::string(HIL_SOURCE_DIR) + "/tests/drivers/netft_box.py", "3", "1", "0x80000004", "0", "0", "0",
                        "0", "0", "0"});
  ASSERT_TRUE(box.ok());
  const std::string port = box.read_line();
  ASSERT_FALSE(port.empty());
  NetFtRdtDriver drv(rdt_config(std::stoi(port)));
  drv.start();
  WrenchSample s;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(drv.poll(s), PollStatus::ok);
    EXPECT_TRUE(s.device_fault);
    EXPECT_EQ(s.status_word, 0x80000004U);
  }
  EXPECT_EQ(drv.counters().device_faults, 3U);
  EXPECT_EQ(drv.describe_status(s), "Net F/T status 0x80000004 (any error, bit 2)");
}

TEST(NetFtDriver, ReadsTheFakeBoxsWrenchInThePlateFrame) {
  FakeNetFtConfig fc;
  fc.T_fp_sensor.translation() = Eigen::Vector3d(0.1, -0.05, 0.02);
  fc.T_fp_sensor.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1, 0.3).normalized()).toRotationMatrix();
  FakeNetFtRdt box(fc);
  Vector6d w;
  w << 12.5, -3.25, 410.0, 1.5, -0.75, 0.125;
  box.set_wrench(w);
  box.start();
  auto cfg = rdt_config(box.port());
  cfg.T_fp_sensor = fc.T_fp_sensor;
  NetFtRdtDriver drv(cfg);
  const auto info = drv.start();
  EXPECT_EQ(info.protocol, "ati_netft_rdt");
  EXPECT_EQ(info.units, "N, Nm");
  WrenchSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
  // One count is 1e-6 N: the plate-frame wrench comes back through two transforms and rounding.
  EXPECT_TRUE(hil::test::near6(s.w_fp, w, Vector6d::Constant(1e-5)));
  EXPECT_EQ(drv.link(), "udp 127.0.0.1:" + std::to_string(box.port()));
  // The box's bias: the reading goes to zero.
  ASSERT_TRUE(drv.bias_on_device());
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok && s.w_sensor.norm() < 1e-5; }));
  EXPECT_EQ(box.stats().biases, 1U);
}

TEST(NetFtDriver, EveryRecordIsHandedOutOrCountedLostUnderDropsCorruptionAndDuplicates) {
  FakeNetFtConfig fc;
  fc.rate_hz = 2000;
  fc.faults.drop_fraction = 0.05;
  fc.faults.corrupt_fraction = 0.02;
  fc.faults.duplicate_fraction = 0.03;
  fc.seed = 7;
  BoxAndDriver bd(fc);
  auto& box = bd.box;
  auto& drv = bd.drv;
  WrenchSample s;
  std::uint64_t ok = 0, bad = 0;
  std::uint32_t previous = 0;
  while (ok < 3000) {
    const PollStatus st = drv.poll(s);
    if (st == PollStatus::ok) {
      ++ok;
      EXPECT_GT(drv.last_rdt_sequence(), previous) << "handed out in order, each once";
      previous = drv.last_rdt_sequence();
    } else if (st == PollStatus::bad_frame) {
      ++bad;
      EXPECT_NE(drv.last_problem().find("not a whole number of 36-byte RDT records"), std::string::npos) << drv.last_problem();
    } else {
      ASSERT_EQ(st, PollStatus::timeout) << drv.last_problem();
    }
  }
  box.stop();
  while (drv.poll(s) == PollStatus::ok) ++ok;  // what was still queued
  const auto b = box.stats();
  const auto& c = drv.counters();
  EXPECT_EQ(ok, c.samples);
  EXPECT_EQ(c.samples, b.records_sent) << "every whole datagram's record was handed out";
  EXPECT_EQ(c.bad_frames, b.datagrams_corrupted);
  EXPECT_EQ(c.late_frames, b.datagrams_duplicated) << "duplicates are recognised by their sequence";
  // Lost on the way (dropped, or inside a corrupt datagram) = the gaps in rdt_sequence.
  EXPECT_EQ(c.samples + c.dropped_frames, drv.last_rdt_sequence());
  EXPECT_GT(c.dropped_frames, 0U);
  EXPECT_GT(bad, 0U);
}

TEST(NetFtDriver, ASilentBoxTimesOutThenIsAskedAgainAndRecovers) {
  FakeNetFtConfig fc;
  BoxAndDriver bd(fc);
  auto& box = bd.box;
  auto& drv = bd.drv;
  WrenchSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok);
  // The box reboots: it forgets the stream, and ignores requests for a while.
  StreamFaults f;
  f.deaf = {TimeWindow{0.0, 1e6}};
  box.set_faults(f);
  box.stop();
  box.start();  // the fault windows count from here: deaf from now on, until cleared
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::timeout; }));
  EXPECT_GT(drv.counters().timeouts, 0U);
  box.set_faults(StreamFaults{});
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok; })) << drv.last_problem();
  EXPECT_GE(box.stats().starts, 1U);
  EXPECT_GT(drv.counters().retries, 0U);
}

TEST(NetFtDriver, StatusWindowsOfTheFakeAreDeviceFaultsAndTheLatchIsReset) {
  FakeNetFtConfig fc;
  fc.faults.status_now = netft::kStatusMonitorLatched;
  BoxAndDriver bd(fc);
  auto& box = bd.box;
  auto& drv = bd.drv;
  WrenchSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok);
  EXPECT_TRUE(s.device_fault);
  EXPECT_EQ(s.status_word, netft::kStatusMonitorLatched) << "a latched monitor condition alone is not an error bit";
  box.set_faults(StreamFaults{});
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok && s.status_word == netft::kStatusMonitorLatched; }))
      << "the latch holds until reset";
  ASSERT_TRUE(drv.reset_latch());
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok && s.status_word == 0; }));
  EXPECT_FALSE(s.device_fault);
  StreamFaults err;
  err.status_now = 0x00000004;  // an error bit: bit 31 joins it
  box.set_faults(err);
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok && s.status_word != 0; }));
  EXPECT_EQ(s.status_word, 0x80000004U);
  EXPECT_TRUE(s.device_fault);
}

TEST(NetFtDriver, ConfigurationAndStartUpErrorsAreNamed) {
  auto c = rdt_config(49152);
  c.host.clear();
  EXPECT_THROW(NetFtRdtDriver{c}, ConfigError);
  c = rdt_config(49152);
  c.netft_calibration.force_unit = "stone";
  try {
    NetFtRdtDriver d(c);
    FAIL() << "accepted an unknown unit";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "force_unit");
  }
  // Nothing listens at this port: start() says so, naming the box.
  FakeNetFtRdt box(FakeNetFtConfig{});
  const int port = box.port();  // bound, never started: requests are not answered
  c = rdt_config(port);
  c.startup_timeout_s = 0.05;
  c.startup_tries = 2;
  NetFtRdtDriver d(c);
  try {
    d.start();
    FAIL() << "started without a box";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("no RDT record after 2 requests"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("udp 127.0.0.1:" + std::to_string(port)), std::string::npos) << e.what();
  }
}
