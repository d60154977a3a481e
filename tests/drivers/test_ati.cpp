// The ATI NETCANOEM protocol: pure codecs, then the driver against the fake plate over the
// loopback bus (calibration read, conversion, tare, sensor→plate transform, faults).
#include <gtest/gtest.h>

#include <numbers>
#include <thread>

#include <hil/drivers/ati_protocol.hpp>
#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;
using hil::test::near6;

TEST(AtiProtocol, GaugeFramesAreBigEndianAndInterleaved) {
  const ati::Gauges g{-2, 0x1234, -32768, 32767, 1, -1};
  const auto fr = ati::encode_gauges(0x12, 0x4000, g);
  EXPECT_EQ(fr[0].id, 0x120U);
  EXPECT_EQ(fr[1].id, 0x121U);
  ASSERT_EQ(fr[0].len, 8);
  ASSERT_EQ(fr[1].len, 6);
  const std::uint8_t a[8] = {0x40, 0x00, 0xFF, 0xFE, 0x80, 0x00, 0x00, 0x01};  // status, SG0, SG2, SG4
  const std::uint8_t b[6] = {0x12, 0x34, 0x7F, 0xFF, 0xFF, 0xFF};              // SG1, SG3, SG5
  for (int i = 0; i < 8; ++i) EXPECT_EQ(fr[0].data[static_cast<std::size_t>(i)], a[i]) << i;
  for (int i = 0; i < 6; ++i) EXPECT_EQ(fr[1].data[static_cast<std::size_t>(i)], b[i]) << i;
  ati::Gauges back{};
  std::uint16_t status = 0;
  ASSERT_TRUE(ati::decode_gauges_first(fr[0], status, back));
  ASSERT_TRUE(ati::decode_gauges_second(fr[1], back));
  EXPECT_EQ(status, 0x4000);
  EXPECT_EQ(back, g);
  CanFrame shorter = fr[0];
  shorter.len = 7;
  EXPECT_FALSE(ati::decode_gauges_first(shorter, status, back));
}

TEST(AtiProtocol, OtherMessages) {
  const ati::MatrixRow row{1.5f, -2.25f, 1e-3f, 0.0f, -7.0f, 123456.0f};
  const auto fr = ati::encode_matrix_row(0x7F, row);
  EXPECT_EQ(fr[0].id, 0x7F2U);
  EXPECT_EQ(fr[2].id, 0x7F4U);
  EXPECT_EQ(fr[0].data[0], 0x3F);  // 1.5f = 0x3FC00000, big endian
  EXPECT_EQ(fr[0].data[1], 0xC0);
  ati::MatrixRow back{};
  for (unsigned k = 0; k < 3; ++k) ASSERT_TRUE(ati::decode_matrix_part(fr[k], k, back));
  EXPECT_EQ(back, row);

  std::int32_t cpf = 0, cpt = 0;
  ASSERT_TRUE(ati::decode_counts(ati::encode_counts(1, 1000000, -5), cpf, cpt));
  EXPECT_EQ(cpf, 1000000);
  EXPECT_EQ(cpt, -5);
  EXPECT_EQ(ati::decode_serial(ati::encode_serial(1, "FT12345")), "FT12345");
  std::uint8_t fu = 0, tu = 0;
  ASSERT_TRUE(ati::decode_units(ati::encode_units(1, 2, 3), fu, tu));
  EXPECT_EQ(ati::force_unit_to_si(fu), 1.0);
  EXPECT_NEAR(ati::torque_unit_to_si(1), 0.112985, 1e-6);
  EXPECT_NEAR(ati::force_unit_to_si(1), 4.44822, 1e-5);
  ati::Firmware fw;
  ASSERT_TRUE(ati::decode_firmware(ati::encode_firmware(1, {2, 3, 0x1234}), fw));
  EXPECT_EQ(fw.build, 0x1234);
  const CanFrame req = ati::request(0x05, ati::kOpReadMatrix, 4);
  EXPECT_EQ(req.id, 0x052U);
  EXPECT_EQ(req.len, 1);
  EXPECT_EQ(req.data[0], 4);
}

namespace {

/// Fake plate and driver on one loopback bus.
struct Bench {
  std::shared_ptr<CanLoopbackBus> bus = CanLoopbackBus::create("ati-test");
  FakeNetCanOemConfig fake_cfg;
  ForcePlateConfig drv_cfg;
  std::unique_ptr<FakeNetCanOemBoard> fake;
  std::unique_ptr<CanForcePlate> plate;

