// `hil fake-rig`: a fake force plate (ATI NETCANOEM on a SocketCAN interface, a Net F/T box on
// UDP, a Robotiq FT 300 on a pseudo-terminal) and a fake robot controller (Modbus TCP on 127.0.0.1), playing a recorded run, with fault
// injection.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/rig_service/drivers_from_rig.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/socketcan.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include "rig_commands.hpp"

namespace hil::cli {
namespace {

struct FakeRigOptions {
  std::string rig, run;
  bool no_plate = false, no_robot = false;
  std::string can_iface;
  int base_id = -1;
  std::string host = "127.0.0.1";
  int port = -1;
  std::string register_map;
  double speed = 1.0;
  bool loop = false;
  double duration_s = 0.0;
  std::uint64_t seed = 1;
  // force plate faults
  double drop = 0, corrupt = 0, duplicate = 0, error_frames_hz = 0, plate_delay_s = 0;
  std::string netft_host = "127.0.0.1";
  int netft_port = -1;
  std::string serial_link;  ///< FT 300: a symlink to the pseudo-terminal, for the rig's serial_device
  double noise = 0;
  std::vector<std::string> plate_exception_windows;
  std::vector<std::string> silent, bus_off, plate_status;
  double plate_clock_offset_s = 0, plate_clock_drift_ppm = 0;
  // robot faults
  double exceptions = 0, slow_fraction = 0, slow_delay_s = 0.5, robot_delay_s = 0;
  std::vector<std::string> robot_silent, exception_windows;
  double robot_clock_offset_s = 0, robot_clock_drift_ppm = 0;
};

std::atomic<bool> g_stop{false};
void on_fake_rig_signal(int) { g_stop = true; }

std::vector<drivers::TimeWindow> windows(const std::vector<std::string>& specs, const char* option) {
  std::vector<drivers::TimeWindow> out;
  for (const auto& s : specs) {
    const auto colon = s.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument("no colon");
      std::size_t n1 = 0, n2 = 0;
      const double a = std::stod(s.substr(0, colon), &n1);
      const double d = std::stod(s.substr(colon + 1), &n2);
      if (n1 != colon || n2 != s.size() - colon - 1 || a < 0 || d <= 0) throw std::invalid_argument("range");
      out.push_back({a, d});
    } catch (const std::exception&) {
      throw std::runtime_error(fmt::format("{} '{}': expected START:DURATION in seconds (start ≥ 0, duration > 0)", option, s));
    }
  }
  return out;
}

/// "0x0020@1.5:0.5": status bits set in the answers from 1.5 s for 0.5 s.
std::vector<drivers::StatusWindow> status_windows(const std::vector<std::string>& specs, const char* option) {
  std::vector<drivers::StatusWindow> out;
  for (const auto& s : specs) {
    const auto at = s.find('@');
    const auto fail = [&] {
      return std::runtime_error(fmt::format("{} '{}': expected BITS@START:DURATION (bits as 0x.... non-zero, start ≥ 0 s, duration > 0 s)",
                                            option, s));
    };
    if (at == std::string::npos || at == 0) throw fail();
    std::uint32_t bits = 0;
    try {
      std::size_t n = 0;
      const unsigned long v = std::stoul(s.substr(0, at), &n, 0);
      if (n != at || v == 0 || v > 0xFFFFFFFFUL) throw fail();
      bits = static_cast<std::uint32_t>(v);
    } catch (const std::logic_error&) {
      throw fail();
    }
    const auto w = windows({s.substr(at + 1)}, option);
    out.push_back({w.front(), bits});
  }
  return out;
}

/// The faults both plates' fakes share (CanFaults, StreamFaults), from the command line.
template <typename Faults>
void plate_faults(const FakeRigOptions& o, Faults& f) {
  f.drop_fraction = o.drop;
  f.corrupt_fraction = o.corrupt;
  f.extra_delay_s = o.plate_delay_s;
  f.silent = windows(o.silent, "--silent");
  f.status = status_windows(o.plate_status, "--plate-status");
}

int fake_rig(const FakeRigOptions& o) {
  if (o.rig.empty() && o.run.empty()) throw std::runtime_error("fake-rig: give --rig RIG and/or --run RUN");
  std::optional<format::Run> run;
  format::RigSpec rig;
  if (!o.run.empty()) {
    run = format::load_run(o.run, o.rig);
    if (!run->rig) throw std::runtime_error("fake-rig: the run " + o.run + " has no rig.yaml; give --rig");
    rig = *run->rig;
  } else {
    rig = format::load_rig(o.rig);
  }
  const Eigen::Isometry3d T_world_base = rig_service::world_to_base(rig);
  std::shared_ptr<const drivers::Scenario> scenario;
  if (run) {
    scenario = std::make_shared<drivers::Scenario>(rig_service::scenario_from_run(*run, T_world_base, o.loop));
  } else {
    drivers::ScenarioPoint still;
    still.joints_rad.assign(rig.robot ? rig.robot->joints.size() : 6, 0.0);
    scenario = std::make_shared<drivers::Scenario>(std::vector<drivers::ScenarioPoint>{still});
  }

  std::unique_ptr<drivers::FakeNetCanOemBoard> plate;
  std::unique_ptr<drivers::FakeNetFtRdt> netft;
  std::unique_ptr<drivers::FakeRobotiqFt300> ft300;
  std::unique_ptr<drivers::FakeRobotController> robot;
  const bool rdt = rig.devices.force_plate && rig.devices.force_plate->protocol == "ati_netft_rdt";
  const bool serial = rig.devices.force_plate && rig.devices.force_plate->protocol == "robotiq_ft300";
  if (!serial && (!o.serial_link.empty() || o.noise > 0 || !o.plate_exception_windows.empty()))
    throw std::runtime_error("fake-rig: --serial-link, --noise and --plate-exception-window are the FT 300's; the rig's plate is not one");
  if (!o.no_plate && serial) {
    // The FT 300 on a pseudo-terminal; --serial-link names it as the rig's serial_device does.
    const auto& fp = *rig.devices.force_plate;
    drivers::FakeFt300Config fc;
    fc.stream_rate_hz = fp.allowed_writes.empty() ? drivers::robotiq::kStreamRateHz : fp.rate_hz;
    fc.slave = fp.slave;
    fc.T_fp_sensor = fp.T_fp_sensor.isometry();
    plate_faults(o, fc.stream);
    fc.stream.status.clear();
    if (!o.plate_status.empty() || !o.bus_off.empty() || o.error_frames_hz > 0 || o.duplicate > 0)
      throw std::runtime_error(
          "fake-rig: --plate-status, --bus-off, --error-frames and --duplicate do not apply to an FT 300 on a serial line");
    fc.noise_fraction = o.noise;
    fc.modbus.exception_windows = windows(o.plate_exception_windows, "--plate-exception-window");
    fc.clock = {o.plate_clock_offset_s, o.plate_clock_drift_ppm, o.speed};
    fc.seed = o.seed;
    ft300 = std::make_unique<drivers::FakeRobotiqFt300>(fc, scenario);
    if (!o.serial_link.empty()) {
      std::error_code ec;
      std::filesystem::remove(o.serial_link, ec);
      std::filesystem::create_symlink(ft300->device_path(), o.serial_link, ec);
      if (ec) throw std::runtime_error("fake-rig: --serial-link " + o.serial_link + ": " + ec.message());
    }
    std::printf("fake-rig: force plate Robotiq FT 300 on %s%s%s\n", ft300->device_path().c_str(), o.serial_link.empty() ? "" : " as ",
                o.serial_link.c_str());
  } else if (!o.no_plate && rdt) {
    // The Net F/T box on 127.0.0.0/8 at the rig's port: the driver finds it with the rig's
    // settings when its host is a loopback address.
    const auto& fp = *rig.devices.force_plate;
    drivers::FakeNetFtConfig nc;
    nc.host = o.netft_host;
    nc.port = o.netft_port >= 0 ? o.netft_port : fp.port;
    nc.rate_hz = fp.rate_hz;
    nc.calibration = rig_service::force_plate_config(rig).netft_calibration;
    nc.T_fp_sensor = fp.T_fp_sensor.isometry();
    plate_faults(o, nc.faults);
    nc.faults.duplicate_fraction = o.duplicate;
    if (!o.bus_off.empty() || o.error_frames_hz > 0)
      throw std::runtime_error("fake-rig: --bus-off and --error-frames are CAN faults; the rig's plate is a Net F/T box on UDP");
    nc.clock = {o.plate_clock_offset_s, o.plate_clock_drift_ppm, o.speed};
    nc.seed = o.seed;
    netft = std::make_unique<drivers::FakeNetFtRdt>(nc, scenario);
    std::printf("fake-rig: force plate ATI Net F/T RDT on udp %s:%d\n", nc.host.c_str(), netft->port());
  } else if (!o.no_plate) {
    drivers::FakeNetCanOemConfig pc;
    std::string iface = o.can_iface;
    if (rig.devices.force_plate) {
      const auto& fp = *rig.devices.force_plate;
      if (fp.protocol != "ati_netcanoem" && fp.protocol != "ati_netft_can")
        throw std::runtime_error("fake-rig: a fake CAN force plate speaks ati_netcanoem or ati_netft_can; the rig's plate is " +
                                 fp.protocol);
      pc.netft_box = fp.protocol == "ati_netft_can";
      if (pc.netft_box) pc.box_calibration = rig_service::force_plate_config(rig).netft_calibration;
      pc.base_id = fp.base_id;
      pc.T_fp_sensor = fp.T_fp_sensor.isometry();
      if (iface.empty()) iface = fp.interface;
    }
    if (iface.empty()) iface = "vcan0";
    if (o.base_id >= 0) pc.base_id = static_cast<std::uint32_t>(o.base_id);
    plate_faults(o, pc.faults);
    pc.faults.error_frame_rate_hz = o.error_frames_hz;
    pc.faults.bus_off = windows(o.bus_off, "--bus-off");
    pc.clock = {o.plate_clock_offset_s, o.plate_clock_drift_ppm, o.speed};
    pc.seed = o.seed;
    drivers::SocketCanOptions so;
    so.interface = iface;
    so.channel.error_mask = 0;
    // Only the requests addressed to the fake: a NETCANOEM board's 16 ids, or the box's one.
    so.channel.filters = {pc.netft_box ? drivers::CanFilter::masked(pc.base_id, 0x7FF)
                                       : drivers::CanFilter::masked(pc.base_id << 4, 0x7F0)};
    so.timestamps = false;
    plate = std::make_unique<drivers::FakeNetCanOemBoard>(pc, drivers::SocketCanChannel::open(so), scenario);
    if (pc.netft_box) std::printf("fake-rig: force plate ATI Net F/T CAN base address 0x%03X on %s\n", pc.base_id, iface.c_str());
    else std::printf("fake-rig: force plate ATI NETCANOEM base 0x%02X on %s\n", pc.base_id, iface.c_str());
  }
  if (!o.no_robot) {
    drivers::FakeRobotConfig rc;
    rc.host = o.host;
    int port = 502;
    if (rig.devices.robot) {
      rc.map = rig_service::register_map(*rig.devices.robot, rig.source);
      port = rig.devices.robot->port;
    }
    if (!o.register_map.empty()) rc.map = drivers::builtin_register_map(o.register_map);
    rc.port = o.port >= 0 ? o.port : port;
    rc.faults.exception_fraction = o.exceptions;
    rc.faults.exception_windows = windows(o.exception_windows, "--modbus-exception-window");
    rc.faults.slow_fraction = o.slow_fraction;
    rc.faults.slow_delay_s = o.slow_delay_s;
    rc.faults.extra_delay_s = o.robot_delay_s;
    rc.faults.silent = windows(o.robot_silent, "--modbus-silent");
    rc.clock = {o.robot_clock_offset_s, o.robot_clock_drift_ppm, o.speed};
    rc.seed = o.seed + 1;
    robot = std::make_unique<drivers::FakeRobotController>(rc, scenario);
    std::printf("fake-rig: robot controller Modbus TCP %s:%d map %s\n", rc.host.c_str(), robot->port(), rc.map.name.c_str());
  }
  if (!plate && !netft && !ft300 && !robot) throw std::runtime_error("fake-rig: --no-plate and --no-robot leave nothing to fake");
  std::fflush(stdout);

  g_stop = false;
  std::signal(SIGINT, on_fake_rig_signal);
  std::signal(SIGTERM, on_fake_rig_signal);
  if (plate) plate->start();
  if (netft) netft->start();
  if (ft300) ft300->start();
  if (robot) robot->start();
  const auto start = std::chrono::steady_clock::now();
  const double scenario_end = scenario->duration_s() / o.speed;
  bool told_end = false;
  spdlog::info("fake-rig: playing {:.1f} s of scenario at {}x{}; Ctrl-C stops", scenario->duration_s(), o.speed, o.loop ? ", looping" : "");
  while (!g_stop) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (o.duration_s > 0 && t >= o.duration_s) break;
    if (!o.loop && !told_end && t >= scenario_end) {
      spdlog::info("fake-rig: scenario ended; holding its last state");
      told_end = true;
    }
  }
  if (plate) plate->stop();
  if (netft) netft->stop();
  if (ft300) ft300->stop();
  if (robot) robot->stop();
  if (ft300 && !o.serial_link.empty()) {
    std::error_code ec;
    std::filesystem::remove(o.serial_link, ec);
  }
  if (plate) {
    const auto s = plate->stats();
    spdlog::info("fake-rig: plate requests {}, gauge answers {}, frames sent {}, dropped {}, corrupted {}, error frames {}, ignored {}",
                 s.requests, s.gauge_answers, s.frames_sent, s.frames_dropped, s.answers_corrupted, s.error_frames_sent, s.ignored_silent);
  }
  if (netft) {
    const auto s = netft->stats();
    spdlog::info("fake-rig: Net F/T requests {} (starts {}, stops {}, biases {}), records {}, sent {}, dropped {}, silenced {}, "
                 "datagrams corrupted {}, duplicated {}, flagged {}",
                 s.requests, s.starts, s.stops, s.biases, s.records, s.records_sent, s.records_dropped, s.records_silenced,
                 s.datagrams_corrupted, s.datagrams_duplicated, s.records_flagged);
  }
  if (ft300) {
    const auto s = ft300->stats();
    spdlog::info("fake-rig: FT 300 requests {} (bad {}, exceptions {}), stream starts {}, stops {}, frames {}, sent {}, dropped {}, "
                 "corrupted {}, silenced {}, noise bytes {}, overruns {}",
                 s.requests, s.bad_requests, s.exceptions, s.stream_starts, s.stream_stops, s.frames, s.frames_sent, s.frames_dropped,
                 s.frames_corrupted, s.frames_silenced, s.noise_bytes, s.overruns);
  }
  if (robot) {
    const auto s = robot->stats();
    spdlog::info("fake-rig: robot connections {}, requests {}, replies {}, exceptions {}, slow {}, ignored {}, writes refused {}",
                 s.connections, s.requests, s.replies, s.exceptions, s.slow, s.ignored_silent, s.writes_refused);
  }
  return 0;
}

}  // namespace

