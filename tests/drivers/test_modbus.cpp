// The robot-controller driver against the fake controller (real libmodbus both sides, 127.0.0.1,
// ephemeral ports), fault injection and recovery.
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <numbers>
#include <thread>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/robot_controller.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;
using hil::test::eventually;

namespace {

const std::vector<double> kJoints{0.1, -1.2, 2.3, -0.4, 1.5707963, -3.0};
const Eigen::Vector3d kP(-0.45, 0.1234, 0.3);
const Eigen::Quaterniond kQ(Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, -1, 0.5).normalized()));

struct Rig {
  std::unique_ptr<FakeRobotController> fake;
  std::unique_ptr<RobotControllerDriver> drv;
  explicit Rig(const RegisterMap& map, double timeout_s = 0.5) {
    FakeRobotConfig fc;
    fc.map = map;
    fake = std::make_unique<FakeRobotController>(fc);
    fake->set_state(kJoints, kP, kQ);
    fake->start();
    ModbusConfig mc;
    mc.port = fake->port();
    mc.map = map;
    mc.timeout_s = timeout_s;
    mc.reconnect_min_s = 0.001;
    mc.reconnect_max_s = 0.01;
    drv = std::make_unique<RobotControllerDriver>(mc);
    drv->connect();
  }
};

void expect_state(const RobotSample& s, double tol_q, double tol_p, double tol_r) {
  ASSERT_EQ(s.joint_count, 6U);
  for (unsigned j = 0; j < 6; ++j) EXPECT_NEAR(s.joints[j], kJoints[j], tol_q) << "j" << j + 1;
  ASSERT_TRUE(s.has_pose);
  EXPECT_NEAR((s.p_base_tcp_m - kP).norm(), 0.0, tol_p);
  EXPECT_NEAR(s.q_base_tcp.angularDistance(kQ), 0.0, tol_r);
}

/// The fake UR controller in lock-step (one scenario second per request) and a driver on it.
struct LockStep {
  FakeRobotController fake;
  RobotControllerDriver drv;
  explicit LockStep(std::vector<ScenarioPoint> pts) : fake(config(), std::make_shared<Scenario>(std::move(pts))), drv(modbus(fake)) {
    drv.connect();
  }
  static FakeRobotConfig config() {
    FakeRobotConfig fc;
    fc.scenario_step_per_request_s = 1.0;
    return fc;
  }
  static ModbusConfig modbus(FakeRobotController& f) {
    f.start();
    ModbusConfig mc;
    mc.port = f.port();
    mc.timeout_s = 1.0;
    return mc;
  }
};

}  // namespace

TEST(RobotDriver, ReadsTheUrMapFromTheFake) {
  Rig rig(ur_register_map());
  RobotSample s;
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok) << rig.drv->last_problem();
  expect_state(s, 0.5e-3 + 1e-9, std::sqrt(3.0) * 0.5e-4, 2e-3);
  EXPECT_GT(s.t_ns, 0);
  EXPECT_GE(s.rtt_ns, 0);
  EXPECT_EQ(s.sequence, 1U);
  EXPECT_EQ(rig.drv->read_plan().size(), 3U);
  // Angles, turn counters, pose, and the angles again to bracket the counters (no torn joint).
  EXPECT_EQ(rig.fake->stats().requests, 4U);
  EXPECT_EQ(rig.drv->counters().torn_reads, 0U);
  EXPECT_EQ(rig.fake->stats().writes_refused, 0U);
}

TEST(RobotDriver, ReadsTheFloat32Map) {
  Rig rig(float32_register_map());
  RobotSample s;
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok) << rig.drv->last_problem();
  expect_state(s, 1e-6, 1e-6, 1e-6);
  EXPECT_EQ(rig.fake->stats().requests, 1U);
}

TEST(RobotDriver, JointsOnlyAndInputRegisters) {
  RegisterMap m;
  for (unsigned j = 0; j < 6; ++j)
    m.entries.push_back({"j" + std::to_string(j + 1), 10 + 2 * j, RegisterTable::input, RegisterType::int32, WordOrder::little, 1e-6, 0.0,
                         -1});
  Rig rig(m);
  RobotSample s;
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok) << rig.drv->last_problem();
  EXPECT_FALSE(s.has_pose);
  ASSERT_EQ(s.joint_count, 6U);
  for (unsigned j = 0; j < 6; ++j) EXPECT_NEAR(s.joints[j], kJoints[j], 0.5e-6 + 1e-12);
}

