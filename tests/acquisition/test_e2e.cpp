// End to end without hardware: the fake rig (ATI plate on an in-process CAN bus, a libmodbus
// robot controller on 127.0.0.1) plays the shipped example run; the Acquirer records and
// publishes; a DDS subscriber and the recording must agree sample for sample. Then each injected
// fault must be reported on DeviceStatus within 3 sample periods and clear when the fault ends.
#include <gtest/gtest.h>
#include <unistd.h>

#include <map>
#include <mutex>
#include <thread>

#include <hil/test/files.hpp>
#include <hil/acquisition/acquirer.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/topics.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/drivers_from_rig.hpp>

using namespace hil;

namespace {

/// Reader options for a CSV that must hold these numeric columns.
format::CsvOptions requiring(std::vector<std::string> columns) {
  format::CsvOptions o;
  o.required = std::move(columns);
  return o;
}

std::shared_ptr<const drivers::Scenario> example_scenario(bool loop) {
  const auto run = format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  return std::make_shared<const drivers::Scenario>(rig_service::scenario_from_run(run, Eigen::Isometry3d::Identity(), loop));
}

int test_domain(int base) { return base + static_cast<int>(getpid() % 40); }

struct StatusLog {
  std::mutex m;
  struct Entry {
    std::int64_t t_ns;
    std::string device;
    std::uint8_t state;
    std::string error;
  };
  std::vector<Entry> entries;
  void add(const hil_msgs::msg::DeviceStatus& s) {
    std::lock_guard<std::mutex> lock(m);
    entries.push_back({static_cast<std::int64_t>(messages::from_time(s.stamp()) * 1e9), s.device(), s.state(), s.last_error()});
  }
  // First status of `device` with a state other than ok at or after t_ns.
  const Entry* first_bad(const std::string& device, std::int64_t after_ns) {
    for (const auto& e : entries)
      if (e.device == device && e.state != hil_msgs::msg::DEVICE_OK && e.t_ns >= after_ns) return &e;
    return nullptr;
  }
  const Entry* first_ok(const std::string& device, std::int64_t after_ns) {
    for (const auto& e : entries)
      if (e.device == device && e.state == hil_msgs::msg::DEVICE_OK && e.t_ns >= after_ns) return &e;
    return nullptr;
  }
};

}  // namespace

TEST(EndToEnd, ThirtySecondsAt1kHzNoneLost) {
  hil::test::TempDir tmp;
  auto scenario = example_scenario(true);
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeNetCanOemConfig fc;
  drivers::FakeNetCanOemBoard fake_plate(fc, bus->open(), scenario);
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  drivers::FakeRobotController fake_robot(rc, scenario);

  drivers::ForcePlateConfig pc;
  auto plate = drivers::make_force_plate(pc, bus->open());
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  auto robot = std::make_unique<drivers::RobotControllerDriver>(mc);

  hil::dds::Participant participant({test_domain(60), "", "hil_localhost", "e2e"});
  std::mutex m;
  std::vector<hil_msgs::msg::PoseWrenchSample> received;
  hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> reader(participant, hil::dds::topics::kPoseWrenchSample,
                                                           [&](const auto& msg, const auto&) {
                                                             std::lock_guard<std::mutex> lock(m);
                                                             received.push_back(msg);
                                                           });

  format::RunInfo info;
  info.rig = "press_bench";
  info.output_rate_hz = 1000;
  const auto dir = tmp.path() + "/run";
  const auto start = acquisition::realtime_ns();
  {
    acquisition::RunRecorder rec(dir, info, "", start, 6);
    acquisition::AcquirerOptions ao;
    ao.sync.output_rate_hz = 1000;  // no decimation: every reading is a sample
    acquisition::Acquirer acq(ao, std::move(plate), std::move(robot), &participant, &rec);
    fake_plate.start();
    fake_robot.start();
    acq.start();
    std::this_thread::sleep_for(std::chrono::seconds(31));
    acq.stop();
    fake_plate.stop();
    fake_robot.stop();
    rec.close();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // last messages in flight
  }
  const auto run = format::load_run(dir);
  std::lock_guard<std::mutex> lock(m);
  ASSERT_GE(run.samples.size(), 30000u) << "at least 30 s of 1 kHz samples";
  ASSERT_EQ(received.size(), run.samples.size()) << "the subscriber and the recording disagree on the count";
  for (std::size_t i = 0; i < received.size(); ++i) {
    ASSERT_EQ(received[i].sample_index(), i) << "lost or reordered on the bus";
    const auto s = messages::from_message(received[i]);
    const auto& r = run.samples.samples[i];
    ASSERT_NEAR(s.t_s, r.t_s, 1e-9);
    ASSERT_EQ(s.f_fp_n, r.f_fp_n) << "row " << i;
    ASSERT_EQ(s.m_fp_nm, r.m_fp_nm) << "row " << i;
    ASSERT_EQ(s.p_world_ee_m, r.p_world_ee_m) << "row " << i;
  }
  // Against the played scenario: the plate's range comes through within its quantization and the
  // float32 pose map's resolution.
  double fz_min = 0, fz_max = 0, px_max = 0;
  for (const auto& s : run.samples.samples) {
    fz_min = std::min(fz_min, s.f_fp_n.z());
    fz_max = std::max(fz_max, s.f_fp_n.z());
    px_max = std::max(px_max, s.p_world_ee_m.x());
  }
  const auto played = format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  double fz_min_played = 0, fz_max_played = 0;
  for (const auto& s : played.samples.samples) {
    fz_min_played = std::min(fz_min_played, s.f_fp_n.z());
    fz_max_played = std::max(fz_max_played, s.f_fp_n.z());
  }
  EXPECT_NEAR(fz_min, fz_min_played, 1.0);
  EXPECT_NEAR(fz_max, fz_max_played, 1.0);
  EXPECT_NEAR(px_max, 0.02, 1e-6);
}