void add_fake_rig(CLI::App& app) {
  static FakeRigOptions o;
  auto* cmd = app.add_subcommand(
      "fake-rig",
      "Fake force plate (ATI NETCANOEM on SocketCAN, a Net F/T box's RDT on UDP 127.0.0.1, or a Robotiq FT 300 on a pseudo-terminal) "
      "and robot controller (Modbus TCP on 127.0.0.1) playing a recorded run, with fault injection");
  cmd->add_option("--rig", o.rig, "rig file (default: the run's rig.yaml)");
  cmd->add_option("--run", o.run, "run folder to replay (default: a still rig)");
  cmd->add_option("--speed", o.speed, "playback speed factor")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_flag("--loop", o.loop, "replay the run in a loop");
  cmd->add_option("--duration", o.duration_s, "stop after this many seconds (0: at Ctrl-C)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", o.seed, "seed of the fault injection's random choices")->capture_default_str();
  auto* g_plate = cmd->add_option_group("force plate");
  g_plate->add_flag("--no-plate", o.no_plate, "no fake force plate");
  g_plate->add_option("--can", o.can_iface, "SocketCAN interface (default: the rig's, else vcan0)");
  g_plate->add_option("--base-id", o.base_id, "ATI NETCANOEM base id 0..0x7F, or a Net F/T box's CAN base address (default: the rig's)")
      ->check(CLI::Range(0, 0x7F9));
  g_plate->add_option("--drop", o.drop, "share of answer frames dropped")->check(CLI::Range(0.0, 1.0));
  g_plate->add_option("--corrupt", o.corrupt, "share of answers (CAN) or datagrams (Net F/T) sent corrupt (wrong length)")
      ->check(CLI::Range(0.0, 1.0));
  g_plate->add_option("--duplicate", o.duplicate, "Net F/T: share of datagrams sent twice")->check(CLI::Range(0.0, 1.0));
  g_plate->add_option("--netft-host", o.netft_host, "Net F/T: listen address (127.0.0.0/8 only)")->capture_default_str();
  g_plate->add_option("--netft-port", o.netft_port, "Net F/T: UDP port (default: the rig's; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  g_plate->add_option("--serial-link", o.serial_link,
                      "FT 300: a symlink to its pseudo-terminal (the rig's serial_device), removed at exit");
  g_plate->add_option("--noise", o.noise, "FT 300: share of stream frames preceded by stray bytes")->check(CLI::Range(0.0, 1.0));
  g_plate->add_option("--plate-exception-window", o.plate_exception_windows,
                      "FT 300: START:DURATION (s) of Modbus exception answers; repeatable");
  g_plate->add_option("--silent", o.silent, "START:DURATION (s) without answers; repeatable");
  g_plate->add_option("--bus-off", o.bus_off, "START:DURATION (s) of bus-off (error frames, silence, restart); repeatable");
  g_plate->add_option("--plate-status", o.plate_status,
                      "BITS@START:DURATION: status bits (e.g. 0x0020, supply too low) in the plate's answers; repeatable");
  g_plate->add_option("--error-frames", o.error_frames_hz, "error-passive error frames per second")->check(CLI::NonNegativeNumber);
  g_plate->add_option("--plate-delay", o.plate_delay_s, "extra delay on every answer (s)")->check(CLI::NonNegativeNumber);
  g_plate->add_option("--plate-clock-offset", o.plate_clock_offset_s, "device clock offset (s)");
  g_plate->add_option("--plate-clock-drift-ppm", o.plate_clock_drift_ppm, "device clock drift (ppm)");
  auto* g_robot = cmd->add_option_group("robot controller");
  g_robot->add_flag("--no-robot", o.no_robot, "no fake robot controller");
  g_robot->add_option("--host", o.host, "listen address (127.0.0.0/8 only)")->capture_default_str();
  g_robot->add_option("--port", o.port, "TCP port (default: the rig's; 0: any free port)")->check(CLI::Range(0, 65535));
  g_robot->add_option("--register-map", o.register_map, "ur or float32 (default: the rig's)")->check(CLI::IsMember({"ur", "float32"}));
  g_robot->add_option("--modbus-exceptions", o.exceptions, "share of requests answered with exception 6 (busy)")
      ->check(CLI::Range(0.0, 1.0));
  g_robot->add_option("--modbus-exception-window", o.exception_windows, "START:DURATION (s) of exception answers; repeatable");
  g_robot->add_option("--modbus-slow", o.slow_fraction, "share of requests answered slowly")->check(CLI::Range(0.0, 1.0));
  g_robot->add_option("--modbus-slow-delay", o.slow_delay_s, "delay of a slow answer (s)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g_robot->add_option("--modbus-silent", o.robot_silent, "START:DURATION (s) without answers; repeatable");
  g_robot->add_option("--robot-delay", o.robot_delay_s, "extra delay on every answer (s)")->check(CLI::NonNegativeNumber);
  g_robot->add_option("--robot-clock-offset", o.robot_clock_offset_s, "device clock offset (s)");
  g_robot->add_option("--robot-clock-drift-ppm", o.robot_clock_drift_ppm, "device clock drift (ppm)");
  cmd->callback([] { set_action([] { return fake_rig(o); }); });
}

}  // namespace hil::cli