TEST(RobotDriver, JointsOnlyMapGetsThePoseByKinematics) {
  RegisterMap m;
  m.entries = {{"j1", 0, RegisterTable::holding, RegisterType::float32, WordOrder::big, 1.0, 0.0, -1},
               {"j2", 2, RegisterTable::holding, RegisterType::float32, WordOrder::big, 1.0, 0.0, -1}};
  FakeRobotConfig fc;
  fc.map = m;
  FakeRobotController fake(fc);
  const std::vector<double> q{std::numbers::pi / 2, -std::numbers::pi / 2};
  fake.set_state(q, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  fake.start();
  ModbusConfig mc;
  mc.port = fake.port();
  mc.map = m;
  // A planar 2R arm with unit links, as the rig adapter would give it (tests/drivers/test_rig_adapter
  // checks the adapter's chain; calibration's tests the DH kinematics).
  mc.kinematics = ForwardKinematics{2, [](const double* qq) {
                                      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
                                      T.translation() = Eigen::Vector3d(std::cos(qq[0]) + std::cos(qq[0] + qq[1]),
                                                                        std::sin(qq[0]) + std::sin(qq[0] + qq[1]), 0.0);
                                      T.linear() = Eigen::AngleAxisd(qq[0] + qq[1], Eigen::Vector3d::UnitZ()).toRotationMatrix();
                                      return T;
                                    }};
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
  ASSERT_TRUE(s.has_pose);
  EXPECT_TRUE(s.pose_from_kinematics);
  EXPECT_LT((s.p_base_tcp_m - Eigen::Vector3d(1, 1, 0)).norm(), 1e-6);
  mc.kinematics->joints = 3;
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(mc); }, "kinematics", "has 3 joints but the register map reads 2"));
  mc.kinematics->T_base_tool = nullptr;
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(mc); }, "kinematics", "no forward kinematics given"));
}

TEST(FakeRobot, RefusesWrites) {
  FakeRobotController fake(FakeRobotConfig{});
  fake.start();
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", fake.port());
  ASSERT_NE(ctx, nullptr);
  ASSERT_EQ(modbus_connect(ctx), 0);
  EXPECT_EQ(modbus_write_register(ctx, 270, 1), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  std::uint16_t r[6];
  EXPECT_EQ(modbus_read_registers(ctx, 270, 6, r), 6);
  EXPECT_EQ(modbus_read_registers(ctx, 1000, 1, r), -1);  // outside the map
  EXPECT_EQ(errno, EMBXILADD);
  modbus_close(ctx);
  modbus_free(ctx);
  EXPECT_EQ(fake.stats().writes_refused, 1U);
}

TEST(FakeRobot, OnlyLoopback) {
  FakeRobotConfig c;
  c.host = "0.0.0.0";
  EXPECT_TRUE(hil::test::config_error([&] { FakeRobotController f(c); }, "host", "127.0.0.0/8 only"));
}

TEST(FakeRobot, PlaysAScenarioWithClockOffset) {
  std::vector<ScenarioPoint> pts(2);
  pts[0].t_s = 0;
  pts[0].joints_rad = std::vector<double>(6, 0.0);
  pts[1].t_s = 1e6;
  pts[1].joints_rad = std::vector<double>(6, 1e6);  // 1 rad per second of scenario time
  FakeRobotConfig c;
  c.map = float32_register_map();
  c.clock.offset_s = 100.0;  // the device is 100 s ahead
  FakeRobotController fake(c, std::make_shared<Scenario>(pts));
  fake.start();
  ModbusConfig mc;
  mc.port = fake.port();
  mc.map = c.map;
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok);
  EXPECT_GE(s.joints[0], 100.0);
  EXPECT_LT(s.joints[0], 200.0);  // a bound against hangs, not a timing check
}

// UR angles (270-275) and turn counters (320-325) come in separate requests. With the fake in
// lock-step (one scenario second per request) joint 1 crosses 0 rad exactly between the first
// poll's angle request and its counter request, in both directions: read naively, the joint
// decodes a full turn off (-6.283 rad for +0.0004, or 6.282 for -0.0006).
TEST(RobotDriver, AJointCrossingZeroBetweenAngleAndCounterReadsHasNoSpike) {
  for (const double direction : {-1.0, 1.0}) {
    SCOPED_TRACE(direction < 0 ? "falling through 0 rad" : "rising through 0 rad");
    std::vector<ScenarioPoint> pts(2);
    pts[0].t_s = 0;
    pts[0].joints_rad = kJoints;
    pts[0].joints_rad[0] = -direction * 0.0004;  // 0.4 mrad on one side; 0.6 mrad on the other a request later
    pts[0].p_base_tcp_m = kP;
    pts[0].q_base_tcp = kQ;
    pts[1] = pts[0];
    pts[1].t_s = 1000;
    pts[1].joints_rad[0] += direction * 1.0;  // 1 mrad per request
    LockStep rig(pts);
    auto& drv = rig.drv;
    RobotSample s;
    double previous = pts[0].joints_rad[0];
    for (int k = 0; k < 12; ++k) {
      ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
      // At most a few requests (mrad) from the last poll, on the side the motion goes.
      EXPECT_LT(std::abs(s.joints[0] - previous), 0.02) << "poll " << k << ": j1 = " << s.joints[0];
      EXPECT_LT(std::abs(s.joints[0]), 0.1) << "poll " << k;
      for (unsigned j = 1; j < 6; ++j) EXPECT_NEAR(s.joints[j], kJoints[j], 1e-3);
      EXPECT_NEAR((s.p_base_tcp_m - kP).norm(), 0.0, 2e-4);
      previous = s.joints[0];
    }
    EXPECT_GE(drv.counters().torn_reads, 1U) << "the crossing was placed between two requests";
  }
}

