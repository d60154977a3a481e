// `hil replay RUN`: publishes a recording on the bus at its own pace or faster: hil's
// PoseWrenchSample and DeviceStatus, the standard topics (/hil/wrench, /hil/pose,
// /hil/joint_states, /tf_static, /tf) and with --clock the recording's time on /clock.
// RUN is an MCAP recording (hil acquire --mcap, hil export) or a run folder; a run folder is first
// written as the MCAP file `hil export` makes, so every path stamps each sample the same way.
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/qos.hpp>
#include <hil/dds/topics.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/mcap/recording.hpp>
#include <hil/messages/sample_msg.hpp>

namespace hil::cli {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_replay_signal(int) { g_stop = true; }

struct ReplayOptions {
  std::string run;
  std::string rig;
  double speed = 1.0;  // 0 = as fast as possible
  int wait_readers = 0;
  double wait_s = 10.0;
  bool clock = false;
  bool ros_topics = true;
};

/// A run folder as the MCAP file `hil export` writes, read back: written to a private temporary
/// file (removed before returning) so that a folder and its export cannot be replayed differently.
mcap::File run_as_recording(const std::string& dir, const std::string& rig) {
  const auto run = format::load_run(dir, rig);
  std::string path = (std::filesystem::temp_directory_path() / "hil-replay-XXXXXX").string();
  const int fd = ::mkstemp(path.data());
  if (fd < 0) throw std::runtime_error("replay: cannot create a temporary file in " + std::filesystem::temp_directory_path().string());
  ::close(fd);
  struct Remove {
    std::string p;
    ~Remove() { std::filesystem::remove(p); }
  } remove{path};
  mcap::RecordingOptions ro;
  ro.compression = mcap::Compression::none;
  mcap::export_run(run, path, ro);
  auto file = mcap::read_file(path);
  file.path = dir;
  return file;
}

/// One DDS writer per recorded topic hil knows; a message is decoded into the writer's type.
class Publisher {
 public:
  Publisher(dds::Participant& p, const ReplayOptions& o) : p_(p), ros_(o.ros_topics) {
    if (o.clock)
      clock_ = std::make_unique<dds::Writer<rosgraph_msgs::msg::Clock>>(p, dds::topics::kClock, dds::qos_of(dds::topics::kClock));
  }

  /// Publishes `m` of the recorded `topic` (m null: only makes its writer, so that subscribers can
  /// match before the first message). \returns false for a topic this replay does not publish.
  /// The QoS are those of the live writers (dds::qos_table()).
  bool publish(const std::string& topic, const mcap::Message* m, const std::string& where) {
    using namespace dds::topics;
    if (topic == mcap::topic::kPoseWrench) return send<hil_msgs::msg::PoseWrenchSample>(w_sample_, kPoseWrenchSample, m, where);
    if (topic == mcap::topic::kDeviceStatus) return send<hil_msgs::msg::DeviceStatus>(w_status_, kDeviceStatus, m, where);
    if (!ros_) return false;
    if (topic == mcap::topic::kWrench) return send<geometry_msgs::msg::WrenchStamped>(w_wrench_, kWrench, m, where);
    if (topic == mcap::topic::kPose) return send<geometry_msgs::msg::PoseStamped>(w_pose_, kPose, m, where);
    if (topic == mcap::topic::kJointStates) return send<sensor_msgs::msg::JointState>(w_joints_, kJointStates, m, where);
    if (topic == mcap::topic::kTfStatic) return send<tf2_msgs::msg::TFMessage>(w_tf_static_, kTfStatic, m, where);
    if (topic == mcap::topic::kTf) return send<tf2_msgs::msg::TFMessage>(w_tf_, kTf, m, where);
    return false;
  }

  void tick(std::uint64_t t_ns) {
    if (!clock_) return;
    rosgraph_msgs::msg::Clock c;
    c.clock(messages::to_time_ns(static_cast<std::int64_t>(t_ns)));
    clock_->write(c);
  }

