// `hil acquire --rig RIG --out RUN`: the rig service. Polls the force plate (CAN) and the robot
// controller (Modbus), synchronizes, records the run and publishes it on the bus until Ctrl-C
// (or --duration). With --play RUN it first starts the fake rig in-process (loopback CAN and a
// Modbus server on 127.0.0.1) playing that run: the whole service without hardware or SocketCAN.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "../commands.hpp"
#include "acquire.hpp"
#include "hil/acquisition/acquirer.hpp"
#include "hil/drivers/socketcan.hpp"
#include "hil/format/error.hpp"
#include "hil/format/ros_frames.hpp"
#include "drivers_from_rig.hpp"
#include "mcap_sink.hpp"

namespace hil::cli {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_acquire_signal(int) { g_stop = true; }
}  // namespace

AcquireResult run_acquisition(const AcquireOptions& o, const std::function<void(const acquisition::SyncedSample&)>& observer) {
  const auto rig = format::load_rig(o.rig);
  std::string rig_text;
  {
    std::ifstream in(o.rig, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    rig_text = ss.str();
  }
  if (!rig.devices.force_plate) throw format::FormatError({o.rig, 0, 0, "devices.force_plate"}, "acquisition needs a force plate section");
  auto pcfg = rig::force_plate_config(rig);
  if (!o.can_interface.empty()) pcfg.interface = o.can_interface;
  const bool with_robot = rig.devices.robot.has_value() && !o.no_robot;
  const Eigen::Isometry3d T_world_base = rig::world_to_base(rig);

  // The in-process fake rig, when asked for.
  std::shared_ptr<drivers::CanLoopbackBus> loop;
  std::unique_ptr<drivers::FakeAtiForcePlate> fake_plate;
  std::unique_ptr<drivers::FakeRobotController> fake_robot;
  std::unique_ptr<drivers::CanChannel> channel;
  double play_duration_s = 0.0;
  drivers::ModbusConfig mcfg;
  if (with_robot) mcfg = rig::robot_controller_config(rig);
  if (!o.play.empty()) {
    const auto played = format::load_run(o.play);
    auto scenario = std::make_shared<const drivers::Scenario>(rig::scenario_from_run(played, T_world_base, false));
    play_duration_s = scenario->duration_s() / o.play_speed;
    drivers::FakeAtiConfig fc;
    fc.base_id = pcfg.base_id;
    fc.T_fp_sensor = pcfg.T_fp_sensor;
    fc.clock.speed = o.play_speed;
    fc.faults = o.plate_faults;
    if (o.play_over_socketcan) {
      drivers::SocketCanOptions so;
      so.interface = pcfg.interface;
      fake_plate = std::make_unique<drivers::FakeAtiForcePlate>(fc, drivers::SocketCanChannel::open(so), scenario);
    } else {
      loop = drivers::CanLoopbackBus::create("loop0");
      fake_plate = std::make_unique<drivers::FakeAtiForcePlate>(fc, loop->open(), scenario);
      channel = loop->open();
    }
    if (with_robot) {
      drivers::FakeRobotConfig rc;
      rc.map = mcfg.map;
      rc.port = 0;
      rc.clock.speed = o.play_speed;
      rc.faults = o.robot_faults;
      fake_robot = std::make_unique<drivers::FakeRobotController>(rc, scenario);
      mcfg.host = "127.0.0.1";
      mcfg.port = fake_robot->port();
    }
  }
  if (!channel) {
    drivers::SocketCanOptions so;
    so.interface = pcfg.interface;
    channel = drivers::SocketCanChannel::open(so);
  }
  if (with_robot && !o.robot_host.empty()) mcfg.host = o.robot_host;
  if (with_robot && o.robot_port > 0) mcfg.port = o.robot_port;

  format::RunInfo info;
  info.rig = rig.name;
  info.output_rate_hz = o.output_rate_hz;
  info.sources.push_back({"force_plate", "can", pcfg.rate_hz, "raw/force_plate.candump.log"});
  if (with_robot) info.sources.push_back({"robot", "modbus", mcfg.rate_hz, "raw/robot.csv"});
  info.notes = o.play.empty() ? "Recorded by hil acquire." : "Recorded by hil acquire from the fake rig playing " + o.play + ".";
  const auto start_ns = acquisition::realtime_ns();
  acquisition::RunRecorder recorder(o.out, info, rig_text, start_ns, with_robot ? mcfg.map.joint_count() : 0);

  // Every CAN frame both ways, as candump -L, next to the readings (raw/force_plate.csv).
  auto can_log = drivers::CanLogChannel::open_write(recorder.raw_path("force_plate.candump.log"),
                                                    drivers::CanLogOptions{pcfg.interface, false, 1.0, {}});
  drivers::CanLogChannel* can_log_ptr = can_log.get();
  channel = std::make_unique<drivers::CanRecordingChannel>(std::move(channel), std::move(can_log));
  auto plate = drivers::make_force_plate(pcfg, std::move(channel));
  std::unique_ptr<drivers::RobotControllerDriver> robot;
  if (with_robot) robot = std::make_unique<drivers::RobotControllerDriver>(mcfg);

  auto& g = globals();
  std::unique_ptr<dds::Participant> bus;
  if (!o.no_bus)
    bus = std::make_unique<dds::Participant>(dds::ParticipantOptions{g.dds_domain >= 0 ? g.dds_domain : dds::domain_from_env(),
                                                                     g.dds_profile, g.dds_profile_name, "hil-acquire"});
  acquisition::AcquirerOptions ao;
  ao.sync.wrench_rate_hz = pcfg.rate_hz;
  ao.sync.output_rate_hz = o.output_rate_hz;
  ao.T_world_base = T_world_base;
  ao.ros_topics = o.ros_topics;
  ao.static_frames = format::static_frames(rig);  // rt/tf_static
  ao.joint_names = format::joint_names(rig, with_robot ? mcfg.map.joint_count() : 0);
  ao.wait_for_subscribers = o.wait_subscribers;
  if (with_robot && !mcfg.map.has_pose() && !mcfg.kinematics)
    throw format::FormatError({o.rig, 0, 0, "robot"}, "the register map reads joints only: the rig needs a robot DH table");
  // --mcap: run.mcap beside the CSV, from the same samples (docs/mcap.md). Made before the
  // acquirer so that it outlives it: the acquirer's last samples reach a sink still there.
  std::unique_ptr<McapSink> mcap_sink;
  if (o.mcap)
    mcap_sink = std::make_unique<McapSink>(recorder.dir() + "/run.mcap", rig, with_robot ? mcfg.map.joint_count() : 0, start_ns,
                                           mcap::parse_compression(o.mcap_compression));
  acquisition::Acquirer acq(ao, std::move(plate), std::move(robot), bus.get(), &recorder);
  if (observer) acq.on_sample(observer);
  if (mcap_sink) acq.on_sample([&mcap_sink](const acquisition::SyncedSample& s) { mcap_sink->sample(s); });

  if (fake_plate) fake_plate->start();
  if (fake_robot) fake_robot->start();
  acq.start();
  if (o.tare) acq.tare();
  std::signal(SIGINT, on_acquire_signal);
  std::signal(SIGTERM, on_acquire_signal);
  const double duration = o.duration_s > 0 ? o.duration_s : play_duration_s;
  const auto t0 = std::chrono::steady_clock::now();
  auto next_progress = t0 + std::chrono::seconds(5);
  auto next_flush = t0 + std::chrono::seconds(1);
  while (!g_stop) {
    const auto now = std::chrono::steady_clock::now();
    if (duration > 0 && now - t0 >= std::chrono::duration<double>(duration)) break;
    if (now >= next_flush) {  // the CAN log is written by the plate thread; FILE* locks make this safe
      can_log_ptr->flush();
      if (mcap_sink) mcap_sink->flush();
      next_flush += std::chrono::seconds(1);
    }
    if (mcap_sink) mcap_sink->health(acq.health(), acquisition::realtime_ns());
    if (o.progress && now >= next_progress) {
      spdlog::info("acquire: {} samples, {:.0f} s", acq.samples(), std::chrono::duration<double>(now - t0).count());
      next_progress += std::chrono::seconds(5);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  acq.stop();
  if (fake_plate) fake_plate->stop();
  if (fake_robot) fake_robot->stop();

  AcquireResult r;
  r.samples = acq.samples();
  r.health = acq.health();
  r.gaps = recorder.gaps();
  std::string summary = fmt::format("Samples: {}, gaps: {}.", r.samples, r.gaps);
  for (const auto& h : r.health)
    summary += fmt::format(" {}: {} samples, {} errors, {} dropped{}.", h.device, h.samples, h.errors, h.frames_dropped,
                           h.last_error.empty() ? "" : ", last error: " + h.last_error);
  recorder.close(summary);
  if (mcap_sink) {
    mcap_sink->health(r.health, acquisition::realtime_ns(), true);  // the devices' final state
    mcap_sink->close();
  }
  r.summary = summary;
  return r;
}

void add_acquire(CLI::App& app) {
  auto* cmd = app.add_subcommand("acquire", "Acquire from the rig: record a run and publish it on the bus");
  static AcquireOptions o;
  cmd->add_option("--rig", o.rig, "rig file (devices section)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o.out, "run folder to create")->required();
  cmd->add_option("--duration", o.duration_s, "seconds to acquire (default: until Ctrl-C, or the played run's length)");
  cmd->add_option("--output-rate", o.output_rate_hz, "output rate in Hz (must divide the force-plate rate)")->capture_default_str();
  cmd->add_option("--can-interface", o.can_interface, "SocketCAN interface (default: the rig's)");
  cmd->add_option("--robot-host", o.robot_host, "Modbus host (default: the rig's)");
  cmd->add_option("--robot-port", o.robot_port, "Modbus port (default: the rig's)");
  cmd->add_flag("--no-robot", o.no_robot, "acquire the force plate only");
  cmd->add_flag("--tare", o.tare, "tare the force plate at start");
  cmd->add_option("--wait-subscribers", o.wait_subscribers, "wait (up to 10 s) for this many PoseWrenchSample subscribers before starting");
  cmd->add_flag("!--no-ros-topics", o.ros_topics, "do not publish rt/hil/wrench, rt/hil/pose, rt/hil/joint_states, rt/tf_static, rt/diagnostics");
  cmd->add_option("--play", o.play, "start the fake rig in-process playing this run (no hardware, no SocketCAN)")
      ->check(CLI::ExistingDirectory);
  cmd->add_flag("--mcap", o.mcap, "also record run.mcap in the run folder (ROS 2 channels, docs/mcap.md)");
  cmd->add_option("--mcap-compression", o.mcap_compression, "chunk compression of run.mcap: none, zstd or lz4")
      ->check(CLI::IsMember({"none", "zstd", "lz4"}))
      ->capture_default_str();
  cmd->add_option("--play-speed", o.play_speed, "playback speed of --play")->capture_default_str();
  cmd->add_flag("--play-on-can", o.play_over_socketcan,
                "with --play: the fake plate answers on the SocketCAN interface (e.g. vcan0) instead of an in-process bus");
  cmd->callback([] {
    set_action([] {
      const auto r = run_acquisition(o, nullptr);
      std::cout << fmt::format("recorded {} -> {}\n", r.summary, o.out);
      for (const auto& h : r.health)
        if (h.samples == 0) return 1;  // a device that never answered is a failed acquisition
      return 0;
    });
  });
}

}  // namespace hil::cli
