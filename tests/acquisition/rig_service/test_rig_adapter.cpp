// rig.yaml device sections -> driver configurations, and the fake rig playing the shipped example
// run through the real drivers (loopback CAN, libmodbus on 127.0.0.1).
#include <gtest/gtest.h>

#include <hil/rig_service/drivers_from_rig.hpp>
#include <hil/error/error.hpp>
#include <hil/test/drivers.hpp>

using namespace hil;
using namespace hil::drivers;

namespace {
const std::string kRig = std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml";
const std::string kRun = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";
}  // namespace

TEST(RigAdapter, ExampleRigGivesDriverConfigs) {
  const auto rig = format::load_rig(kRig);
  const ForcePlateConfig fp = rig_service::force_plate_config(rig);
  EXPECT_EQ(fp.protocol, ForcePlateProtocol::ati_netcanoem);
  EXPECT_EQ(fp.interface, "vcan0");
  EXPECT_EQ(fp.base_id, 0U);
  EXPECT_EQ(fp.rate_hz, 1000.0);
  ASSERT_EQ(fp.saturation_limits.size(), 6U);
  EXPECT_EQ(fp.saturation_limits[2], 1980.0);
  const ModbusConfig mb = rig_service::robot_controller_config(rig);
  EXPECT_EQ(mb.transport, ModbusTransport::tcp);
  EXPECT_EQ(mb.port, 5020);
  EXPECT_EQ(mb.rate_hz, 125.0);
  EXPECT_EQ(mb.map.name, "ur");
  EXPECT_EQ(mb.map.entries.size(), 12U);
}

TEST(RigAdapter, DeclarativeAndCustomSections) {
  format::RigSpec rig;
  rig.source = "lab.yaml";
  format::ForcePlateDeviceSpec fp;
  fp.protocol = "declarative";
  format::CanSignalSpec s;
  s.component = "fz";
  s.frame_id = 0x181;
  s.length_bits = 0;
  fp.signals.push_back(s);
  rig.devices.force_plate = fp;
  try {
    rig_service::force_plate_config(rig);
    FAIL() << "no error";
  } catch (const error::FormatError& e) {
    EXPECT_EQ(e.where().file, "lab.yaml");
    EXPECT_EQ(e.where().field, "devices.force_plate.signals[0].length_bits");
    EXPECT_EQ(e.message(), "must be 1..64");
  }
  rig.devices.force_plate->signals[0].length_bits = 16;
  rig.devices.force_plate->signals[0].component = "torque";
  try {
    rig_service::force_plate_config(rig);
    FAIL() << "no error";
  } catch (const error::FormatError& e) {
    EXPECT_EQ(e.where().field, "devices.force_plate.signals[0].component");
  }
  rig.devices.force_plate->signals[0].component = "fz";
  EXPECT_EQ(rig_service::force_plate_config(rig).signals.size(), 1U);

  format::RobotControllerSpec rc;
  rc.register_map = "custom";
  rc.registers = {{"j1", 10, "input", "float32", "little", 1.0, 0.0}, {"j2", 11, "input", "int16", "big", 1.0, 0.0}};
  rig.devices.robot = rc;
  try {
    rig_service::robot_controller_config(rig);
    FAIL() << "no error";
  } catch (const error::FormatError& e) {
    EXPECT_EQ(e.where().field, "devices.robot.registers[1].address");
    EXPECT_EQ(e.message(), "register 11 overlaps registers[0] ('j1')");
  }
  rig.devices.robot->registers[1].address = 12;
  const ModbusConfig mb = rig_service::robot_controller_config(rig);
  EXPECT_EQ(mb.map.entries[0].table, RegisterTable::input);
  EXPECT_EQ(mb.map.entries[0].word_order, WordOrder::little);
  EXPECT_FALSE(mb.kinematics.has_value());  // no robot section, no DH table
  // Joints only, with the robot's DH table: the pose comes by forward kinematics.
  format::RobotSpec robot;
  robot.joints.resize(2);
  robot.joints[0].a_m = 0.4;
  robot.joints[1].d_m = 0.1;
  robot.joints[1].type = format::JointType::prismatic;
  rig.robot = robot;
  const ModbusConfig fk = rig_service::robot_controller_config(rig);
  ASSERT_TRUE(fk.kinematics.has_value());
  ASSERT_EQ(fk.kinematics->joints, 2U);
  // Link 1 of 0.4 m along x after joint 1 (standard DH), then the slider's d = 0.1 m + q2 along z.
  const double q[2] = {1.5707963267948966, 0.05};
  const Eigen::Isometry3d T = fk.kinematics->T_base_tool(q);
  EXPECT_LT((T.translation() - Eigen::Vector3d(0.0, 0.4, 0.15)).norm(), 1e-12) << T.translation().transpose();
  // The example rig's UR map reads the tool pose: no kinematics needed.
  EXPECT_FALSE(rig_service::robot_controller_config(format::load_rig(kRig)).kinematics.has_value());
}