  explicit Bench(const Eigen::Isometry3d& T_fp_sensor = Eigen::Isometry3d::Identity(), std::uint32_t base = 0x0A) {
    fake_cfg.base_id = base;
    fake_cfg.T_fp_sensor = T_fp_sensor;
    drv_cfg.base_id = base;
    drv_cfg.T_fp_sensor = T_fp_sensor;
    drv_cfg.response_timeout_s = 0.5;  // generous: the test machine is shared; no timing is checked
    drv_cfg.startup_timeout_s = 0.5;
  }
  void start_fake(std::shared_ptr<const Scenario> scenario = nullptr) {
    fake = std::make_unique<FakeNetCanOemBoard>(fake_cfg, bus->open(), std::move(scenario));
    fake->start();
  }
  ForcePlateInfo start_driver() {
    plate = make_force_plate(drv_cfg, bus->open());
    return plate->start();
  }
  /// The quantisation bound of the conversion: half a count on every gauge.
  Vector6d tolerance() const {
    const auto* ati = dynamic_cast<const AtiNetCanOemDriver*>(plate.get());
    const Vector6d per_gauge = 0.5 * ati->gauge_to_wrench().cwiseAbs().rowwise().sum();
    const double f = per_gauge.head<3>().norm(), m = per_gauge.tail<3>().norm();
    const double arm = drv_cfg.T_fp_sensor.translation().norm();
    Vector6d tol;
    tol << f, f, f, m + arm * f, m + arm * f, m + arm * f;
    return tol * 1.0001 + Vector6d::Constant(1e-9);
  }
};

Vector6d wrench(double fx, double fy, double fz, double mx, double my, double mz) {
  Vector6d w;
  w << fx, fy, fz, mx, my, mz;
  return w;
}

}  // namespace

TEST(AtiDriver, ReadsCalibrationFromTheDevice) {
  Bench b;
  b.fake_cfg.serial = "FT31337";
  b.fake_cfg.counts_per_force = 2000;
  b.fake_cfg.force_units = 1;  // lbf
  b.start_fake();
  const ForcePlateInfo info = b.start_driver();
  EXPECT_EQ(info.serial, "FT31337");
  EXPECT_EQ(info.firmware, "1.0.42");
  EXPECT_EQ(info.units, "lbf, N-m");
  EXPECT_EQ(info.counts_per_force, 2000);
  EXPECT_EQ(info.counts_per_torque, 100000);
  EXPECT_TRUE(info.calibration.isApprox(b.fake_cfg.calibration.cast<float>().cast<double>(), 0.0));
  const auto* ati = dynamic_cast<const AtiNetCanOemDriver*>(b.plate.get());
  EXPECT_NEAR(ati->gauge_to_wrench()(0, 0), 60.0 * 4.4482216152605 / 2000, 1e-9);
  EXPECT_NEAR(ati->gauge_to_wrench()(3, 3), 180.0 / 100000, 1e-12);
}

TEST(AtiDriver, ConvertsGaugesToTheWrenchWithinQuantisation) {
  Bench b;
  b.start_fake();
  b.start_driver();
  const Vector6d tol = b.tolerance();
  for (const Vector6d& w : {wrench(0, 0, 0, 0, 0, 0), wrench(10, -20, 500, 1.5, -2.5, 0.25), wrench(-300, 250, -1200, -30, 20, 10)}) {
    b.fake->set_wrench(w);
    WrenchSample s;
    ASSERT_EQ(b.plate->poll(s), PollStatus::ok) << b.plate->last_problem();
    EXPECT_TRUE(near6(s.w_fp, w, tol));
    EXPECT_TRUE(near6(s.w_sensor, w, tol));
    EXPECT_GT(s.t_ns, 0);
    EXPECT_EQ(s.status_word, 0);
    EXPECT_FALSE(s.gauge_saturated);
  }
  EXPECT_EQ(b.plate->counters().samples, 3U);
  EXPECT_TRUE(b.plate->counters().connected);
}

TEST(AtiDriver, AppliesTheSensorToPlateTransform) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.01, -0.02, -0.035);
  Bench b(T);
  b.start_fake();
  b.start_driver();
  const Vector6d w_fp = wrench(15, -5, 300, 2, 1, -0.5);
  b.fake->set_wrench(w_fp);
  WrenchSample s;
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok) << b.plate->last_problem();
  EXPECT_TRUE(near6(s.w_fp, w_fp, b.tolerance()));
  // The raw sensor-frame wrench is the plate wrench seen from the sensor.
  const Eigen::Matrix3d R = T.linear();
  const Eigen::Vector3d f_s = R.transpose() * w_fp.head<3>();
  const Eigen::Vector3d m_s = R.transpose() * (w_fp.tail<3>() - T.translation().cross(w_fp.head<3>()));
  Vector6d w_s;
  w_s << f_s, m_s;
  EXPECT_TRUE(near6(s.w_sensor, w_s, b.tolerance()));
}

