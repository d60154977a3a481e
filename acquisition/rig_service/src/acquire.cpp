// The rig service behind `hil acquire` and `hil demo`. Polls the force plate (CAN) and the robot
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

#include <hil/rig_service/acquire.hpp>
#include <hil/acquisition/acquirer.hpp>
#include <hil/acquisition/identity.hpp>
#include <hil/drivers/netft_driver.hpp>
#include <hil/drivers/robotiq_driver.hpp>
#include <hil/drivers/socketcan.hpp>
#include <hil/error/error.hpp>
#include <hil/format/ros_frames.hpp>
#include <hil/rig_service/drivers_from_rig.hpp>
#include <hil/acquisition/mcap_sink.hpp>

namespace hil::rig_service {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_acquire_signal(int) { g_stop = true; }
}  // namespace

namespace {
/// The rig's devices as `hil acquire` opens them: with --play, the fake rig in-process first
/// (members are destroyed in reverse order: the channel before the fakes it talks to).
struct RigDevices {
  format::RigSpec rig;
  std::string rig_text;
  drivers::ForcePlateConfig plate_cfg;
  bool with_robot = false;
  drivers::ModbusConfig robot_cfg;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  double play_duration_s = 0.0;
  std::shared_ptr<drivers::CanLoopbackBus> loop;
  std::unique_ptr<drivers::FakeNetCanOemBoard> fake_plate;
  std::unique_ptr<drivers::FakeNetFtRdt> fake_netft;
  std::unique_ptr<drivers::FakeRobotiqFt300> fake_ft300;
  std::unique_ptr<drivers::FakeRobotController> fake_robot;
  std::unique_ptr<drivers::CanChannel> channel;  ///< CAN protocols only