TEST(EndToEnd, InjectedFaultsAreReportedAndRecoveredFrom) {
  hil::test::TempDir tmp;
  auto scenario = example_scenario(true);
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeNetCanOemConfig fc;
  fc.faults.silent.push_back({1.0, 0.3});   // plate silent from 1.0 s to 1.3 s
  fc.faults.bus_off.push_back({3.0, 0.3});  // bus-off from 3.0 s to 3.3 s (losses are forgotten after 1 s)
  drivers::FakeNetCanOemBoard fake_plate(fc, bus->open(), scenario);
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  rc.faults.exception_windows.push_back({1.5, 0.3});  // Modbus exceptions from 1.5 s to 1.8 s
  drivers::FakeRobotController fake_robot(rc, scenario);

  drivers::ForcePlateConfig pc;
  auto plate = drivers::make_force_plate(pc, bus->open());
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  auto robot = std::make_unique<drivers::RobotControllerDriver>(mc);

  hil::dds::Participant participant({test_domain(100), "", "hil_localhost", "e2e-faults"});
  StatusLog log;
  hil::dds::Reader<hil_msgs::msg::DeviceStatus> reader(
      participant, hil::dds::topics::kDeviceStatus, [&](const auto& msg, const auto&) { log.add(msg); }, hil::dds::StreamQos{true, 0, 10});
  format::RunInfo info;
  info.rig = "press_bench";
  info.output_rate_hz = 50;
  const auto dir = tmp.path() + "/run";
  std::int64_t fake_start = 0;
  {
    acquisition::RunRecorder rec(dir, info, "", acquisition::realtime_ns(), 6);
    acquisition::AcquirerOptions ao;
    acquisition::Acquirer acq(ao, std::move(plate), std::move(robot), &participant, &rec);
    fake_start = acquisition::realtime_ns();
    fake_plate.start();
    fake_robot.start();
    acq.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(5000));
    acq.stop();
    fake_plate.stop();
    fake_robot.stop();
    rec.close();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  (void)fake_start;
  const auto run = format::load_run(dir);
  std::lock_guard<std::mutex> lock(log.m);
  ASSERT_FALSE(log.entries.empty());

  // Reads the raw plate stream to find the last good reading before each plate fault.
  std::vector<std::int64_t> plate_t;
  {
    const auto csv = format::read_csv(dir + "/raw/force_plate.csv", requiring({"t_ns"}));
    for (double t : csv.numeric("t_ns")) plate_t.push_back(static_cast<std::int64_t>(t));
  }
  auto last_before_hole = [&](std::int64_t from_ns) {
    for (std::size_t i = 1; i < plate_t.size(); ++i)
      if (plate_t[i - 1] >= from_ns && plate_t[i] - plate_t[i - 1] > 100'000'000) return plate_t[i - 1];
    return std::int64_t{0};
  };
  const std::int64_t period_ns = 1'000'000;  // 1 kHz plate
  // The 3-period rule itself is tested on exact time stamps (test_monitor.cpp); here, in wall-clock
  // time with the fakes and the acquisition sharing two cores with other tests, allow 5 ms of
  // scheduling slack (a run under CI load was 0.18 ms over a 1 ms slack).
  const std::int64_t slack_ns = 5'000'000;
  // Silence: reported within 3 periods of the last reading, and cleared after.
  const auto silent_from = last_before_hole(plate_t.front());
  ASSERT_NE(silent_from, 0) << "the silent window left no hole in the raw stream";
  const auto* bad = log.first_bad("force_plate", silent_from);
  ASSERT_NE(bad, nullptr) << "silence never reported";
  EXPECT_LE(bad->t_ns - silent_from, 3 * period_ns + slack_ns) << "reported " << (bad->t_ns - silent_from) / 1e6 << " ms late";
  EXPECT_TRUE(bad->error.find("silent") != std::string::npos || bad->error.find("lost") != std::string::npos) << bad->error;
  EXPECT_NE(log.first_ok("force_plate", bad->t_ns), nullptr) << "never recovered from the silence";
  // Bus-off: the second hole in the raw stream; reported as a fault naming bus-off.
  const auto busoff_from = last_before_hole(silent_from + 200'000'000);
  ASSERT_NE(busoff_from, 0);
  const auto* fault = log.first_bad("force_plate", busoff_from);
  ASSERT_NE(fault, nullptr);
  EXPECT_LE(fault->t_ns - busoff_from, 3 * period_ns + slack_ns) << "reported " << (fault->t_ns - busoff_from) / 1e6 << " ms late";
  bool named_bus_off = false;
  for (const auto& e : log.entries)
    if (e.device == "force_plate" && e.t_ns >= busoff_from && e.t_ns < busoff_from + 400'000'000)
      named_bus_off = named_bus_off || e.error.find("bus-off") != std::string::npos || e.error.find("bus_error") != std::string::npos;
  EXPECT_TRUE(named_bus_off);
  EXPECT_NE(log.first_ok("force_plate", fault->t_ns), nullptr) << "never recovered from bus-off";
  // Modbus exceptions: the robot is reported faulty, then ok again.
  const auto* robot_bad = log.first_bad("robot", 0);
  ASSERT_NE(robot_bad, nullptr) << "Modbus exceptions never reported";
  EXPECT_NE(log.first_ok("robot", robot_bad->t_ns), nullptr);
  // The recording marks the holes: rows flagged kGapBefore after each.
  const auto& q = run.samples;
  (void)q;
  int flagged = 0;
  const auto csv = format::read_csv(dir + "/samples.csv", requiring({"t", "quality"}));
  for (double v : csv.numeric("quality")) flagged += (static_cast<std::uint32_t>(v) & acquisition::kGapBefore) != 0;
  EXPECT_GE(flagged, 2) << "the silent and bus-off holes must be marked in the recording";
  // The samples whose pose spans the robot's exception burst (1.5-1.8 s) are device faults.
  const auto t = csv.numeric("t");
  const auto quality = csv.numeric("quality");
  int refused = 0;
  for (std::size_t i = 0; i < t.size(); ++i)
    refused += t[i] > 1.4 && t[i] < 2.0 && (static_cast<std::uint32_t>(quality[i]) & acquisition::kDeviceFault) != 0;
  EXPECT_GE(refused, 8) << "0.3 s of refused robot polls at 50 Hz output";
}

