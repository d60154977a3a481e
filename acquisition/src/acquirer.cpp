#include <hil/acquisition/acquirer.hpp>

#include <fcntl.h>
#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <cstring>

#include <hil/messages/ros_msgs.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/qos.hpp>
#include <hil/dds/topics.hpp>
#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/error.hpp>

namespace hil::acquisition {
// What the acquirer publishes, as the bus messages of formats/messages.
using messages::to_diagnostic_status;
using messages::to_joint_state;
using messages::to_message;
using messages::to_tf_message;
using messages::to_time_ns;

// Append-only CSV of each device's own readings, flushed with the run (whole lines per write).
class RawWriter {
 public:
  explicit RawWriter(const RunRecorder& rec) {
    plate_ = open(rec.raw_path("force_plate.csv"), "t_ns,seq,stamp,status_word,g0,g1,g2,g3,g4,g5,fx,fy,fz,mx,my,mz\n");
    robot_ = open(rec.raw_path("robot.csv"), "t_ns,rtt_ns,seq,px,py,pz,qw,qx,qy,qz,joints\n");
  }
  ~RawWriter() {
    flush();
    ::close(plate_);
    ::close(robot_);
  }
  void plate(const drivers::WrenchSample& s) {
    fmt::format_to(std::back_inserter(plate_buf_), "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", s.t_ns, s.sequence,
                   static_cast<int>(s.stamp), s.status_word, s.gauges[0], s.gauges[1], s.gauges[2], s.gauges[3], s.gauges[4], s.gauges[5],
                   s.w_fp[0], s.w_fp[1], s.w_fp[2], s.w_fp[3], s.w_fp[4], s.w_fp[5]);
  }
  void robot(const drivers::RobotSample& s, const Eigen::Isometry3d& T_world_ee) {
    const Eigen::Quaterniond q(T_world_ee.linear());
    const auto& p = T_world_ee.translation();
    fmt::format_to(std::back_inserter(robot_buf_), "{},{},{},{},{},{},{},{},{},{},", s.t_ns, s.rtt_ns, s.sequence, p.x(), p.y(), p.z(),
                   q.w(), q.x(), q.y(), q.z());
    for (unsigned j = 0; j < s.joint_count; ++j) fmt::format_to(std::back_inserter(robot_buf_), "{}{}", j ? " " : "", s.joints[j]);
    robot_buf_ += '\n';
  }
  void flush() {
    write_all(plate_, plate_buf_);
    write_all(robot_, robot_buf_);
  }

 private:
  static int open(const std::string& path, const char* header) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
    std::string h(header);
    write_all(fd, h);
    return fd;
  }
  static void write_all(int fd, std::string& buf) {
    std::size_t done = 0;
    while (done < buf.size()) {
      const auto n = ::write(fd, buf.data() + done, buf.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        spdlog::error("raw recording: write failed: {}", std::strerror(errno));
        break;
      }
      done += static_cast<std::size_t>(n);
    }
    buf.clear();
  }
  int plate_ = -1, robot_ = -1;
  std::string plate_buf_, robot_buf_;
};

namespace {

std::int64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

DeviceHealth merged(const DeviceHealth& h, const drivers::DeviceCounters& c) {
  DeviceHealth out = h;
  out.frames_dropped = std::max(out.frames_dropped, c.dropped_frames);
  out.device_faults = c.device_faults;
  return out;
}

hil_msgs::msg::DeviceStatus to_msg(const DeviceHealth& h, std::int64_t now_ns) {
  hil_msgs::msg::DeviceStatus m;
  m.stamp(to_time_ns(now_ns));
  m.device(h.device);
  m.state(static_cast<std::uint8_t>(h.state));
  m.connected(h.connected);
  m.rate_hz(h.rate_hz);
  m.last_sample_age_s(std::isfinite(h.last_sample_age_s) ? h.last_sample_age_s : -1.0);
  m.samples(h.samples);
  m.frames_dropped(h.frames_dropped);
  m.device_faults(h.device_faults);
  m.errors(h.errors);
  m.last_error(h.state == DeviceState::ok ? h.last_error : (h.reason.empty() ? h.last_error : h.reason));
  return m;
}

}  // namespace