// The example run played by the fakes and read back by the drivers, at three instants of the run
// (the device clock is frozen at that instant: speed ~0, offset = instant).
TEST(FakeRigPlaysARun, DriversReadTheRunBack) {
  const auto run = format::load_run(kRun);
  ASSERT_TRUE(run.rig.has_value());
  const Eigen::Isometry3d T_world_base = rig_service::world_to_base(*run.rig);
  const auto scenario = std::make_shared<Scenario>(rig_service::scenario_from_run(run, T_world_base, false));
  for (const std::size_t k : {std::size_t{0}, run.samples.size() / 2, run.samples.size() - 1}) {
    const auto& want = run.samples.samples[k];
    const double speed = 1e-12;
    const DeviceClock frozen{want.t_s / speed, 0.0, speed};

    auto bus = CanLoopbackBus::create();
    ForcePlateConfig pc = rig_service::force_plate_config(*run.rig);
    FakeNetCanOemConfig fc;
    fc.clock = frozen;
    fc.base_id = pc.base_id;  // the run's board (the fake's default is the factory's 0x20)
    FakeNetCanOemBoard plate(fc, bus->open(), scenario);
    plate.start();
    pc.response_timeout_s = 0.5;
    pc.startup_timeout_s = 0.5;
    auto drv = make_force_plate(pc, bus->open());
    drv->start();
    WrenchSample w;
    ASSERT_EQ(drv->poll(w), PollStatus::ok) << drv->last_problem();
    Vector6d expect;
    expect << want.f_fp_n, want.m_fp_nm;
    Vector6d tol;
    tol << 0.1, 0.1, 0.1, 0.003, 0.003, 0.003;  // the fake plate's quantisation
    EXPECT_TRUE(hil::test::near6(w.w_fp, expect, tol)) << "sample " << k;

    FakeRobotConfig rc;
    rc.map = rig_service::register_map(*run.rig->devices.robot, run.rig->source);
    rc.clock = frozen;
    FakeRobotController robot(rc, scenario);
    robot.start();
    ModbusConfig mc = rig_service::robot_controller_config(*run.rig);
    mc.port = robot.port();
    RobotControllerDriver rdrv(mc);
    rdrv.connect();
    RobotSample r;
    ASSERT_EQ(rdrv.poll(r), PollStatus::ok) << rdrv.last_problem();
    ASSERT_TRUE(r.has_pose);
    const Eigen::Vector3d p_world = T_world_base * r.p_base_tcp_m;
    EXPECT_LT((p_world - want.p_world_ee_m).norm(), 1e-4) << "sample " << k;
    const Eigen::Quaterniond q_world(T_world_base.linear() * r.q_base_tcp.toRotationMatrix());
    EXPECT_LT(q_world.angularDistance(want.q_world_ee), 2e-3) << "sample " << k;
  }
}
