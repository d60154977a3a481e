// `hil replay RUN`: publishes a recorded run as PoseWrenchSample, at its own pace or faster.
// RUN may also be an MCAP recording (hil acquire --mcap, hil export): its /hil/pose_wrench channel.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <csignal>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/mcap/recording.hpp>

namespace hil::cli {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_replay_signal(int) { g_stop = true; }

struct ReplayOptions {
  std::string run;
  double speed = 1.0;  // 0 = as fast as possible
  int wait_readers = 0;
  double wait_s = 10.0;
};
}  // namespace

/// The messages to publish: a run folder's samples, or an MCAP recording's /hil/pose_wrench.
std::vector<hil_msgs::msg::PoseWrenchSample> load_samples(const std::string& path) {
  std::vector<hil_msgs::msg::PoseWrenchSample> out;
  if (std::filesystem::is_regular_file(path)) {
    out = mcap::read_pose_wrench(mcap::read_file(path));
    if (out.empty()) throw error::FormatError({path, 0, 0, ""}, "the recording holds no /hil/pose_wrench message");
    return out;
  }
  const auto run = format::load_run(path);
  for (std::size_t i = 0; i < run.samples.size(); ++i)
    out.push_back(messages::to_message(run.samples.samples[i], i, run.samples.joints_rad.row(static_cast<Eigen::Index>(i))));
  return out;
}

int replay(const ReplayOptions& o) {
  const auto samples = load_samples(o.run);
  dds::Participant p(participant_options("hil-replay"));
  dds::Writer<hil_msgs::msg::PoseWrenchSample> w(p, dds::topics::kPoseWrenchSample);
  if (o.wait_readers > 0 && !w.wait_for_readers(o.wait_readers, std::chrono::milliseconds(static_cast<long>(o.wait_s * 1e3))))
    throw std::runtime_error(fmt::format("replay: fewer than {} subscribers after {} s", o.wait_readers, o.wait_s));
  std::signal(SIGINT, on_replay_signal);
  spdlog::info("replaying {} samples ({:.1f} s) from {} at {}", samples.size(), samples.back().t_s() - samples.front().t_s(), o.run,
               o.speed > 0 ? fmt::format("{}x", o.speed) : std::string("full speed"));
  const auto start = std::chrono::steady_clock::now();
  const double t0 = samples.front().t_s();
  std::size_t sent = 0;
  for (std::size_t i = 0; i < samples.size() && !g_stop; ++i) {
    if (o.speed > 0)
      std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                std::chrono::duration<double>((samples[i].t_s() - t0) / o.speed)));
    if (!w.write(samples[i])) throw std::runtime_error(fmt::format("replay: DDS refused sample {}", i));
    ++sent;
  }
  if (o.wait_readers > 0) w.wait_for_acknowledgments(std::chrono::seconds(10));
  spdlog::info("replay: {} samples published", sent);
  return 0;
}

void add_replay(CLI::App& app) {
  auto* cmd = app.add_subcommand("replay", "Publish a recorded run on the bus as PoseWrenchSample");
  static ReplayOptions o;
  cmd->add_option("RUN", o.run, "run folder, or an MCAP recording (.mcap)")->required()->check(CLI::ExistingPath);
  cmd->add_option("--speed", o.speed, "1 = real time, 10 = ten times faster, 0 = as fast as possible")->capture_default_str();
  cmd->add_option("--wait-subscribers", o.wait_readers,
                  "wait for this many subscribers before starting, and for their acknowledgments at the end");
  cmd->add_option("--wait-timeout", o.wait_s, "seconds to wait for subscribers")->capture_default_str();
  cmd->callback([] { set_action([] { return replay(o); }); });
}

}  // namespace hil::cli