  bool rdt() const { return plate_cfg.protocol == drivers::ForcePlateProtocol::ati_netft_rdt; }
  bool ft300() const { return plate_cfg.protocol == drivers::ForcePlateProtocol::robotiq_ft300; }
  bool can() const { return !rdt() && !ft300(); }
  void start_fakes() {
    if (fake_plate) fake_plate->start();
    if (fake_netft) fake_netft->start();
    if (fake_ft300) fake_ft300->start();
    if (fake_robot) fake_robot->start();
  }
  void stop_fakes() {
    if (fake_plate) fake_plate->stop();
    if (fake_netft) fake_netft->stop();
    if (fake_ft300) fake_ft300->stop();
    if (fake_robot) fake_robot->stop();
  }
  /// The plate's driver: on the channel for CAN protocols (consumed), on its own UDP socket for
  /// RDT, on its serial port for the FT 300.
  std::unique_ptr<drivers::ForcePlate> make_plate() {
    if (rdt()) return std::make_unique<drivers::NetFtRdtDriver>(plate_cfg);
    if (ft300()) return std::make_unique<drivers::RobotiqFt300Driver>(plate_cfg);
    return drivers::make_force_plate(plate_cfg, std::move(channel));
  }
  std::string link() const {
    if (rdt()) return "udp " + plate_cfg.host + ":" + std::to_string(plate_cfg.port);
    if (ft300()) return plate_cfg.serial_device;
    return channel->name();
  }
  /// The run's source kind for the plate.
  const char* source_kind() const { return rdt() ? "udp" : ft300() ? "serial" : "can"; }
};

RigDevices open_rig_devices(const AcquireOptions& o) {
  RigDevices d;
  d.rig = format::load_rig(o.rig);
  {
    std::ifstream in(o.rig, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    d.rig_text = ss.str();
  }
  const auto& rig = d.rig;
  if (!rig.devices.force_plate) throw error::FormatError({o.rig, 0, 0, "devices.force_plate"}, "acquisition needs a force plate section");
  d.plate_cfg = rig_service::force_plate_config(rig);
  if (!o.can_interface.empty()) d.plate_cfg.interface = o.can_interface;
  d.with_robot = rig.devices.robot.has_value() && !o.no_robot;
  d.T_world_base = rig_service::world_to_base(rig);
  if (d.with_robot) d.robot_cfg = rig_service::robot_controller_config(rig);
  if (!o.play.empty()) {
    const auto played = format::load_run(o.play);
    auto scenario = std::make_shared<const drivers::Scenario>(rig_service::scenario_from_run(played, d.T_world_base, o.play_loop));
    d.play_duration_s = o.play_loop ? 0.0 : scenario->duration_s() / o.play_speed;
    if (d.ft300()) {
      // The fake sensor on a pseudo-terminal; the driver opens its slave side.
      drivers::FakeFt300Config fc;
      fc.stream_rate_hz = d.plate_cfg.robotiq_stream ? d.plate_cfg.rate_hz : drivers::robotiq::kStreamRateHz;
      fc.T_fp_sensor = d.plate_cfg.T_fp_sensor;
      fc.clock.speed = o.play_speed;
      fc.stream = o.stream_faults;
      fc.modbus = o.plate_modbus_faults;
      d.fake_ft300 = std::make_unique<drivers::FakeRobotiqFt300>(fc, scenario);
      d.plate_cfg.serial_device = d.fake_ft300->device_path();
    }
    if (d.rdt()) {
      // The fake box on 127.0.0.1 (an ephemeral port); the driver is pointed at it.
      drivers::FakeNetFtConfig nc;
      nc.rate_hz = d.plate_cfg.rate_hz;
      nc.calibration = d.plate_cfg.netft_calibration;
      nc.T_fp_sensor = d.plate_cfg.T_fp_sensor;
      nc.clock.speed = o.play_speed;
      nc.faults = o.stream_faults;
      d.fake_netft = std::make_unique<drivers::FakeNetFtRdt>(nc, scenario);
      d.plate_cfg.host = "127.0.0.1";
      d.plate_cfg.port = d.fake_netft->port();
    }
    drivers::FakeNetCanOemConfig fc;
    fc.netft_box = d.plate_cfg.protocol == drivers::ForcePlateProtocol::ati_netft_can;
    if (fc.netft_box) fc.box_calibration = d.plate_cfg.netft_calibration;
    fc.base_id = d.plate_cfg.base_id;
    fc.T_fp_sensor = d.plate_cfg.T_fp_sensor;
    fc.clock.speed = o.play_speed;
    fc.faults = o.plate_faults;
    if (!d.can()) {
      // no CAN fake
    } else if (o.play_over_socketcan) {
      drivers::SocketCanOptions so;
      so.interface = d.plate_cfg.interface;
      d.fake_plate = std::make_unique<drivers::FakeNetCanOemBoard>(fc, drivers::SocketCanChannel::open(so), scenario);
    } else {
      d.loop = drivers::CanLoopbackBus::create("loop0");
      d.fake_plate = std::make_unique<drivers::FakeNetCanOemBoard>(fc, d.loop->open(), scenario);
      d.channel = d.loop->open();
    }
    if (d.with_robot) {
      drivers::FakeRobotConfig rc;
      rc.map = d.robot_cfg.map;
      rc.port = 0;
      rc.clock.speed = o.play_speed;
      rc.faults = o.robot_faults;
      d.fake_robot = std::make_unique<drivers::FakeRobotController>(rc, scenario);
      d.robot_cfg.host = "127.0.0.1";
      d.robot_cfg.port = d.fake_robot->port();
    }
  }
  if (!d.channel && d.can()) {
    drivers::SocketCanOptions so;
    so.interface = d.plate_cfg.interface;
    d.channel = drivers::SocketCanChannel::open(so);
  }
  if (d.with_robot && !o.robot_host.empty()) d.robot_cfg.host = o.robot_host;
  if (d.with_robot && o.robot_port > 0) d.robot_cfg.port = o.robot_port;
  if (d.with_robot && !d.robot_cfg.map.has_pose() && !d.robot_cfg.kinematics)
    throw error::FormatError({o.rig, 0, 0, "robot"}, "the register map reads joints only: the rig needs a robot DH table");
  return d;
}
}  // namespace

AcquireResult run_acquisition(const AcquireOptions& o, const std::function<void(const acquisition::SyncedSample&)>& observer) {
  RigDevices d = open_rig_devices(o);
  const auto& rig = d.rig;
  const auto& pcfg = d.plate_cfg;
  const auto& mcfg = d.robot_cfg;
  const bool with_robot = d.with_robot;

  format::RunInfo info;
  info.rig = rig.name;
  info.output_rate_hz = o.output_rate_hz;
  if (d.can()) info.sources.push_back({"force_plate", "can", pcfg.rate_hz, "raw/force_plate.candump.log"});
  else info.sources.push_back({"force_plate", d.source_kind(), pcfg.rate_hz, "raw/force_plate.csv"});
  if (with_robot) info.sources.push_back({"robot", "modbus", mcfg.rate_hz, "raw/robot.csv"});
  info.notes = o.play.empty() ? "Recorded by hil acquire." : "Recorded by hil acquire from the fake rig playing " + o.play + ".";
  const auto start_ns = acquisition::realtime_ns();
  acquisition::RunRecorder recorder(o.out, info, d.rig_text, start_ns, with_robot ? mcfg.map.joint_count() : 0);

  // Every CAN frame both ways, as candump -L, next to the readings (raw/force_plate.csv).
  drivers::CanLogChannel* can_log_ptr = nullptr;
  if (d.can()) {
    auto can_log = drivers::CanLogChannel::open_write(recorder.raw_path("force_plate.candump.log"),
                                                      drivers::CanLogOptions{pcfg.interface, false, 1.0, {}});
    can_log_ptr = can_log.get();
    d.channel = std::make_unique<drivers::CanRecordingChannel>(std::move(d.channel), std::move(can_log));
  }
  auto plate = d.make_plate();
  std::unique_ptr<drivers::RobotControllerDriver> robot;
  if (with_robot) robot = std::make_unique<drivers::RobotControllerDriver>(mcfg);

  std::unique_ptr<dds::Participant> bus;
  if (!o.no_bus) bus = std::make_unique<dds::Participant>(o.participant);
  acquisition::AcquirerOptions ao;
  ao.sync.wrench_rate_hz = pcfg.rate_hz;
  ao.sync.output_rate_hz = o.output_rate_hz;
  ao.T_world_base = d.T_world_base;
  ao.ros_topics = o.ros_topics;
  ao.sensor_best_effort = o.sensor_best_effort;
  ao.static_frames = format::static_frames(rig);        // rt/tf_static
  if (o.tf) ao.tf_moving = format::moving_frame(&rig);  // rt/tf
  ao.world_frame = rig.tf.world;
  ao.joint_names = format::joint_names(rig, with_robot ? mcfg.map.joint_count() : 0);
  ao.wait_for_subscribers = o.wait_subscribers;
  ao.rt_priority = o.rt_priority;
  // --mcap: run.mcap beside the CSV, from the same samples (docs/mcap.md). Made before the
  // acquirer so that it outlives it: the acquirer's last samples reach a sink still there.
  std::unique_ptr<acquisition::McapSink> mcap_sink;
  if (o.mcap)
    mcap_sink = std::make_unique<acquisition::McapSink>(recorder.dir() + "/run.mcap", rig, with_robot ? mcfg.map.joint_count() : 0,
                                                        start_ns, mcap::parse_compression(o.mcap_compression), o.tf);
  acquisition::Acquirer acq(ao, std::move(plate), std::move(robot), bus.get(), &recorder);
  if (observer) acq.on_sample(observer);
  if (mcap_sink) acq.on_sample([&mcap_sink](const acquisition::SyncedSample& s) { mcap_sink->sample(s); });

  d.start_fakes();
  acq.start();
  // What the devices said about themselves goes into run.yaml at once (crash-safe rewrite).
  recorder.set_source_identity("force_plate", acquisition::plate_identity(acq.plate_info()));
  if (with_robot) recorder.set_source_identity("robot", acquisition::robot_identity(mcfg, acq.robot_identity()));
  if (o.tare) acq.tare();
  std::signal(SIGINT, on_acquire_signal);
  std::signal(SIGTERM, on_acquire_signal);
  const double duration = o.duration_s > 0 ? o.duration_s : d.play_duration_s;
  const auto t0 = std::chrono::steady_clock::now();
  auto next_progress = t0 + std::chrono::seconds(5);
  auto next_flush = t0 + std::chrono::seconds(1);
  while (!g_stop) {
    const auto now = std::chrono::steady_clock::now();
    if (duration > 0 && now - t0 >= std::chrono::duration<double>(duration)) break;
    if (now >= next_flush) {  // the CAN log is written by the plate thread; FILE* locks make this safe
      if (can_log_ptr != nullptr) can_log_ptr->flush();
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
  d.stop_fakes();

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

int run_check(const AcquireOptions& o, std::ostream& out) {
  RigDevices d = open_rig_devices(o);
  d.start_fakes();
  bool ok = true;
  auto print_identity = [&](const acquisition::Identity& id) {
    for (const auto& [k, v] : id) out << fmt::format("  {:<18} {}\n", k, v);
  };
  // Polls until one reading arrives or `budget_s` passes: a device that is up answers within a
  // few periods; the budget covers a fake rig still starting and a slow first Modbus answer.
  auto first_reading = [](auto&& poll, double budget_s) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(budget_s);
    drivers::PollStatus st = drivers::PollStatus::timeout;
    while (std::chrono::steady_clock::now() < until) {
      st = poll();
      if (st == drivers::PollStatus::ok || st == drivers::PollStatus::closed) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return st;
  };

  if (o.scan) {
    if (d.plate_cfg.protocol != drivers::ForcePlateProtocol::ati_netcanoem) {
      ok = false;
      out << fmt::format("scan: only NETCANOEM boards answer a base-id scan; the rig's force plate is {}\n",
                         drivers::to_string(d.plate_cfg.protocol));
    } else {
      const auto boards = drivers::scan_netcanoem(*d.channel);
      out << fmt::format("scan: NETCANOEM base ids 0x00-0x7F on {}: {} board(s) answered\n", d.channel->name(), boards.size());
      bool rigs_found = false;
      for (const auto& b : boards) {
        out << fmt::format("  base id 0x{:02X} (ids 0x{:03X}-0x{:03X})  serial '{}'\n", b.base_id, b.base_id << 4, (b.base_id << 4) | 0xF,
                           b.serial);
        rigs_found = rigs_found || b.base_id == d.plate_cfg.base_id;
      }
      if (!boards.empty() && !rigs_found)
        out << fmt::format("  the rig file says base_id 0x{:02X}: set devices.force_plate.base_id to the board's\n", d.plate_cfg.base_id);
    }
  }
  if (d.plate_cfg.protocol == drivers::ForcePlateProtocol::ati_netcanoem)
    out << fmt::format("force plate (ATI NETCANOEM on {}, base id 0x{:02X}):\n", d.link(), d.plate_cfg.base_id);
  else out << fmt::format("force plate ({} on {}):\n", drivers::to_string(d.plate_cfg.protocol), d.link());
  auto plate = d.make_plate();
  try {
    print_identity(acquisition::plate_identity(plate->start()));
    drivers::WrenchSample w;
    const auto st = first_reading([&] { return plate->poll(w); }, 1.0);
    if (st == drivers::PollStatus::ok) {
      out << fmt::format("  {:<18} f [{:.3f}, {:.3f}, {:.3f}] N, m [{:.4f}, {:.4f}, {:.4f}] N m (plate frame, not tared)\n", "wrench",
                         w.w_fp[0], w.w_fp[1], w.w_fp[2], w.w_fp[3], w.w_fp[4], w.w_fp[5]);
      if (d.plate_cfg.protocol == drivers::ForcePlateProtocol::ati_netcanoem)
        out << fmt::format("  {:<18} [{}, {}, {}, {}, {}, {}]\n", "gauges", w.gauges[0], w.gauges[1], w.gauges[2], w.gauges[3], w.gauges[4],
                           w.gauges[5]);
      out << fmt::format("  {:<18} {}\n", "status", w.device_fault ? plate->describe_status(w) : "ok");
      if (w.device_fault) ok = false;
    } else {
      ok = false;
      out << fmt::format("  FAILED: no wrench within 1 s ({}{}{})\n", drivers::to_string(st), plate->last_problem().empty() ? "" : ": ",
                         plate->last_problem());
    }
  } catch (const std::exception& e) {
    ok = false;
    out << fmt::format("  FAILED: {}\n", e.what());
  }

  if (d.with_robot) {
    out << fmt::format("robot controller ({}, map {}):\n", d.robot_cfg.describe(), d.robot_cfg.map.name);
    try {
      drivers::RobotControllerDriver robot(d.robot_cfg);
      robot.connect();
      print_identity(acquisition::robot_identity(d.robot_cfg, robot.identify()));
      drivers::RobotSample r;
      const auto st = first_reading([&] { return robot.poll(r); }, 2.0);
      if (st == drivers::PollStatus::ok) {
        if (r.has_pose) {
          Eigen::Isometry3d T_base_tcp = Eigen::Isometry3d::Identity();
          T_base_tcp.linear() = r.q_base_tcp.toRotationMatrix();
          T_base_tcp.translation() = r.p_base_tcp_m;
          const Eigen::Isometry3d T_world_tcp = d.T_world_base * T_base_tcp;
          const Eigen::Quaterniond q(T_world_tcp.linear());
          const Eigen::Vector3d p = T_world_tcp.translation();
          out << fmt::format("  {:<18} p [{:.4f}, {:.4f}, {:.4f}] m, q [{:.4f}, {:.4f}, {:.4f}, {:.4f}] (wxyz, world{})\n", "pose", p.x(),
                             p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), r.pose_from_kinematics ? ", from the joints" : "");
        }
        std::string joints;
        for (unsigned j = 0; j < r.joint_count; ++j) joints += fmt::format("{}{:.4f}", j ? ", " : "", r.joints[j]);
        if (r.joint_count > 0) out << fmt::format("  {:<18} [{}] rad\n", "joints", joints);
        out << fmt::format("  {:<18} {:.2f} ms\n", "round trip", static_cast<double>(r.rtt_ns) * 1e-6);
      } else {
        ok = false;
        out << fmt::format("  FAILED: no reading within 2 s ({}{}{})\n", drivers::to_string(st), robot.last_problem().empty() ? "" : ": ",
                           robot.last_problem());
      }
    } catch (const std::exception& e) {
      ok = false;
      out << fmt::format("  FAILED: {}\n", e.what());
    }
  }
  d.stop_fakes();
  out << (ok ? "check passed\n" : "check failed\n");
  return ok ? 0 : 1;
}

}  // namespace hil::rig_service