Acquirer::Acquirer(AcquirerOptions options, std::unique_ptr<drivers::ForcePlate> plate,
                   std::unique_ptr<drivers::RobotControllerDriver> robot, dds::Participant* bus, RunRecorder* recorder)
    : opt_(std::move(options)), plate_(std::move(plate)), robot_(std::move(robot)), bus_(bus), recorder_(recorder),
      sync_(opt_.sync, [this](const SyncedSample& s) { emit(s); }), plate_mon_(opt_.force_plate_name, opt_.sync.wrench_rate_hz),
      robot_mon_(opt_.robot_name, robot_ ? robot_->config().rate_hz : 1.0) {
  if (!plate_) throw std::invalid_argument("acquirer: a force plate is required");
  if (bus_) {
    // Every writer's QoS from the one table (idl/src/qos.cpp, docs/ros.md).
    namespace tp = dds::topics;
    const auto qos = [this](const char* topic) { return dds::qos_of(topic, opt_.sensor_best_effort); };
    w_sample_ = std::make_unique<dds::Writer<hil_msgs::msg::PoseWrenchSample>>(*bus_, tp::kPoseWrenchSample, qos(tp::kPoseWrenchSample));
    w_status_ = std::make_unique<dds::Writer<hil_msgs::msg::DeviceStatus>>(*bus_, tp::kDeviceStatus, qos(tp::kDeviceStatus));
    if (opt_.ros_topics) {
      w_wrench_ = std::make_unique<dds::Writer<geometry_msgs::msg::WrenchStamped>>(*bus_, tp::kWrench, qos(tp::kWrench));
      w_pose_ = std::make_unique<dds::Writer<geometry_msgs::msg::PoseStamped>>(*bus_, tp::kPose, qos(tp::kPose));
      w_joints_ = std::make_unique<dds::Writer<sensor_msgs::msg::JointState>>(*bus_, tp::kJointStates, qos(tp::kJointStates));
      if (!opt_.static_frames.empty())
        w_tf_static_ = std::make_unique<dds::Writer<tf2_msgs::msg::TFMessage>>(*bus_, tp::kTfStatic, qos(tp::kTfStatic));
      if (opt_.tf_moving) w_tf_ = std::make_unique<dds::Writer<tf2_msgs::msg::TFMessage>>(*bus_, tp::kTf, qos(tp::kTf));
      w_diagnostics_ = std::make_unique<dds::Writer<diagnostic_msgs::msg::DiagnosticArray>>(*bus_, tp::kDiagnostics, qos(tp::kDiagnostics));
    }
  }
  if (recorder_) raw_ = std::make_unique<RawWriter>(*recorder_);
}

Acquirer::~Acquirer() { stop(); }

void Acquirer::on_sample(std::function<void(const SyncedSample&)> f) {
  std::lock_guard<std::mutex> lock(mutex_);
  sinks_.push_back(std::move(f));
}

void Acquirer::start() {
  start_ns_ = recorder_ ? recorder_->start_ns() : realtime_ns();
  plate_info_ = plate_->start();
  spdlog::info("force plate: {} serial '{}' firmware '{}' on {}", plate_info_.protocol, plate_info_.serial, plate_info_.firmware,
               plate_->link());
  if (robot_) {
    robot_->connect();
    robot_identity_ = robot_->identify();
    spdlog::info("robot controller: {}{}", robot_->config().describe(),
                 robot_identity_.answered ? ", server id " + std::to_string(robot_identity_.server_id) + " '" + robot_identity_.text + "'"
                                          : "");
  }
  plate_hardware_id_ = plate_info_.protocol + (plate_info_.serial.empty() ? "" : " serial " + plate_info_.serial) + " on " + plate_->link();
  if (robot_) robot_hardware_id_ = robot_->config().describe();
  if (w_tf_static_) w_tf_static_->write(to_tf_message(opt_.static_frames, to_time_ns(realtime_ns())));
  if (opt_.wait_for_subscribers > 0 && w_sample_ && !w_sample_->wait_for_readers(opt_.wait_for_subscribers, std::chrono::seconds(10)))
    spdlog::warn("acquire: fewer than {} subscribers after 10 s; starting anyway", opt_.wait_for_subscribers);
  running_ = true;
  plate_thread_ = std::thread([this] { plate_loop(); });
  if (robot_) robot_thread_ = std::thread([this] { robot_loop(); });
}

