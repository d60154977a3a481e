#pragma once
/// \file The rig service's core: polls the force plate and the robot controller on their own
/// threads, synchronizes, records and publishes, and watches device health.
///
/// Threads: one per device (each driver holds its own CAN channel or libmodbus context). Both push
/// into the Synchronizer under one mutex; outputs are recorded and published from the thread that
/// completed them. DeviceStatus goes out on every state change and every `status_period_s`.
/// Exceptions never leave a device thread: a failing poll is a status, counted and reported.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <hil/acquisition/monitor.hpp>
#include <hil/acquisition/recorder.hpp>
#include <hil/acquisition/sync.hpp>
#include <hil/dds/bus.hpp>
#include <optional>

#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/robot_controller.hpp>
#include <hil/format/ros_frames.hpp>

namespace hil::acquisition {

struct AcquirerOptions {
  SyncConfig sync;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();  ///< robot base in world
  Eigen::Isometry3d T_tcp_ee = Eigen::Isometry3d::Identity();      ///< ee in the controller's tool frame
  double status_period_s = 1.0;
  /// start() waits (up to 10 s) for this many PoseWrenchSample subscribers before polling, so
  /// that they see the run from its first sample.
  int wait_for_subscribers = 0;
  /// Also publish rt/hil/wrench (every force-plate reading as it arrives: the low-latency live
  /// stream), rt/hil/pose and rt/hil/joint_states (at the output rate), the rig's fixed frames on
  /// rt/tf_static (once, kept for late joiners) and device health on rt/diagnostics (docs/ros.md).
  bool ros_topics = true;
  /// The sensor streams (rt/hil/wrench, rt/hil/pose, rt/hil/joint_states, rt/tf) best effort, keep
  /// last 5 (ROS 2's SensorDataQoS) instead of reliable (dds::qos_table()).
  bool sensor_best_effort = false;
  /// The rig's fixed frames (format::static_frames(rig)); none: nothing on rt/tf_static.
  std::vector<format::StaticFrame> static_frames;
  /// The moving edge (format::moving_frame(rig)) on rt/tf with every synchronized sample; none:
  /// nothing on rt/tf (`hil acquire --no-tf`).
  std::optional<format::MovingFrame> tf_moving;
  /// header.frame_id of rt/hil/pose: world's name on ROS topics (RigSpec::tf.world).
  std::string world_frame = "world";
  /// JointState names (format::joint_names(rig, n)); joints beyond these are named jK.
  std::vector<std::string> joint_names;
  /// SCHED_FIFO priority (1-99) for the two device threads; 0 = the normal scheduler. Where the
  /// process may not (no CAP_SYS_NICE, no RLIMIT_RTPRIO) the threads stay normal and a warning
  /// says why: acquisition never fails for it.
  int rt_priority = 0;
  std::string force_plate_name = "force_plate";
  std::string robot_name = "robot";
};

/// Raw per-device streams written next to the run (raw/force_plate.csv, raw/robot.csv).
class RawWriter;

class Acquirer {
 public:
  /// \param bus, recorder  not owned, may be null; must outlive the Acquirer.
  Acquirer(AcquirerOptions options, std::unique_ptr<drivers::ForcePlate> plate, std::unique_ptr<drivers::RobotControllerDriver> robot,
           dds::Participant* bus, RunRecorder* recorder);
  ~Acquirer();
  Acquirer(const Acquirer&) = delete;
  Acquirer& operator=(const Acquirer&) = delete;

  /// Starts the devices (ATI start-up reads, Modbus connect) and the threads.
  /// \throws drivers::DeviceError if a device cannot be started.
  void start();
  /// Stops the threads and flushes the synchronizer (pending samples go out). Idempotent.
  void stop();
  /// Software tare of the force plate (averages the next samples).
  void tare();

  /// Called for every synchronized sample (under the pipeline lock: keep it short).
  void on_sample(std::function<void(const SyncedSample&)> f);
  std::vector<DeviceHealth> health() const;
  std::uint64_t samples() const { return emitted_; }
  std::uint64_t status_messages() const { return status_sent_; }
  const drivers::ForcePlateInfo& plate_info() const { return plate_info_; }
  /// The controller's answer to Report Server ID at start (or why there was none).
  const drivers::ControllerIdentity& robot_identity() const { return robot_identity_; }
  /// CPU time (s) the two device threads used, pipeline work included; valid after stop().
  double device_threads_cpu_s() const { return cpu_ns_.load() * 1e-9; }
  /// How many device threads run at options.rt_priority (0 when not asked or not permitted).
  int rt_threads() const { return rt_threads_.load(); }

 private:
  void enter_rt(const char* device);
  void plate_loop();
  void robot_loop();
  void emit(const SyncedSample& s);
  void publish_wrench(const WrenchReading& r);
  void check_health(std::int64_t now_ns, bool periodic);
  void publish_status(const std::vector<DeviceHealth>& hs, std::int64_t now_ns);

  AcquirerOptions opt_;
  std::unique_ptr<drivers::ForcePlate> plate_;
  std::unique_ptr<drivers::RobotControllerDriver> robot_;
  dds::Participant* bus_;
  RunRecorder* recorder_;
  drivers::ForcePlateInfo plate_info_;
  drivers::ControllerIdentity robot_identity_;

  mutable std::mutex mutex_;  ///< guards sync_, monitors, writers, sinks
  Synchronizer sync_;
  DeviceMonitor plate_mon_, robot_mon_;
  StateLog plate_log_, robot_log_;          ///< which state changes reach the log (all reach the bus)
  drivers::DeviceCounters plate_counters_;  ///< the plate driver's counters after its last poll
  drivers::DeviceCounters robot_counters_;  ///< the robot driver's counters after its last poll
  std::unique_ptr<dds::Writer<hil_msgs::msg::PoseWrenchSample>> w_sample_;
  std::unique_ptr<dds::Writer<hil_msgs::msg::DeviceStatus>> w_status_;
  std::unique_ptr<dds::Writer<geometry_msgs::msg::WrenchStamped>> w_wrench_;
  std::unique_ptr<dds::Writer<geometry_msgs::msg::PoseStamped>> w_pose_;
  std::unique_ptr<dds::Writer<sensor_msgs::msg::JointState>> w_joints_;
  std::unique_ptr<dds::Writer<tf2_msgs::msg::TFMessage>> w_tf_static_;
  std::unique_ptr<dds::Writer<tf2_msgs::msg::TFMessage>> w_tf_;
  std::unique_ptr<dds::Writer<diagnostic_msgs::msg::DiagnosticArray>> w_diagnostics_;
  std::string plate_hardware_id_, robot_hardware_id_;  ///< set in start(), before the threads
  std::vector<std::function<void(const SyncedSample&)>> sinks_;
  std::unique_ptr<RawWriter> raw_;
  std::int64_t last_status_ns_ = 0;
  std::int64_t start_ns_ = 0;  ///< the run's t = 0
  std::uint64_t last_plate_drops_ = 0, last_robot_failures_ = 0;

  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> emitted_{0}, status_sent_{0};
  std::atomic<std::int64_t> cpu_ns_{0};
  std::atomic<int> rt_threads_{0};
  std::thread plate_thread_, robot_thread_;
};

}  // namespace hil::acquisition
