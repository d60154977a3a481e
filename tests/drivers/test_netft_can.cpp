// The Net F/T box's CAN mode (short data): the codec against the manual's byte order, the driver
// against the fake box on the in-process bus with every fault it injects: every answer the box sent
// whole is a reading, a cut answer is a bad frame, a status bit is a device fault, the bias command
// reaches the box.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/netft_can.hpp>
#include <hil/drivers/netft_driver.hpp>

using namespace hil::drivers;

namespace {

constexpr std::uint32_t kBase = 0x120;

ForcePlateConfig box_config(double rate_hz = 500.0) {
  ForcePlateConfig c;
  c.protocol = ForcePlateProtocol::ati_netft_can;
  c.base_id = kBase;
  c.netft_calibration = {100.0, 1000.0, "N", "Nm"};  // 16-bit values: 0.01 N, 1 mN·m
  c.rate_hz = rate_hz;
  c.startup_timeout_s = 0.2;
  return c;
}

/// For tests of what a reading holds, not of its timing: the default answer window (0.9 period,
/// 1.8 ms at 500 Hz) is shorter than a loaded CI machine may take to schedule the fake box's thread
/// (a fresh-clone CI run saw one poll time out here).
ForcePlateConfig patient_config() {
  auto c = box_config();
  c.response_timeout_s = 0.2;
  return c;
}

/// The fake box on an in-process bus and a started driver on it.
struct BoxOnBus {
  std::shared_ptr<CanLoopbackBus> bus = CanLoopbackBus::create("netft-can");
  FakeNetCanOemBoard box;
  std::unique_ptr<CanForcePlate> drv;
  explicit BoxOnBus(FakeNetCanOemConfig fc, const ForcePlateConfig& dc = box_config()) : box(with_box(fc), bus->open()) {
    box.start();
    drv = make_force_plate(dc, bus->open());
    drv->start();
  }
  static FakeNetCanOemConfig with_box(FakeNetCanOemConfig fc) {
    fc.netft_box = true;
    fc.base_id = kBase;
    fc.box_calibration = {100.0, 1000.0, "N", "Nm"};
    return fc;
  }
};

}  // namespace

TEST(NetFtCanCodec, ShortDataIsLittleEndianInTheManualsOrder) {
  netft_can::ShortData d;
  d.counts = {0x0256, -2, 3, 4, 5, 6};  // Fx Fy Fz Tx Ty Tz
  d.status = 0x8001;
  d.sample = 0xBEEF;
  const auto f = netft_can::encode_short(0x100, d);
  EXPECT_EQ(f[0].id, 0x105U);
  EXPECT_EQ(f[1].id, 0x106U);
  // The manual: "a 16-bit value received as 0x56 0x02 represents 0x0256"; answer 1 = Fx Tx Fy Ty.
  const std::uint8_t first[8] = {0x56, 0x02, 4, 0, 0xFE, 0xFF, 5, 0};
  const std::uint8_t second[8] = {3, 0, 6, 0, 0x01, 0x80, 0xEF, 0xBE};  // Fz Tz status sample
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(f[0].data[static_cast<std::size_t>(i)], first[i]) << "answer 1 byte " << i;
    EXPECT_EQ(f[1].data[static_cast<std::size_t>(i)], second[i]) << "answer 2 byte " << i;
  }
  netft_can::ShortData back;
  ASSERT_TRUE(netft_can::decode_short_first(f[0], back));
  ASSERT_TRUE(netft_can::decode_short_second(f[1], back));
  EXPECT_EQ(back.counts, d.counts);
  EXPECT_EQ(back.status, d.status);
  EXPECT_EQ(back.sample, d.sample);
  auto cut = f[1];
  cut.len = 6;
  EXPECT_FALSE(netft_can::decode_short_second(cut, back));
  const auto req = netft_can::request(0x100, netft_can::kRequestShortData);
  EXPECT_EQ(req.id, 0x100U);
  EXPECT_EQ(req.len, 1U);
  EXPECT_EQ(req.data[0], 0x02);
}