// A joint resting on 0 rad whose reading flickers across it (encoder noise of a count) at every
// angle read: no counter read is bracketed by two angle reads on one side, so the poll fails as
// a named bad frame after its re-reads instead of returning a value that may be a turn off.
TEST(RobotDriver, AnAngleFlickeringAcrossZeroAtEveryReadIsABadFrameNotAGuess) {
  // Requests of one poll: angles, counters, pose, angles again; then (counters, angles) per re-read.
  const char sides[] = "+++--++--+";
  std::vector<ScenarioPoint> pts;
  for (int k = 0; sides[k] != 0; ++k) {
    ScenarioPoint p;
    p.t_s = k;
    p.joints_rad = kJoints;
    p.joints_rad[0] = sides[k] == '+' ? 0.001 : -0.001;
    p.p_base_tcp_m = kP;
    p.q_base_tcp = kQ;
    pts.push_back(p);
  }
  LockStep rig(pts);
  auto& drv = rig.drv;
  RobotSample s;
  EXPECT_EQ(drv.poll(s), PollStatus::bad_frame);
  EXPECT_NE(drv.last_problem().find("wrapping"), std::string::npos) << drv.last_problem();
  EXPECT_EQ(drv.counters().samples, 0U);
  EXPECT_EQ(drv.counters().torn_reads, 4U);
  EXPECT_EQ(rig.fake.stats().requests, 10U);
}

TEST(RobotDriver, UnreachableControllerThrowsThenBacksOff) {
  FakeRobotConfig fc;
  auto fake = std::make_unique<FakeRobotController>(fc);
  const int port = fake->port();
  fake.reset();  // nothing listens on this port now
  ModbusConfig mc;
  mc.port = port;
  mc.reconnect_min_s = 10.0;
  mc.reconnect_max_s = 10.0;
  RobotControllerDriver drv(mc);
  try {
    drv.connect();
    FAIL() << "no error";
  } catch (const DeviceError& e) {
    EXPECT_EQ(std::string(e.what()), "Modbus TCP 127.0.0.1:" + std::to_string(port) + " unit 1: connect failed: Connection refused");
  }
  RobotSample s;
  EXPECT_EQ(drv.poll(s), PollStatus::disconnected);  // tries once...
  EXPECT_EQ(drv.poll(s), PollStatus::disconnected);  // ...then waits for the back-off
  EXPECT_EQ(drv.counters().polls, 2U);
  EXPECT_FALSE(drv.counters().connected);
}

TEST(RobotDriver, BadConfigurationIsNamed) {
  ModbusConfig c;
  c.port = 0;
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(c); }, "port", "1..65535"));
  c = ModbusConfig{};
  c.transport = ModbusTransport::rtu;
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(c); }, "serial_device", "needs a serial device"));
  c.serial_device = "/dev/ttyS0";
  c.parity = 'X';
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(c); }, "parity", "N, E or O"));
  c = ModbusConfig{};
  c.map.entries.clear();
  EXPECT_TRUE(hil::test::config_error([&] { RobotControllerDriver d(c); }, "registers", "is empty"));
}

// Fault injection on the fake controller: each is reported and the driver recovers.
TEST(RobotFaults, ExceptionResponses) {
  Rig rig(ur_register_map());
  ModbusFaults f;
  f.exception_fraction = 1.0;
  rig.fake->set_faults(f);
  RobotSample s;
  EXPECT_EQ(rig.drv->poll(s), PollStatus::exception);
  EXPECT_EQ(rig.drv->last_problem(), "exception response: Slave device or server is busy");
  EXPECT_EQ(rig.drv->counters().exceptions, 1U);
  EXPECT_TRUE(rig.drv->counters().connected);  // the link is fine
  rig.fake->set_faults({});
  ASSERT_EQ(rig.drv->poll(s), PollStatus::ok);
  expect_state(s, 0.5e-3 + 1e-9, 1e-4, 2e-3);
}