void Acquirer::stop() {
  if (!running_.exchange(false)) return;
  if (plate_thread_.joinable()) plate_thread_.join();
  if (robot_thread_.joinable()) robot_thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  sync_.flush();
  if (raw_) raw_->flush();
  if (recorder_) recorder_->flush();
  const auto now = realtime_ns();
  std::vector<DeviceHealth> last{merged(plate_mon_.health(now), plate_counters_)};
  if (robot_) last.push_back(merged(robot_mon_.health(now), robot_counters_));
  publish_status(last, now);
  // Subscribers get the last samples before the writers go away with this object.
  if (w_sample_) w_sample_->wait_for_acknowledgments(std::chrono::seconds(2));
  if (w_status_) w_status_->wait_for_acknowledgments(std::chrono::seconds(1));
  if (w_diagnostics_) w_diagnostics_->wait_for_acknowledgments(std::chrono::seconds(1));
}

void Acquirer::tare() { plate_->tare(); }

std::vector<DeviceHealth> Acquirer::health() const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = realtime_ns();
  std::vector<DeviceHealth> out{merged(plate_mon_.health(now), plate_counters_)};
  if (robot_) out.push_back(merged(robot_mon_.health(now), robot_counters_));
  return out;
}

void Acquirer::enter_rt(const char* device) {
  if (opt_.rt_priority <= 0) return;
  sched_param sp{};
  sp.sched_priority = opt_.rt_priority;
  const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (e == 0) {
    ++rt_threads_;
    spdlog::info("{}: device thread at real-time priority {} (SCHED_FIFO)", device, opt_.rt_priority);
  } else {
    spdlog::warn("{}: real-time priority {} not permitted ({}); the device thread runs at normal priority{}", device, opt_.rt_priority,
                 std::strerror(e), e == EPERM ? " (needs CAP_SYS_NICE or an RLIMIT_RTPRIO of at least the priority)" : "");
  }
}

void Acquirer::plate_loop() {
  enter_rt(opt_.force_plate_name.c_str());
  drivers::RatePacer pacer(plate_->config().rate_hz);
  drivers::WrenchSample s;
  bool refused = false;  // a Modbus plate (FT 300) refused polls since its last reading
  while (running_) {
    const auto st = plate_->poll(s);
    const auto now = realtime_ns();
    WrenchReading r;
    if (st == drivers::PollStatus::ok) {
      r.t_ns = s.t_ns != 0 ? s.t_ns : now;
      r.seq = s.sequence;
      r.wrench_fp = s.w_fp;
      if (s.saturated_axes || s.gauge_saturated) r.quality |= kWrenchSaturated;
      // The first reading after refusals marks the samples filtered across them, as a refused
      // robot poll marks the samples interpolated across it.
      if (s.device_fault || s.error_frames > 0 || refused) r.quality |= kDeviceFault;
      refused = false;
      // The live stream goes out first, outside the lock: the robot thread holds the lock while it
      // synchronises, records and publishes samples (a CSV flush among them), and a monitor's
      // wrench must not wait behind that. Only this thread uses the wrench writer.
      if (w_wrench_) publish_wrench(r);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      switch (st) {
        case drivers::PollStatus::ok: {
          if (r.quality & kDeviceFault) {
            plate_mon_.error(plate_->describe_fault(s), now);
          }
          plate_mon_.sample(r.t_ns);
          if (raw_) raw_->plate(s);
          sync_.push_wrench(r);
          break;
        }
        case drivers::PollStatus::timeout:
          // A request the plate did not answer in time: a lost reading. A longer silence is
          // seen by the monitor after a few periods.
          plate_mon_.dropped(1, now);
          break;
        case drivers::PollStatus::exception: refused = true; [[fallthrough]];
        case drivers::PollStatus::bad_frame:
        case drivers::PollStatus::bus_error:
          plate_mon_.error(fmt::format("{}: {}", drivers::to_string(st), plate_->last_problem()), now);
          break;
        case drivers::PollStatus::disconnected:
        case drivers::PollStatus::closed: plate_mon_.link(false, now); break;
      }
      // The driver's counters change in poll(), outside the lock: the other threads read this
      // copy, taken under it (TSan found health() and the robot thread reading them mid-poll).
      plate_counters_ = plate_->counters();
      const auto drops = plate_counters_.dropped_frames;
      if (drops > last_plate_drops_) plate_mon_.dropped(drops - last_plate_drops_, now);
      last_plate_drops_ = drops;
      check_health(now, true);
    }
    if (st == drivers::PollStatus::closed) break;
    // A device that pushes its readings is read as they come: poll() waits for the next one. A
    // failing poll waits out the period whatever the device (a CAN interface that is down fails at
    // once, and must not spin a core).
    if (plate_->paced() || st != drivers::PollStatus::ok) pacer.wait();
  }
  cpu_ns_ += thread_cpu_ns();
}

