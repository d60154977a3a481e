// Modbus against an independent implementation (Debian's python3-pymodbus): the driver reads a
// pymodbus server, and a pymodbus client reads the fake robot controller.
#include <gtest/gtest.h>

#include <sstream>

#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/robot_controller.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;

namespace {

bool have_pymodbus() {
  hil::test::Child c({HIL_PYTHON3, "-c", "import pymodbus.client, pymodbus.server.async_io; print('ok')"});
  return c.ok() && c.read_line() == "ok" && c.wait() == 0;
}

std::string script(const char* name) { return std::string(HIL_SOURCE_DIR) + "/tests/drivers/" + name; }

const std::vector<double> kJoints{0.1, -1.2, 2.3, -0.4, 1.5707963, -3.0};
const Eigen::Vector3d kP(-0.45, 0.1234, 0.3);
const Eigen::Quaterniond kQ(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0, 1, 1).normalized()));

}  // namespace

TEST(Pymodbus, DriverReadsAPymodbusServer) {
  if (!have_pymodbus()) GTEST_SKIP() << "python3-pymodbus (with python3-serial-asyncio) is not installed";
  // The UR map's registers, encoded by our codec, served by pymodbus.
  const RegisterMap map = ur_register_map();
  std::vector<std::uint16_t> regs(410, 0);
  encode_state(map, kJoints, kP, kQ, regs);
  auto range = [&](unsigned a, unsigned n) {
    std::string s = std::to_string(a) + "=";
    for (unsigned i = 0; i < n; ++i) s += (i ? "," : "") + std::to_string(regs[a + i]);
    return s;
  };
  hil::test::Child server({HIL_PYTHON3, script("pymodbus_server.py"), range(270, 6), range(320, 6), range(400, 6)});
  ASSERT_TRUE(server.ok());
  const std::string port = server.read_line();
  ASSERT_FALSE(port.empty()) << "the pymodbus server did not start";
  ModbusConfig mc;
  mc.port = std::stoi(port);
  mc.timeout_s = 2.0;
  RobotControllerDriver drv(mc);
  drv.connect();
  RobotSample s;
  ASSERT_EQ(drv.poll(s), PollStatus::ok) << drv.last_problem();
  ASSERT_EQ(s.joint_count, 6U);
  for (unsigned j = 0; j < 6; ++j) EXPECT_NEAR(s.joints[j], kJoints[j], 0.5e-3 + 1e-9) << "j" << j + 1;
  ASSERT_TRUE(s.has_pose);
  EXPECT_LT((s.p_base_tcp_m - kP).norm(), 1e-4);
  EXPECT_LT(s.q_base_tcp.angularDistance(kQ), 2e-3);
  // Input registers through the same code path.
  RegisterMap in;
  in.entries = {{"j1", 270, RegisterTable::input, RegisterType::uint16, WordOrder::big, 1e-3, 0.0, 320}};
  mc.map = in;
  RobotControllerDriver drv2(mc);
  drv2.connect();
  ASSERT_EQ(drv2.poll(s), PollStatus::ok) << drv2.last_problem();
  EXPECT_NEAR(s.joints[0], kJoints[0], 0.5e-3 + 1e-9);
}

TEST(Pymodbus, PymodbusClientReadsTheFakeController) {
  if (!have_pymodbus()) GTEST_SKIP() << "python3-pymodbus (with python3-serial-asyncio) is not installed";
  for (const RegisterMap& map : {ur_register_map(), float32_register_map()}) {
    FakeRobotConfig fc;
    fc.map = map;
    FakeRobotController fake(fc);
    fake.set_state(kJoints, kP, kQ);
    fake.start();
    std::vector<std::uint16_t> expected(410, 0);
    encode_state(map, kJoints, kP, kQ, expected);
    const bool ur = map.name == "ur";
    const std::vector<std::pair<unsigned, unsigned>> ranges = ur ? std::vector<std::pair<unsigned, unsigned>>{{270, 6}, {320, 6}, {400, 6}}
                                                                 : std::vector<std::pair<unsigned, unsigned>>{{0, 24}};
    std::vector<std::string> argv{HIL_PYTHON3, script("pymodbus_client.py"), std::to_string(fake.port())};
    for (const auto& [a, n] : ranges) argv.push_back(std::to_string(a) + ":" + std::to_string(n));
    hil::test::Child client(argv);
    ASSERT_TRUE(client.ok());
    for (const auto& [a, n] : ranges) {
      std::istringstream line(client.read_line());
      for (unsigned i = 0; i < n; ++i) {
        unsigned v = 99999;
        line >> v;
        EXPECT_EQ(v, expected[a + i]) << map.name << " register " << a + i;
      }
    }
    EXPECT_EQ(client.wait(), 0);
    EXPECT_EQ(fake.stats().replies, ranges.size());
  }
}