  /// Waits for `n` readers of the samples (made before the first message for that).
  bool wait_for_readers(int n, std::chrono::milliseconds timeout) {
    send<hil_msgs::msg::PoseWrenchSample>(w_sample_, dds::topics::kPoseWrenchSample, nullptr, "");
    return w_sample_->wait_for_readers(n, timeout);
  }
  void wait_for_acknowledgments(std::chrono::seconds timeout) {
    if (w_sample_) w_sample_->wait_for_acknowledgments(timeout);
  }

 private:
  template <class Msg>
  bool send(std::unique_ptr<dds::Writer<Msg>>& w, const char* topic, const mcap::Message* m, const std::string& where) {
    if (denied_.count(topic)) return false;
    if (!w) {
      try {
        w = std::make_unique<dds::Writer<Msg>>(p_, topic, dds::qos_of(topic));
      } catch (const std::exception& e) {
        // The samples are what a replay is for; any other topic a secure participant may not
        // publish (its permissions name the topics) is left out, said once.
        if (std::string(topic) == dds::topics::kPoseWrenchSample) throw;
        spdlog::warn("replay: {} not published: {}", topic, e.what());
        denied_.insert(topic);
        return false;
      }
    }
    if (!m) return true;
    Msg msg;
    mcap::from_cdr(m->data, msg, where);
    if (!w->write(msg)) throw std::runtime_error(fmt::format("replay: DDS refused the message on {} ({})", topic, where));
    return true;
  }

  dds::Participant& p_;
  bool ros_;
  std::set<std::string> denied_;
  std::unique_ptr<dds::Writer<hil_msgs::msg::PoseWrenchSample>> w_sample_;
  std::unique_ptr<dds::Writer<hil_msgs::msg::DeviceStatus>> w_status_;
  std::unique_ptr<dds::Writer<geometry_msgs::msg::WrenchStamped>> w_wrench_;
  std::unique_ptr<dds::Writer<geometry_msgs::msg::PoseStamped>> w_pose_;
  std::unique_ptr<dds::Writer<sensor_msgs::msg::JointState>> w_joints_;
  std::unique_ptr<dds::Writer<tf2_msgs::msg::TFMessage>> w_tf_static_;
  std::unique_ptr<dds::Writer<tf2_msgs::msg::TFMessage>> w_tf_;
  std::unique_ptr<dds::Writer<rosgraph_msgs::msg::Clock>> clock_;
};

}  // namespace