TEST(NetFtCanDriver, ReadsTheBoxScaledByTheRigsCountsAndBiasesIt) {
  FakeNetCanOemConfig fc;
  BoxOnBus rig(fc, patient_config());
  rig.box.set_wrench((Vector6d() << 1.5, -2.25, 120.0, 0.25, -0.5, 0.125).finished());
  WrenchSample s;
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok) << rig.drv->last_problem();
  EXPECT_NEAR(s.w_fp[0], 1.5, 1e-9);
  EXPECT_NEAR(s.w_fp[1], -2.25, 1e-9);
  EXPECT_NEAR(s.w_fp[2], 120.0, 1e-9);
  EXPECT_NEAR(s.w_fp[3], 0.25, 1e-9);
  EXPECT_NEAR(s.w_fp[5], 0.125, 1e-9);
  EXPECT_FALSE(s.device_fault);
  auto& box = dynamic_cast<NetFtCanDriver&>(*rig.drv);
  const auto before = box.last_sample_number();
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok);
  EXPECT_EQ(static_cast<std::uint16_t>(box.last_sample_number() - before), 1U) << "the box counts its answers";
  ASSERT_TRUE(box.bias_on_device());
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok);
  EXPECT_NEAR(s.w_fp[2], 0.0, 1e-9) << "the box biased its readings at the present load";
}

TEST(NetFtCanDriver, StatusBitsAreDeviceFaultsNamedByBit) {
  FakeNetCanOemConfig fc;
  fc.faults.status_now = 0x0004;
  BoxOnBus rig(fc, patient_config());
  WrenchSample s;
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok);
  EXPECT_TRUE(s.device_fault);
  EXPECT_EQ(s.status_word, 0x8004U);
  EXPECT_EQ(rig.drv->describe_status(s), "Net F/T CAN status 0x8004 (bit 15, bit 2)");
  EXPECT_GE(rig.drv->counters().device_faults, 1U);
}

TEST(NetFtCanDriver, EveryWholeAnswerIsAReadingUnderDropsCorruptionSilenceAndDelay) {
  FakeNetCanOemConfig fc;
  fc.faults.drop_fraction = 0.05;
  fc.faults.corrupt_fraction = 0.05;
  fc.faults.silent = {{0.3, 0.1}};
  fc.seed = 11;
  BoxOnBus rig(fc);
  WrenchSample s;
  std::uint64_t ok = 0, bad = 0, timeouts = 0;
  RatePacer pacer(500.0);  // as the acquisition polls: 0.8 s, across the silence
  for (int k = 0; k < 400; ++k) {
    pacer.wait();
    const auto st = rig.drv->poll(s);
    ok += st == PollStatus::ok;
    bad += st == PollStatus::bad_frame;
    timeouts += st == PollStatus::timeout;
  }
  rig.box.stop();
  const auto stats = rig.box.stats();
  EXPECT_GT(stats.answers_corrupted, 5U);
  EXPECT_GT(stats.frames_dropped, 5U);
  EXPECT_GT(stats.ignored_silent, 20U);
  // Each whole answer was read (none lost, none torn) or, when it came after its poll had given up
  // (a loaded machine), drained as late by the next poll; at most the last one is still in flight.
  // (A fresh-clone CI run saw 3 of 303 answers late.)
  const auto late = rig.drv->counters().late_frames;
  EXPECT_LE(ok + 1, stats.gauge_answers_delivered) << "the start-up reading is one of the box's answers";
  EXPECT_LE(stats.gauge_answers_delivered, ok + 1 + late + 1) << "an answer neither read nor counted late";
  EXPECT_EQ(bad, rig.drv->counters().bad_frames);
  EXPECT_GE(bad, stats.answers_corrupted - 2) << "a cut first answer is a bad frame";
  EXPECT_GT(timeouts, 20U);
}

TEST(NetFtCanDriver, WhatIsWrongIsNamed) {
  auto c = box_config();
  c.base_id = 0x7FA;
  EXPECT_THROW(NetFtCanDriver(c, CanLoopbackBus::create("x")->open()), ConfigError);
  c = box_config();
  c.netft_calibration.counts_per_force = 0.0;
  EXPECT_THROW(NetFtCanDriver(c, CanLoopbackBus::create("y")->open()), ConfigError);
  // Nobody at the base address: the start names it and what to check.
  auto bus = CanLoopbackBus::create("empty");
  NetFtCanDriver drv(box_config(), bus->open());
  try {
    drv.start();
    FAIL() << "started without a box";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("base address 0x120"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("CAN Bus"), std::string::npos) << e.what();
  }
}