// The plate flags its readings (ATI status bits: supply too low, then temperature too high) in two
// windows. Every output sample whose filter window holds a flagged reading is recorded with
// kDeviceFault; samples far from them are not; DeviceStatus names the bits.
TEST(EndToEnd, FlaggedReadingsNeverReachTheRecordingAsGoodSamples) {
  hil::test::TempDir tmp;
  auto scenario = example_scenario(true);
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeNetCanOemConfig fc;
  fc.faults.status.push_back({{0.8, 0.3}, drivers::ati::kStatusSupplyTooLow});
  fc.faults.status.push_back({{1.8, 0.3}, drivers::ati::kStatusTemperatureTooHigh});
  drivers::FakeNetCanOemBoard fake_plate(fc, bus->open(), scenario);
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  drivers::FakeRobotController fake_robot(rc, scenario);
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  hil::dds::Participant participant({test_domain(180), "", "hil_localhost", "e2e-status"});
  StatusLog log;
  hil::dds::Reader<hil_msgs::msg::DeviceStatus> reader(
      participant, hil::dds::topics::kDeviceStatus, [&](const auto& msg, const auto&) { log.add(msg); }, hil::dds::StreamQos{true, 0, 10});
  format::RunInfo info;
  info.rig = "press_bench";
  info.output_rate_hz = 50;
  const auto dir = tmp.path() + "/run";
  const std::int64_t start_ns = acquisition::realtime_ns();
  std::uint64_t device_faults = 0;
  {
    acquisition::RunRecorder rec(dir, info, "", start_ns, 6);
    acquisition::Acquirer acq(acquisition::AcquirerOptions{}, drivers::make_force_plate({}, bus->open()),
                              std::make_unique<drivers::RobotControllerDriver>(mc), &participant, &rec);
    fake_plate.start();
    fake_robot.start();
    acq.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(3000));
    acq.stop();
    for (const auto& h : acq.health())
      if (h.device == "force_plate") device_faults = h.device_faults;
    fake_plate.stop();
    fake_robot.stop();
    rec.close();
  }
  std::vector<double> flagged_s;  // times of the readings the plate flagged, run time
  {
    const auto raw = format::read_csv(dir + "/raw/force_plate.csv", requiring({"t_ns", "status_word"}));
    const auto t = raw.numeric("t_ns");
    const auto st = raw.numeric("status_word");
    for (std::size_t i = 0; i < t.size(); ++i)
      if (st[i] != 0) flagged_s.push_back((t[i] - static_cast<double>(start_ns)) * 1e-9);
  }
  ASSERT_GT(flagged_s.size(), 100U) << "the status windows left no flagged readings";
  EXPECT_EQ(device_faults, flagged_s.size());
  const auto csv = format::read_csv(dir + "/samples.csv", requiring({"t", "quality"}));
  const auto ts = csv.numeric("t");
  const auto q = csv.numeric("quality");
  ASSERT_GT(ts.size(), 100U);
  const auto is_fault = [&](std::size_t i) { return (static_cast<std::uint32_t>(q[i]) & acquisition::kDeviceFault) != 0; };
  // The output nearest each flagged reading has it in its filter window: flagged.
  for (const double tf : flagged_s) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < ts.size(); ++i)
      if (std::abs(ts[i] - tf) < std::abs(ts[best] - tf)) best = i;
    if (std::abs(ts[best] - tf) > 0.02) continue;  // no output near it (the run's edges)
    EXPECT_TRUE(is_fault(best)) << "sample at t = " << ts[best] << " s recorded as good next to a reading flagged at " << tf << " s";
  }
  // Samples 0.2 s away from every flagged reading are not marked (the flag is specific).
  std::size_t clean = 0;
  for (std::size_t i = 0; i < ts.size(); ++i) {
    double nearest = 1e9;
    for (const double tf : flagged_s) nearest = std::min(nearest, std::abs(ts[i] - tf));
    if (nearest < 0.2) continue;
    EXPECT_FALSE(is_fault(i)) << "sample at t = " << ts[i] << " s marked with no flagged reading near";
    ++clean;
  }
  EXPECT_GT(clean, 50U);
  std::lock_guard<std::mutex> lock(log.m);
  bool named_supply = false, named_temperature = false;
  for (const auto& e : log.entries) {
    named_supply = named_supply || (e.device == "force_plate" && e.error.find("supply too low") != std::string::npos);
    named_temperature = named_temperature || (e.device == "force_plate" && e.error.find("temperature too high") != std::string::npos);
  }
  EXPECT_TRUE(named_supply);
  EXPECT_TRUE(named_temperature);
}