TEST(AtiDriver, TareAveragesThenSubtracts) {
  Bench b;
  b.start_fake();
  b.start_driver();
  const Vector6d load = wrench(3, -4, 50, 0.3, -0.2, 0.1);
  b.fake->set_wrench(load);
  b.plate->tare(4);
  WrenchSample s;
  for (int i = 0; i < 4; ++i) {
    ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
    EXPECT_TRUE(s.taring);
  }
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_FALSE(s.taring);
  EXPECT_TRUE(near6(s.w_fp, Vector6d::Zero(), b.tolerance()));
  const Vector6d more = wrench(0, 0, 100, 0, 0, 0);
  b.fake->set_wrench(load + more);
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_TRUE(near6(s.w_fp, more, 2 * b.tolerance()));
  b.plate->clear_tare();
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_TRUE(near6(s.w_fp, load + more, b.tolerance()));
}

TEST(AtiDriver, ReportsSaturation) {
  Bench b;
  b.drv_cfg.saturation_limits = {660, 660, 1980, 60, 60, 60};
  b.start_fake();
  b.start_driver();
  b.fake->set_wrench(wrench(700, 0, 0, 0, 0, 0));
  WrenchSample s;
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_EQ(s.saturated_axes, 0x01);
  EXPECT_FALSE(s.gauge_saturated);
  b.fake->set_wrench(wrench(0, 0, 5000, 0, 0, 0));  // beyond the gauges' range
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_TRUE(s.gauge_saturated);
  EXPECT_NE(s.saturated_axes & 0x04, 0);
}

TEST(AtiDriver, PlaysAScenario) {
  std::vector<ScenarioPoint> pts(2);
  pts[0].t_s = 0.0;
  pts[0].w_fp = wrench(0, 0, 100, 0, 0, 0);
  pts[1].t_s = 1000.0;
  pts[1].w_fp = wrench(0, 0, 100, 0, 0, 0);
  Bench b;
  b.start_fake(std::make_shared<Scenario>(pts));
  b.start_driver();
  WrenchSample s;
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  EXPECT_TRUE(near6(s.w_fp, pts[0].w_fp, b.tolerance()));
}

TEST(AtiDriver, NoDeviceFailsStartNamingTheStep) {
  Bench b;
  b.drv_cfg.startup_timeout_s = 0.01;
  b.drv_cfg.startup_tries = 2;
  try {
    b.start_driver();
    FAIL() << "no error";
  } catch (const DeviceError& e) {
    EXPECT_STREQ(e.what(), "ATI NETCANOEM (base 0x0A) on ati-test: serial number (opcode 0x5): no answer after 2 tries of 10 ms");
  }
  WrenchSample s;
  EXPECT_EQ(b.plate->poll(s), PollStatus::disconnected);
}

TEST(AtiDriver, BadConfigurationIsNamed) {
  auto bus = CanLoopbackBus::create();
  ForcePlateConfig c;
  c.base_id = 0x80;
  EXPECT_TRUE(hil::test::config_error([&] { AtiNetCanOemDriver d(c, bus->open()); }, "base_id", "0..0x7F"));
  c.base_id = 1;
  c.saturation_limits = {1, 2, 3};
  EXPECT_TRUE(hil::test::config_error([&] { AtiNetCanOemDriver d(c, bus->open()); }, "saturation_limits", "needs 6 values"));
  c.saturation_limits.clear();
  c.T_fp_sensor.linear() *= 2.0;
  EXPECT_TRUE(hil::test::config_error([&] { AtiNetCanOemDriver d(c, bus->open()); }, "sensor_pose", "not a rigid transform"));
}

// Fault injection: each fault is seen by the driver and polling recovers when it ends.
class AtiFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    b.drv_cfg.response_timeout_s = 0.05;
    b.start_fake();
    b.start_driver();
    b.fake->set_wrench(wrench(1, 2, 30, 0.1, 0.2, 0.3));
  }
  void expect_recovers() {
    b.fake->set_faults(CanFaults{});
    WrenchSample s;
    // The first poll after the fault may still see stale answers or a pending error frame.
    ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::ok; }));
    EXPECT_TRUE(near6(s.w_fp, wrench(1, 2, 30, 0.1, 0.2, 0.3), b.tolerance()));
    EXPECT_EQ(b.plate->counters().consecutive_failures, 0U);
  }
  Bench b;
};