void Acquirer::robot_loop() {
  enter_rt(opt_.robot_name.c_str());
  drivers::RatePacer pacer(robot_->config().rate_hz);
  drivers::RobotSample s;
  Eigen::VectorXd q;
  while (running_) {
    const auto st = robot_->poll(s);
    const auto now = realtime_ns();
    // Pose outside the lock.
    PoseReading r;
    Eigen::Isometry3d T_world_ee = Eigen::Isometry3d::Identity();
    bool have_pose = false;
    if (st == drivers::PollStatus::ok) {
      q = Eigen::Map<const Eigen::VectorXd>(s.joints.data(), s.joint_count);
      if (s.has_pose) {  // read from the controller, or from the joints by the rig's DH chain
        Eigen::Isometry3d T_base_tcp = Eigen::Isometry3d::Identity();
        T_base_tcp.linear() = s.q_base_tcp.toRotationMatrix();
        T_base_tcp.translation() = s.p_base_tcp_m;
        T_world_ee = opt_.T_world_base * T_base_tcp * opt_.T_tcp_ee;
        have_pose = true;
      }
      r.t_ns = s.t_ns;
      r.rtt_ns = s.rtt_ns;
      r.seq = s.sequence;
      r.p_world_ee_m = T_world_ee.translation();
      r.q_world_ee = Eigen::Quaterniond(T_world_ee.linear()).normalized();
      r.joints_rad = q;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      switch (st) {
        case drivers::PollStatus::ok:
          if (!have_pose) {
            robot_mon_.error("the register map gives neither a tool pose nor joints with a DH table", now);
            break;
          }
          robot_mon_.sample(s.t_ns);
          if (raw_) raw_->robot(s, T_world_ee);
          sync_.push_pose(r);
          break;
        case drivers::PollStatus::timeout: break;
        case drivers::PollStatus::exception:
          // The controller answered and refused: its samples meanwhile are device faults.
          sync_.pose_refused();
          [[fallthrough]];
        case drivers::PollStatus::bad_frame:
        case drivers::PollStatus::bus_error:
          robot_mon_.error(fmt::format("{}: {}", drivers::to_string(st), robot_->last_problem()), now);
          break;
        case drivers::PollStatus::disconnected:
        case drivers::PollStatus::closed: robot_mon_.link(false, now); break;
      }
      robot_counters_ = robot_->counters();  // as plate_counters_: read by the other threads under the lock
      check_health(now, false);
    }
    pacer.wait();
  }
  cpu_ns_ += thread_cpu_ns();
}

void Acquirer::emit(const SyncedSample& s) {
  ++emitted_;
  for (auto& f : sinks_) f(s);
  if (recorder_) {
    recorder_->append(s);
    if (raw_ && s.index % 50 == 0) raw_->flush();
  }
  if (!w_sample_) return;
  // Header stamp: the sample's absolute time; t_s: since the run's start.
  auto m = to_message(to_row(s, static_cast<double>(s.t_ns) * 1e-9), s.index, s.joints_rad.transpose());
  m.header().stamp(to_time_ns(s.t_ns));
  m.t_s(static_cast<double>(s.t_ns - start_ns_) * 1e-9);
  m.wrench_seq(s.wrench_seq);
  m.pose_seq(s.pose_seq);
  m.wrench_age_s(s.wrench_age_s);
  m.pose_age_s(std::isfinite(s.pose_age_s) ? s.pose_age_s : -1.0);
  m.quality_flags(s.quality);
  w_sample_->write(m);
  if (w_pose_) {
    geometry_msgs::msg::PoseStamped p;
    p.header(m.header());
    p.header().frame_id(opt_.world_frame);
    p.pose(m.pose_world_ee());
    w_pose_->write(p);
    if (s.joints_rad.size() > 0) w_joints_->write(to_joint_state(m, opt_.joint_names));
  }
  if (w_tf_) {
    format::Pose T_world_ee;
    T_world_ee.translation_m = s.p_world_ee_m;
    T_world_ee.rotation = s.q_world_ee;
    w_tf_->write(to_tf_message({opt_.tf_moving->at(T_world_ee)}, m.header().stamp()));
  }
}