TEST(RobotFaults, SilenceTimesOutThenReconnects) {
  Rig rig(ur_register_map(), 0.05);
  ModbusFaults f;
  f.silent_now = true;
  rig.fake->set_faults(f);
  RobotSample s;
  EXPECT_EQ(rig.drv->poll(s), PollStatus::timeout);
  EXPECT_EQ(rig.drv->last_problem(), "no answer: Connection timed out");
  EXPECT_EQ(rig.drv->counters().retries, 1U);  // flushed and retried once
  EXPECT_FALSE(rig.drv->counters().connected);
  rig.fake->set_faults({});
  ASSERT_TRUE(eventually([&] { return rig.drv->poll(s) == PollStatus::ok; }));
  EXPECT_GE(rig.drv->counters().reconnects, 1U);
  expect_state(s, 0.5e-3 + 1e-9, 1e-4, 2e-3);
}

TEST(RobotFaults, SlowResponsesTimeOutAndLateAnswersAreFlushed) {
  Rig rig(float32_register_map(), 0.05);
  ModbusFaults f;
  f.slow_fraction = 1.0;
  f.slow_delay_s = 0.15;
  rig.fake->set_faults(f);
  RobotSample s;
  EXPECT_EQ(rig.drv->poll(s), PollStatus::timeout);
  EXPECT_GE(rig.fake->stats().slow, 1U);
  rig.fake->set_faults({});
  ASSERT_TRUE(eventually([&] { return rig.drv->poll(s) == PollStatus::ok; }));
  expect_state(s, 1e-6, 1e-6, 1e-6);
}

TEST(RobotFaults, ServerRestartIsSurvived) {
  FakeRobotConfig fc;
  fc.map = float32_register_map();
  auto fake = std::make_unique<FakeRobotController>(fc);
  fake->set_state(kJoints, kP, kQ);
  fake->start();
  ModbusConfig mc;
  mc.port = fake->port();
  mc.map = fc.map;
  mc.timeout_s = 0.1;
  mc.reconnect_min_s = 0.001;
  mc.reconnect_max_s = 0.01;
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok);
  fake.reset();
  const PollStatus st = drv.poll(s);
  EXPECT_TRUE(st == PollStatus::disconnected || st == PollStatus::timeout || st == PollStatus::bad_frame) << to_string(st);
  fc.port = mc.port;
  fake = std::make_unique<FakeRobotController>(fc);
  fake->set_state(kJoints, kP, kQ);
  fake->start();
  ASSERT_TRUE(eventually([&] { return drv.poll(s) == PollStatus::ok; }));
  expect_state(s, 1e-6, 1e-6, 1e-6);
  EXPECT_GE(drv.counters().reconnects, 1U);
}

// Modbus RTU through the same register-map code: a libmodbus RTU server on the master side of a
// pseudo-terminal, the driver on its slave device as on a serial line.
TEST(RobotDriverRtu, ReadsOverASerialLine) {
  int master = -1, slave = -1;
  char name[128];
  ASSERT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
  termios tio{};
  tcgetattr(slave, &tio);
  cfmakeraw(&tio);
  tcsetattr(slave, TCSANOW, &tio);

  const RegisterMap map = ur_register_map();
  modbus_mapping_t* mapping = modbus_mapping_new(0, 0, 410, 0);
  ASSERT_NE(mapping, nullptr);
  encode_state(map, kJoints, kP, kQ, std::span<std::uint16_t>(mapping->tab_registers, 410));
  modbus_t* server = modbus_new_rtu("/dev/null", 115200, 'N', 8, 1);
  ASSERT_NE(server, nullptr);
  modbus_set_slave(server, 7);
  modbus_set_socket(server, master);
  modbus_set_indication_timeout(server, 0, 50000);
  std::atomic<bool> stop{false};
  std::atomic<int> replies{0};
  std::thread t([&] {
    std::uint8_t q[MODBUS_RTU_MAX_ADU_LENGTH];
    while (!stop) {
      const int rc = modbus_receive(server, q);
      if (rc > 0 && modbus_reply(server, q, rc, mapping) > 0) ++replies;
    }
  });

  ModbusConfig mc;
  mc.transport = ModbusTransport::rtu;
  mc.serial_device = name;
  mc.unit_id = 7;
  mc.timeout_s = 1.0;
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  const PollStatus st = drv.poll(s);
  stop = true;
  t.join();
  ASSERT_EQ(st, PollStatus::ok) << drv.last_problem();
  expect_state(s, 0.5e-3 + 1e-9, 1e-4, 2e-3);
  EXPECT_EQ(replies.load(), 4);  // the angle block twice, bracketing the turn counters
  drv.disconnect();
  modbus_free(server);
  modbus_mapping_free(mapping);
  ::close(master);
  ::close(slave);
}
