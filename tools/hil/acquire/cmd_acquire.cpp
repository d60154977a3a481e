// `hil acquire --rig RIG --out RUN`: the rig service. Polls the force plate (CAN) and the robot
// controller (Modbus), synchronizes, records the run and publishes it on the bus until Ctrl-C
// (or --duration). With --play RUN it first starts the fake rig in-process (loopback CAN and a
// Modbus server on 127.0.0.1) playing that run: the whole service without hardware or SocketCAN.
// The run itself is hil::rig_service::run_acquisition (shared with `hil demo`).
#include <fmt/format.h>

#include <iostream>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/rig_service/acquire.hpp>

namespace hil::cli {

using rig_service::AcquireOptions;
using rig_service::run_acquisition;
using rig_service::run_check;

void add_acquire(CLI::App& app) {
  auto* cmd = app.add_subcommand("acquire", "Acquire from the rig: record a run and publish it on the bus");
  static AcquireOptions o;
  cmd->add_option("--rig", o.rig, "rig file (devices section)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o.out, "run folder to create (required unless --check)");
  static bool check = false;
  cmd->add_flag("--check", check,
                "bring-up check: read each device's identity and one reading, print them and exit 0 (all answered) or 1; "
                "records nothing");
  cmd->add_flag("--scan", o.scan,
                "with --check: first ask every NETCANOEM base id 0x00-0x7F for its serial and list the boards that answer");
  cmd->add_option("--duration", o.duration_s, "seconds to acquire (default: until Ctrl-C, or the played run's length)");
  cmd->add_option("--output-rate", o.output_rate_hz, "output rate in Hz (must divide the force-plate rate)")->capture_default_str();
  cmd->add_option("--can-interface", o.can_interface, "SocketCAN interface (default: the rig's)");
  cmd->add_option("--robot-host", o.robot_host, "Modbus host (default: the rig's)");
  cmd->add_option("--robot-port", o.robot_port, "Modbus port (default: the rig's)");
  cmd->add_flag("--no-robot", o.no_robot, "acquire the force plate only");
  cmd->add_flag("--tare", o.tare, "tare the force plate at start");
  cmd->add_option("--wait-subscribers", o.wait_subscribers, "wait (up to 10 s) for this many PoseWrenchSample subscribers before starting");
  cmd->add_option("--rt-priority", o.rt_priority,
                  "run the device threads at this SCHED_FIFO priority (1-99) where permitted; 0: normal scheduling")
      ->check(CLI::Range(0, 99))
      ->capture_default_str();
  cmd->add_flag("!--no-ros-topics", o.ros_topics,
                "do not publish rt/hil/wrench, rt/hil/pose, rt/hil/joint_states, rt/tf_static, rt/tf, rt/diagnostics");
  static std::string sensor_qos = "reliable";
  cmd->add_option("--sensor-qos", sensor_qos,
                  "QoS of rt/hil/wrench, rt/hil/pose, rt/hil/joint_states and rt/tf: reliable (keep last 5000) or best-effort (keep "
                  "last 5, ROS 2's SensorDataQoS); rt/hil/pose_wrench stays reliable")
      ->check(CLI::IsMember({"reliable", "best-effort"}))
      ->capture_default_str()
      ->each([](const std::string& v) { o.sensor_best_effort = v == "best-effort"; });
  cmd->add_flag("!--no-tf", o.tf, "do not publish the moving robot base -> ee transform on rt/tf (nor /tf in run.mcap)");
  auto* play = cmd->add_option("--play", o.play, "start the fake rig in-process playing this run (no hardware, no SocketCAN)")
                   ->check(CLI::ExistingDirectory);
  cmd->add_flag("--mcap", o.mcap, "also record run.mcap in the run folder (ROS 2 channels, docs/mcap.md)");
  cmd->add_option("--mcap-compression", o.mcap_compression, "chunk compression of run.mcap: none, zstd or lz4")
      ->check(CLI::IsMember({"none", "zstd", "lz4"}))
      ->capture_default_str();
  cmd->add_option("--play-speed", o.play_speed, "playback speed of --play")->capture_default_str();
  cmd->add_flag("--play-loop", o.play_loop,
                "with --play: start the run again at its end (a soak); the acquisition ends at --duration or Ctrl-C")
      ->needs(play);
  cmd->add_flag("--play-on-can", o.play_over_socketcan,
                "with --play: the fake plate answers on the SocketCAN interface (e.g. vcan0) instead of an in-process bus");
  cmd->callback([] {
    if (!check && o.out.empty()) throw CLI::RequiredError("--out");
    set_action([] {
      if (!check && !o.no_bus) o.participant = participant_options("hil-acquire");
      if (check) return run_check(o, std::cout);
      const auto r = run_acquisition(o, nullptr);
      std::cout << fmt::format("recorded {} -> {}\n", r.summary, o.out);
      for (const auto& h : r.health)
        if (h.samples == 0) return 1;  // a device that never answered is a failed acquisition
      return 0;
    });
  });
}

}  // namespace hil::cli