// Faults switched on and off while the service runs, as `hil fake-rig` does from its command line.
TEST(EndToEnd, FaultSwitchesAreReportedWithinThreePeriods) {
  auto scenario = example_scenario(true);
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeNetCanOemBoard fake_plate(drivers::FakeNetCanOemConfig{}, bus->open(), scenario);
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  drivers::FakeRobotController fake_robot(rc, scenario);
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  mc.timeout_s = 0.02;
  hil::dds::Participant participant({test_domain(140), "", "hil_localhost", "e2e-switches"});
  StatusLog log;
  hil::dds::Reader<hil_msgs::msg::DeviceStatus> reader(
      participant, hil::dds::topics::kDeviceStatus, [&](const auto& msg, const auto&) { log.add(msg); }, hil::dds::StreamQos{true, 0, 10});
  acquisition::AcquirerOptions ao;
  acquisition::Acquirer acq(ao, drivers::make_force_plate({}, bus->open()), std::make_unique<drivers::RobotControllerDriver>(mc),
                            &participant, nullptr);
  fake_plate.start();
  fake_robot.start();
  acq.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));

  struct Case {
    const char* name;
    const char* device;
    std::function<void()> on, off;
    double period_s;
    std::vector<std::string> reasons;  // what the report must say (any of)
  };
  drivers::CanFaults corrupt;
  corrupt.corrupt_fraction = 1.0;
  drivers::CanFaults errors;
  errors.error_frame_rate_hz = 200.0;
  drivers::CanFaults drops;
  drops.drop_fraction = 1.0;
  drivers::ModbusFaults slow;
  slow.slow_fraction = 1.0;
  slow.slow_delay_s = 0.05;  // beyond the driver's 20 ms timeout
  const std::vector<Case> cases = {
      {"corrupt frames", "force_plate", [&] { fake_plate.set_faults(corrupt); }, [&] { fake_plate.set_faults({}); }, 1e-3, {"bad frame"}},
      {"error frames",
       "force_plate",
       [&] { fake_plate.set_faults(errors); },
       [&] { fake_plate.set_faults({}); },
       1e-3,
       {"error frame", "CAN bus error"}},
      {"dropped frames",
       "force_plate",
       [&] { fake_plate.set_faults(drops); },
       [&] { fake_plate.set_faults({}); },
       1e-3,
       {"lost", "silent"}},
      {"slow responses", "robot", [&] { fake_robot.set_faults(slow); }, [&] { fake_robot.set_faults({}); }, 8e-3, {"silent", "timeout"}},
  };
  for (const auto& c : cases) {
    // Wait for a quiet state of the device first (drops keep it degraded for a second).
    std::this_thread::sleep_for(std::chrono::milliseconds(1300));
    const auto t_on = acquisition::realtime_ns();
    c.on();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto t_off = acquisition::realtime_ns();
    c.off();
    // Losses are remembered for a second; give the device up to 3 s to be ok again.
    for (int k = 0; k < 30; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      std::lock_guard<std::mutex> lock(log.m);
      if (k >= 12 && log.first_ok(c.device, t_off)) break;
    }
    std::lock_guard<std::mutex> lock(log.m);
    const StatusLog::Entry* bad = nullptr;
    for (const auto& e : log.entries) {
      if (bad || e.device != c.device || e.state == hil_msgs::msg::DEVICE_OK || e.t_ns < t_on) continue;
      for (const auto& r : c.reasons)
        if (e.error.find(r) != std::string::npos) bad = &e;
    }
    ASSERT_NE(bad, nullptr) << c.name << ": never reported with its reason";
    // Three periods of the device, plus the poll in flight when the fault was switched on.
    const double late_s = (bad->t_ns - t_on) * 1e-9;
    EXPECT_LE(late_s, 4 * c.period_s + 2e-3) << c.name << ": reported " << late_s * 1e3 << " ms after it began (" << bad->error << ")";
    EXPECT_NE(log.first_ok(c.device, t_off), nullptr) << c.name << ": never recovered";
  }
  acq.stop();
  fake_plate.stop();
  fake_robot.stop();
}