void Acquirer::publish_wrench(const WrenchReading& r) {
  // The live wrench stream: every reading as it arrives, stamped with its receive time, before
  // synchronisation (which waits for poses), so monitors see it with the least delay.
  geometry_msgs::msg::WrenchStamped w;
  w.header().stamp(to_time_ns(r.t_ns));
  w.header().frame_id("force_plate");
  auto& f = w.wrench().force();
  f.x(r.wrench_fp[0]), f.y(r.wrench_fp[1]), f.z(r.wrench_fp[2]);
  auto& t = w.wrench().torque();
  t.x(r.wrench_fp[3]), t.y(r.wrench_fp[4]), t.z(r.wrench_fp[5]);
  w_wrench_->write(w);
}

void Acquirer::check_health(std::int64_t now_ns, bool periodic) {
  const bool plate_changed = plate_mon_.update(now_ns);
  const bool robot_changed = robot_ && robot_mon_.update(now_ns);
  auto log_state = [](const DeviceMonitor& m, const std::string& device, int held_back) {
    const std::string more = held_back > 0 ? fmt::format(" [{} more state change(s) not logged]", held_back) : "";
    if (m.state() == DeviceState::ok) spdlog::info("{}: ok again{}", device, more);
    else spdlog::warn("{}: {} ({}){}", device, to_string(m.state()), m.reason(), more);
  };
  int held_back = 0;
  if (plate_changed) {
    const auto h = merged(plate_mon_.health(now_ns), plate_counters_);
    if (plate_log_.change(plate_mon_.state(), now_ns, held_back, plate_mon_.reason())) log_state(plate_mon_, h.device, held_back);
    publish_status({h}, now_ns);
  } else if (periodic && plate_log_.flush(now_ns, held_back, plate_mon_.state(), plate_mon_.reason())) {
    log_state(plate_mon_, opt_.force_plate_name, held_back);
  }
  if (robot_changed) {
    const auto h = merged(robot_mon_.health(now_ns), robot_counters_);
    if (robot_log_.change(robot_mon_.state(), now_ns, held_back, robot_mon_.reason())) log_state(robot_mon_, h.device, held_back);
    publish_status({h}, now_ns);
  } else if (robot_ && periodic && robot_log_.flush(now_ns, held_back, robot_mon_.state(), robot_mon_.reason())) {
    log_state(robot_mon_, opt_.robot_name, held_back);
  }
  if (periodic && now_ns - last_status_ns_ >= static_cast<std::int64_t>(opt_.status_period_s * 1e9)) {
    last_status_ns_ = now_ns;
    std::vector<DeviceHealth> all{merged(plate_mon_.health(now_ns), plate_counters_)};
    if (robot_) all.push_back(merged(robot_mon_.health(now_ns), robot_counters_));
    publish_status(all, now_ns);
    if (recorder_) recorder_->flush();
    if (raw_) raw_->flush();
  }
}

void Acquirer::publish_status(const std::vector<DeviceHealth>& hs, std::int64_t now_ns) {
  if (!w_status_) return;
  // Each device on hil's own topic, and the same statuses in one array on ROS's /diagnostics.
  diagnostic_msgs::msg::DiagnosticArray diag;
  diag.header().stamp(to_time_ns(now_ns));
  for (const auto& h : hs) {
    const auto m = to_msg(h, now_ns);
    w_status_->write(m);
    ++status_sent_;
    if (w_diagnostics_)
      diag.status().push_back(to_diagnostic_status(m, h.device == opt_.force_plate_name ? plate_hardware_id_ : robot_hardware_id_));
  }
  if (w_diagnostics_ && !diag.status().empty()) w_diagnostics_->write(diag);
}

}  // namespace hil::acquisition