TEST_F(AtiFaults, SilentDeviceTimesOut) {
  CanFaults f;
  f.silent_now = true;
  b.fake->set_faults(f);
  WrenchSample s;
  EXPECT_EQ(b.plate->poll(s), PollStatus::timeout);
  EXPECT_EQ(b.plate->last_problem(), "no gauge answer");
  EXPECT_EQ(b.plate->counters().timeouts, 1U);
  expect_recovers();
}

TEST_F(AtiFaults, DroppedFramesTimeOut) {
  CanFaults f;
  f.drop_fraction = 1.0;
  b.fake->set_faults(f);
  WrenchSample s;
  EXPECT_EQ(b.plate->poll(s), PollStatus::timeout);
  EXPECT_GT(b.fake->stats().frames_dropped, 0U);
  expect_recovers();
}

TEST_F(AtiFaults, CorruptFramesAreBadFrames) {
  CanFaults f;
  f.corrupt_fraction = 1.0;
  b.fake->set_faults(f);
  WrenchSample s;
  EXPECT_EQ(b.plate->poll(s), PollStatus::bad_frame);
  EXPECT_EQ(b.plate->last_problem(), "gauge frame 1 (id 0x0A0) has length 5, expected 8");
  EXPECT_EQ(b.plate->counters().bad_frames, 1U);
  expect_recovers();
}

TEST_F(AtiFaults, BusOffIsReportedThenRecovered) {
  CanFaults f;
  f.bus_off = {TimeWindow{0.0, 1e6}};
  b.fake->set_faults(f);
  WrenchSample s;
  ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::bus_error; }));
  EXPECT_TRUE(b.plate->counters().bus_off);
  EXPECT_EQ(b.plate->counters().bus_off_events, 1U);
  EXPECT_TRUE(b.plate->last_bus_error().bus_off);
  expect_recovers();
  EXPECT_FALSE(b.plate->counters().bus_off);
}

TEST_F(AtiFaults, ErrorFramesAndStatusBit) {
  CanFaults f;
  f.error_frame_rate_hz = 500;
  b.fake->set_faults(f);
  WrenchSample s;
  ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::ok && s.device_fault; }));
  EXPECT_EQ(s.status_word, ati::kStatusCanBusError | ati::kStatusAnyError);
  ASSERT_TRUE(hil::test::eventually([&] {
    b.plate->poll(s);
    return b.plate->counters().error_frames > 0;
  }));
  EXPECT_TRUE(b.plate->last_bus_error().error_passive);
  EXPECT_EQ(describe(b.plate->last_bus_error()), "error-passive, tx errors 0, rx errors 130");
  expect_recovers();
}

TEST_F(AtiFaults, DelayedAnswersAreLateThenDrained) {
  CanFaults f;
  f.extra_delay_s = 0.2;  // longer than the poll timeout
  b.fake->set_faults(f);
  WrenchSample s;
  EXPECT_EQ(b.plate->poll(s), PollStatus::timeout);
  // Later polls find the answers that came too late and discard them.
  ASSERT_TRUE(hil::test::eventually([&] {
    b.plate->poll(s);
    return b.plate->counters().late_frames > 0;
  }));
  expect_recovers();
}

TEST(GaugeModel, IntegerQuantisationThroughTheInverseMatrix) {
  FakeNetCanOemConfig c;
  const AtiGaugeModel model(c);
  bool sat = true;
  const ati::Gauges g = model.gauges(Vector6d::Zero(), sat);
  EXPECT_FALSE(sat);
  EXPECT_EQ(g, ati::Gauges{});
  const Vector6d w = wrench(12.3, -4.5, 678.9, 1.2, -3.4, 5.6);
  const ati::Gauges g2 = model.gauges(w, sat);
  Eigen::Matrix<double, 6, 1> gv;
  for (int i = 0; i < 6; ++i) gv[i] = g2[static_cast<std::size_t>(i)];
  Vector6d k;
  k << 1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5;
  const Vector6d back = k.asDiagonal() * (c.calibration * gv);
  const Vector6d bound = 0.5 * k.asDiagonal() * c.calibration.cwiseAbs().rowwise().sum();
  EXPECT_TRUE(near6(back, w, bound));
}