int replay(const ReplayOptions& o) {
  const bool folder = std::filesystem::is_directory(o.run);
  if (!folder && !o.rig.empty())
    throw error::FormatError({"command line", 0, 0, "--rig"}, "--rig is for a run folder; an MCAP recording carries its frames");
  mcap::Recovery recovery;
  const auto file = folder ? run_as_recording(o.run, o.rig) : mcap::recover_file(o.run, recovery);
  if (!recovery.complete)
    spdlog::warn("{} was not closed or is damaged at its end: replaying the {} messages in its first {} chunks ({} of {} bytes); "
                 "reading stopped at {}",
                 o.run, recovery.messages, recovery.chunks, recovery.bytes_read, recovery.bytes_total, recovery.stopped);
  // Log-time order, file order among equal times (a sample's messages share its stamp).
  std::vector<const mcap::Message*> order;
  order.reserve(file.messages.size());
  for (const auto& m : file.messages) order.push_back(&m);
  std::stable_sort(order.begin(), order.end(), [](const auto* a, const auto* b) { return a->log_time_ns < b->log_time_ns; });
  std::map<std::uint16_t, std::string> topic_of;
  for (const auto& c : file.channels) topic_of[c.id] = c.topic;
  // The samples' channel checked as a hil recording's (encoding, schema, every payload).
  if (!recovery.complete && file.messages_on(mcap::topic::kPoseWrench).empty())
    throw error::FormatError({o.run, 0, 0, ""}, "nothing of it can be replayed: reading stopped at " + recovery.stopped);
  if (mcap::read_pose_wrench(file).empty())
    throw error::FormatError({o.run, 0, 0, ""}, fmt::format("the recording holds no {} message", mcap::topic::kPoseWrench));

  dds::Participant p(participant_options("hil-replay"));
  Publisher pub(p, o);
  for (const auto& c : file.channels) pub.publish(c.topic, nullptr, "");
  if (o.wait_readers > 0 && !pub.wait_for_readers(o.wait_readers, std::chrono::milliseconds(static_cast<long>(o.wait_s * 1e3))))
    throw std::runtime_error(fmt::format("replay: fewer than {} subscribers after {} s", o.wait_readers, o.wait_s));
  std::signal(SIGINT, on_replay_signal);
  const std::uint64_t t0 = order.front()->log_time_ns, t_end = order.back()->log_time_ns;
  spdlog::info("replaying {} messages ({:.1f} s) from {} at {}{}", order.size(), static_cast<double>(t_end - t0) * 1e-9, o.run,
               o.speed > 0 ? fmt::format("{}x", o.speed) : std::string("full speed"), o.clock ? ", /clock from the recording" : "");
  const auto start = std::chrono::steady_clock::now();
  std::map<std::string, std::size_t> sent, skipped;
  std::uint64_t last_tick = 0;
  bool ticked = false;
  for (std::size_t i = 0; i < order.size() && !g_stop; ++i) {
    const auto& m = *order[i];
    if (o.speed > 0)
      std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                std::chrono::duration<double>(static_cast<double>(m.log_time_ns - t0) * 1e-9 / o.speed)));
    // /clock first, once per instant: a use_sim_time node sees the time before the data stamped with it.
    if (!ticked || m.log_time_ns != last_tick) pub.tick(m.log_time_ns);
    ticked = true;
    last_tick = m.log_time_ns;
    const auto& topic = topic_of[m.channel_id];
    if (pub.publish(topic, &m, fmt::format("{}: message {} on {}", o.run, i, topic))) ++sent[topic];
    else ++skipped[topic];
  }
  if (o.wait_readers > 0) pub.wait_for_acknowledgments(std::chrono::seconds(10));
  std::string counts;
  for (const auto& [topic, n] : sent) counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", topic, n);
  for (const auto& [topic, n] : skipped) counts += fmt::format("; {} {} not published", topic, n);
  spdlog::info("replay: {} samples published ({})", sent[mcap::topic::kPoseWrench], counts);
  return 0;
}

void add_replay(CLI::App& app) {
  auto* cmd = app.add_subcommand("replay", "Publish a recording on the bus: hil's samples, the standard ROS topics and optionally /clock");
  static ReplayOptions o;
  cmd->add_option("RUN", o.run, "run folder, or an MCAP recording (.mcap)")->required()->check(CLI::ExistingPath);
  cmd->add_option("--rig", o.rig, "rig file for a run folder (default: its rig.yaml): the frames on /tf_static and /tf")
      ->check(CLI::ExistingFile);
  cmd->add_option("--speed", o.speed, "1 = real time, 10 = ten times faster, 0 = as fast as possible")->capture_default_str();
  cmd->add_option("--wait-subscribers", o.wait_readers,
                  "wait for this many PoseWrenchSample subscribers before starting, and for their acknowledgments at the end");
  cmd->add_option("--wait-timeout", o.wait_s, "seconds to wait for subscribers")->capture_default_str();
  cmd->add_flag("--clock", o.clock, "publish the recording's time on /clock (rosgraph_msgs/Clock) for nodes with use_sim_time");
  cmd->add_flag("!--no-ros-topics", o.ros_topics,
                "publish hil's own types only (rt/hil/pose_wrench, rt/hil/device_status), not the standard topics");
  cmd->callback([] { set_action([] { return replay(o); }); });
}

}  // namespace hil::cli
