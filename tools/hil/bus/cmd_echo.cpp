// `hil echo TOPIC`: prints a topic live, one line per message.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <mutex>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>
#include <hil/error/error.hpp>

namespace hil::cli {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_echo_signal(int) { g_stop = true; }

struct EchoOptions {
  std::string topic;
  long count = 0;  // 0 = until Ctrl-C
  double timeout_s = 0.0;
};

std::string fmt_pws(const hil_msgs::msg::PoseWrenchSample& m) {
  const auto& p = m.pose_world_ee().position();
  const auto& f = m.wrench_fp().force();
  const auto& t = m.wrench_fp().torque();
  return fmt::format(
      "#{} t={:.4f} p=[{:.6f} {:.6f} {:.6f}] f=[{:.3f} {:.3f} {:.3f}] m=[{:.4f} {:.4f} {:.4f}] q={} ages={:.1f}/{:.1f} ms stamp={}.{:09}",
      m.sample_index(), m.t_s(), p.x(), p.y(), p.z(), f.x(), f.y(), f.z(), t.x(), t.y(), t.z(), m.quality_flags(), m.wrench_age_s() * 1e3,
      m.pose_age_s() * 1e3, m.header().stamp().sec(), m.header().stamp().nanosec());
}

std::string fmt_status(const hil_msgs::msg::DeviceStatus& m) {
  static const char* states[] = {"ok", "degraded", "fault", "disconnected"};
  return fmt::format("{} {} connected={} rate={:.1f} Hz age={:.1f} ms samples={} dropped={} errors={}{}", m.device(),
                     m.state() < 4 ? states[m.state()] : "?", m.connected(), m.rate_hz(), m.last_sample_age_s() * 1e3, m.samples(),
                     m.frames_dropped(), m.errors(), m.last_error().empty() ? "" : " last: " + m.last_error());
}

std::string fmt_contact(const hil_msgs::msg::ContactEstimate& m) {
  return fmt::format("t={:.3f} points={} K_inst={:.4g} mu_inst={:.3f} K={:.4g}+-{:.2g} mu={:.3f}+-{:.2g} n={} err={:.3f}", m.t_s(),
                     m.contact_points(), m.k_instant_n_per_m(), m.mu_instant(), m.k_global_n_per_m(), m.k_global_std(), m.mu_global(),
                     m.mu_global_std(), m.samples_used(), m.relative_force_error());
}

std::string fmt_stiffness(const hil_msgs::msg::StiffnessEstimate& m) {
  std::string s = fmt::format("configs={} rank={} params={}", m.configurations(), m.rank(), m.parameters().size());
  for (const auto& p : m.parameters()) s += fmt::format(" {}={:.4g}+-{:.2g}({})", p.name(), p.value(), p.std_dev(), p.identifiability());
  return s;
}

std::string fmt_measurement(const hil_msgs::msg::StiffnessMeasurement& m) {
  const auto& d = m.displacement_world_m();
  return fmt::format("config={} joints={} d=[{:.6g} {:.6g} {:.6g}]", m.config(), m.joints_rad().size(), d.x(), d.y(), d.z());
}

std::string fmt_tf(const tf2_msgs::msg::TFMessage& m) {
  std::string s = fmt::format("{} transforms", m.transforms().size());
  for (const auto& t : m.transforms()) {
    const auto& p = t.transform().translation();
    const auto& q = t.transform().rotation();
    s += fmt::format("\n  {} -> {} p=[{:.6g} {:.6g} {:.6g}] q=[{:.6g} {:.6g} {:.6g} {:.6g}]", t.header().frame_id(), t.child_frame_id(),
                     p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z());
  }
  return s;
}

std::string fmt_clock(const rosgraph_msgs::msg::Clock& m) { return fmt::format("{}.{:09}", m.clock().sec(), m.clock().nanosec()); }

std::string fmt_diagnostics(const diagnostic_msgs::msg::DiagnosticArray& m) {
  static const char* levels[] = {"OK", "WARN", "ERROR", "STALE"};
  std::string s;
  for (const auto& d : m.status()) {
    s += fmt::format("{}{} {} '{}' ({})", s.empty() ? "" : "\n", d.name(), d.level() < 4 ? levels[d.level()] : "?", d.message(),
                     d.hardware_id());
    for (const auto& kv : d.values()) s += fmt::format(" {}={}", kv.key(), kv.value());
  }
  return s;
}

template <class Msg>
int echo(dds::Participant& p, const std::string& topic, std::string (*show)(const Msg&), const EchoOptions& o,
         const dds::StreamQos& qos = {}) {
  std::atomic<long> n{0};
  std::mutex out;
  dds::Reader<Msg> reader(
      p, topic,
      [&](const Msg& m, const auto&) {
        std::lock_guard<std::mutex> lock(out);
        // The main loop looks at n only every 5 ms; a fast publisher delivers more than that.
        if (o.count && n >= o.count) return;
        std::cout << show(m) << '\n' << std::flush;
        ++n;
      },
      qos);
  const auto start = std::chrono::steady_clock::now();
  while (!g_stop && (o.count == 0 || n < o.count)) {
    if (o.timeout_s > 0 && std::chrono::steady_clock::now() - start > std::chrono::duration<double>(o.timeout_s)) {
      spdlog::warn("echo: {} messages on {} before the timeout", n.load(), topic);
      // A script waiting for a topic must be able to tell "nothing came" from success: without
      // --count the timeout ends a successful run only if something arrived.
      return o.count == 0 && n > 0 ? 0 : 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return 0;
}

std::string resolve(const std::string& t) {
  if (t.rfind("rt/", 0) == 0) return t;
  if (t == "pose_wrench") return dds::topics::kPoseWrenchSample;
  if (t == "device_status") return dds::topics::kDeviceStatus;
  if (t == "contact_estimate") return dds::topics::kContactEstimate;
  if (t == "stiffness_estimate") return dds::topics::kStiffnessEstimate;
  if (t == "stiffness_measurement") return dds::topics::kStiffnessMeasurement;
  if (t == "tf_static") return dds::topics::kTfStatic;
  if (t == "tf") return dds::topics::kTf;
  if (t == "clock") return dds::topics::kClock;
  if (t == "diagnostics") return dds::topics::kDiagnostics;
  return "rt/" + (t.front() == '/' ? t.substr(1) : t);
}

}  // namespace

void add_echo(CLI::App& app) {
  auto* cmd = app.add_subcommand("echo",
                                 "Print a bus topic live: pose_wrench, device_status, contact_estimate, "
                                 "stiffness_estimate, stiffness_measurement, tf_static, tf, clock, diagnostics (or its rt/... name)");
  static EchoOptions o;
  cmd->add_option("TOPIC", o.topic, "topic")->required();
  cmd->add_option("-n,--count", o.count, "stop after this many messages (0: until Ctrl-C)");
  cmd->add_option("--timeout", o.timeout_s,
                  "give up after this many seconds (0: never); exit 1 if fewer than --count messages (without --count: none) arrived");
  cmd->callback([] {
    set_action([] {
      std::signal(SIGINT, on_echo_signal);
      std::signal(SIGTERM, on_echo_signal);
      dds::Participant p(participant_options("hil-echo"));
      const auto topic = resolve(o.topic);
      if (topic == dds::topics::kPoseWrenchSample) return echo<hil_msgs::msg::PoseWrenchSample>(p, topic, fmt_pws, o);
      if (topic == dds::topics::kDeviceStatus) return echo<hil_msgs::msg::DeviceStatus>(p, topic, fmt_status, o);
      if (topic == dds::topics::kContactEstimate) return echo<hil_msgs::msg::ContactEstimate>(p, topic, fmt_contact, o);
      if (topic == dds::topics::kStiffnessEstimate) return echo<hil_msgs::msg::StiffnessEstimate>(p, topic, fmt_stiffness, o);
      if (topic == dds::topics::kStiffnessMeasurement) return echo<hil_msgs::msg::StiffnessMeasurement>(p, topic, fmt_measurement, o);
      // /tf_static is latched (transient local): a late echo still gets the tree.
      if (topic == dds::topics::kTfStatic) return echo<tf2_msgs::msg::TFMessage>(p, topic, fmt_tf, o, dds::StreamQos{true, 1, 1});
      if (topic == dds::topics::kTf) return echo<tf2_msgs::msg::TFMessage>(p, topic, fmt_tf, o, dds::StreamQos{true, 100, 0});
      // /clock is best effort, keep last 1 (rclcpp's ClockQoS).
      if (topic == dds::topics::kClock) return echo<rosgraph_msgs::msg::Clock>(p, topic, fmt_clock, o, dds::StreamQos{false, 1, 0});
      if (topic == dds::topics::kDiagnostics) return echo<diagnostic_msgs::msg::DiagnosticArray>(p, topic, fmt_diagnostics, o);
      throw error::FormatError({"command line", 0, 0, "TOPIC"},
                               "unknown topic '" + o.topic +
                                   "' (known: pose_wrench, device_status, contact_estimate, stiffness_estimate, "
                                   "stiffness_measurement, tf_static, tf, clock, diagnostics)");
    });
  });
}

}  // namespace hil::cli