TEST(ScenarioTest, InterpolatesAndLoops) {
  std::vector<ScenarioPoint> pts(3);
  for (int i = 0; i < 3; ++i) {
    pts[static_cast<std::size_t>(i)].t_s = i;
    pts[static_cast<std::size_t>(i)].w_fp = Vector6d::Constant(10.0 * i);
    pts[static_cast<std::size_t>(i)].joints_rad = {0.1 * i};
  }
  pts[2].q_base_tcp = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  pts[1].q_base_tcp = Eigen::Quaterniond::Identity();
  Scenario s(pts);
  ScenarioPoint p;
  s.at(0.5, p);
  EXPECT_NEAR(p.w_fp[0], 5.0, 1e-12);
  EXPECT_NEAR(p.joints_rad[0], 0.05, 1e-12);
  s.at(1.5, p);
  EXPECT_NEAR(Eigen::AngleAxisd(p.q_base_tcp).angle(), 0.5, 1e-9);
  s.at(99, p);
  EXPECT_NEAR(p.w_fp[0], 20.0, 1e-12);
  Scenario looped(pts, true);
  looped.at(2.5, p);
  EXPECT_NEAR(p.w_fp[0], 5.0, 1e-9);
  std::vector<ScenarioPoint> bad(2);
  EXPECT_TRUE(hil::test::config_error([&] { Scenario x(bad); }, "scenario[1].t_s", "strictly increasing"));
  const DeviceClock clock{0.5, 100.0, 2.0};
  EXPECT_NEAR(clock.scenario_time(10.0), (10.0 * 1.0001 + 0.5) * 2.0, 1e-12);
}

// The fake's count of intact answers is what the fault soak reconciles with the recording: only
// answers with every frame sent whole count, late ones once they are out.
TEST_F(AtiFaults, OnlyIntactAnswersCountAsDelivered) {
  WrenchSample s;
  const auto delivered0 = b.fake->stats().gauge_answers_delivered;
  ASSERT_EQ(b.plate->poll(s), PollStatus::ok);
  // The fake counts after its send returns, possibly after the driver has its answer.
  auto delivered_becomes = [&](std::uint64_t n) {
    return hil::test::eventually([&] { return b.fake->stats().gauge_answers_delivered == n; });
  };
  EXPECT_TRUE(delivered_becomes(delivered0 + 1));
  CanFaults dropped;
  dropped.drop_fraction = 1.0;
  b.fake->set_faults(dropped);
  EXPECT_EQ(b.plate->poll(s), PollStatus::timeout);
  CanFaults corrupt;
  corrupt.corrupt_fraction = 1.0;
  b.fake->set_faults(corrupt);
  EXPECT_EQ(b.plate->poll(s), PollStatus::bad_frame);
  EXPECT_EQ(b.fake->stats().gauge_answers_delivered, delivered0 + 1) << "a dropped or corrupted answer counted";
  CanFaults late;
  late.extra_delay_s = 0.002;  // inside the 50 ms timeout
  b.fake->set_faults(late);
  ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::ok; }));
  b.fake->stop();  // its counts are final
  // Every intact answer became a reading, or left a frame reported as late.
  const auto delivered = b.fake->stats().gauge_answers_delivered - delivered0;
  EXPECT_GE(delivered, 2U);
  EXPECT_LE(b.plate->counters().samples, delivered);
  EXPECT_LE(delivered, b.plate->counters().samples + b.plate->counters().late_frames);
}

// A second gauge frame left over from an earlier answer (its poll gave up between the two frames)
// must not complete this poll's reading: that would tear it across two answers.
TEST(AtiDriver, StaleSecondFrameNeverTearsAReading) {
  Bench b;
  b.start_fake();
  b.start_driver();
  b.fake->stop();  // from here the test answers by hand
  auto plate_side = b.bus->open();
  const ati::Gauges stale{1, 2, 3, 4, 555, 666}, ours{10, 20, 30, 40, 50, 60};
  std::thread device([&] {
    CanFrame req;
    ASSERT_EQ(plate_side->receive(req, std::chrono::seconds(2)), IoStatus::ok);
    const auto old_answer = ati::encode_gauges(b.drv_cfg.base_id, 0, stale);
    const auto new_answer = ati::encode_gauges(b.drv_cfg.base_id, 0, ours);
    ASSERT_EQ(plate_side->send(old_answer[1], std::chrono::milliseconds(100)), IoStatus::ok);
    ASSERT_EQ(plate_side->send(new_answer[0], std::chrono::milliseconds(100)), IoStatus::ok);
    ASSERT_EQ(plate_side->send(new_answer[1], std::chrono::milliseconds(100)), IoStatus::ok);
  });
  WrenchSample s;
  const auto late0 = b.plate->counters().late_frames;
  const auto st = b.plate->poll(s);
  device.join();
  ASSERT_EQ(st, PollStatus::ok);
  EXPECT_EQ(s.gauges, ours) << "gauges 4-5 came from the stale frame";
  EXPECT_EQ(b.plate->counters().late_frames, late0 + 1);
}

// Every class of status bit the board documents marks the reading as a device fault, counted and
// named; none is only logged. The board sets bit 15 (any error) with each.
TEST_F(AtiFaults, EveryStatusBitClassIsADeviceFaultNamedAndCounted) {
  const struct {
    std::uint16_t bit;
    const char* words;
  } classes[] = {
      {ati::kStatusWatchdogReset, "watchdog reset"},
      {ati::kStatusDacAdcTooHigh, "DAC/ADC check too high"},
      {ati::kStatusAnalogGround, "analog ground out of range"},
      {ati::kStatusSupplyTooLow, "supply too low"},
      {ati::kStatusSupplyTooHigh, "supply too high"},
      {ati::kStatusBadCalibration, "bad active calibration"},
      {ati::kStatusEepromFailure, "EEPROM failure"},
      {ati::kStatusConfigInvalid, "configuration invalid"},
      {ati::kStatusTemperatureTooHigh, "temperature too high"},
      {ati::kStatusTemperatureTooLow, "temperature too low"},
      {ati::kStatusCanBusError, "CAN bus error"},
  };
  std::uint64_t faults = 0;
  for (const auto& c : classes) {
    SCOPED_TRACE(c.words);
    CanFaults f;
    f.status_now = c.bit;
    b.fake->set_faults(f);
    WrenchSample s;
    ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::ok && s.status_word != 0; }));
    EXPECT_EQ(s.status_word, static_cast<std::uint32_t>(c.bit | ati::kStatusAnyError));
    EXPECT_TRUE(s.device_fault);
    EXPECT_GT(b.plate->counters().device_faults, faults);
    faults = b.plate->counters().device_faults;
    const std::string said = b.plate->describe_status(s);
    EXPECT_NE(said.find(c.words), std::string::npos) << said;
    EXPECT_NE(said.find("any error"), std::string::npos) << said;
    b.fake->set_faults(CanFaults{});
    ASSERT_TRUE(hil::test::eventually([&] { return b.plate->poll(s) == PollStatus::ok && s.status_word == 0; }));
    EXPECT_FALSE(s.device_fault);
  }
}

TEST(AtiProtocol, StatusWordsAreNamedBitByBitWithReservedBitsByNumber) {
  EXPECT_EQ(ati::describe_status(0), "0x0000 (ok)");
  EXPECT_EQ(ati::describe_status(0x8020), "0x8020 (supply too low, any error)");
  EXPECT_EQ(ati::describe_status(0x8200), "0x8200 (any error, reserved bit 9)");
  EXPECT_EQ(ati::describe_status(0x0001), "0x0001 (watchdog reset)");
}

// The base-id scan: two boards on one bus, at the factory's 0x20 and at 0x05, answer their serial
// request; nothing else does. An empty bus gives an empty list after the window.
TEST(NetCanOem, ScanFindsBoardsByBaseId) {
  auto bus = CanLoopbackBus::create();
  FakeNetCanOemConfig a;  // the factory's base id
  FakeNetCanOemConfig b;
  b.base_id = 0x05;
  b.serial = "FT-OTHER";
  FakeNetCanOemBoard board_a(a, bus->open());
  FakeNetCanOemBoard board_b(b, bus->open());
  board_a.start();
  board_b.start();
  auto ch = bus->open();
  const auto found = scan_netcanoem(*ch, 0.2);
  ASSERT_EQ(found.size(), 2U);
  EXPECT_EQ(found[0].base_id, 0x05U);
  EXPECT_EQ(found[0].serial, "FT-OTHER");
  EXPECT_EQ(found[1].base_id, 0x20U);
  EXPECT_EQ(found[1].serial, "FT-FAKE1");
  EXPECT_EQ(a.base_id, ati::kFactoryBase);
  board_a.stop();
  board_b.stop();
  EXPECT_TRUE(scan_netcanoem(*ch, 0.05).empty());
}
