// `hil demo`: the README's main job on shipped data, no hardware needed. The re-created ACU
// experiment of the contact paper (test 2a, examples/acu) is simulated with a hidden effect chosen
// by seed; the fake rig plays it (ATI plate on an in-process CAN bus, a Modbus robot controller on
// 127.0.0.1); the rig service acquires, records and publishes it on DDS while the online contact
// worker publishes estimates and a monitor watches the bus; the recording is checked against what
// was played, contact stiffness and friction are identified, and the diagnosis names what the
// nominal model gets wrong.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sstream>

#include <unistd.h>

#include <hil/rig_service/acquire.hpp>
#include <hil/services/contact_identify.hpp>
#include <hil/services/contact_simulate.hpp>
#include <hil/services/contact_worker.hpp>
#include <hil/services/diagnose_output.hpp>
#include <hil/services/diagnose_run.hpp>
#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include "data_dir.hpp"
#include <hil/acquisition/recorder.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>
#include <hil/diagnose/contact_family.hpp>
#include <hil/format/run.hpp>
#include "summary.hpp"

namespace hil::cli {

namespace contact = services::contact;
namespace diagnose = services::diagnose;
using rig_service::AcquireOptions;
using services::ContactWorker;
using rig_service::run_acquisition;
using services::contact::SimulateArgs;
using services::contact::simulate_run;
namespace {
struct DemoOptions {
  // Defaults from hil's data dir (data_dir.hpp); empty if it is missing, refused when run.
  std::string trajectory = data_file_or_empty("examples/acu/traj_2a.csv");
  std::string rig = data_file_or_empty("examples/acu/acu.yaml");
  int decimate = 20;  ///< the 1 kHz trajectory to the paper's 50 Hz
  std::string out;
  double speed = 1.0;
  unsigned seed = 1;
  std::string effect;  ///< empty: chosen by the seed
};
// The effects the demo hides. Not robot_compliance (taken for a nonlinear stiffness on this scene)
// nor contact_damping (through the acquisition chain, a damping of the drawn size is taken for a
// delay of the wrench: docs/diagnosis.md).
const std::vector<std::string> kDemoEffects{"sensor_bias", "geometric_offset",    "viscous_friction",
                                            "sensor_gain", "nonlinear_stiffness", "time_offset"};
}  // namespace

int demo(const DemoOptions& o) {
  namespace fs = std::filesystem;
  const std::string out =
      o.out.empty() ? (fs::temp_directory_path() / "hil-demo" / fmt::format("run-{}", acquisition::realtime_ns() / 1'000'000)).string()
                    : o.out;
  const std::string effect = o.effect.empty() ? kDemoEffects[o.seed % kDemoEffects.size()] : o.effect;
  std::cout << "hil demo: the re-created ACU experiment (contact paper, test 2a) with a hidden effect goes through the\n"
               "  fake rig, acquisition and DDS; the contact worker estimates online, the recording is identified,\n"
               "  and the diagnosis names what the nominal contact model gets wrong.\n\n";

  // 1. The played run: the rig's contact scene along the trajectory, with the hidden effect.
  const std::string played_dir = out + "-played", truth_file = out + "-hidden-truth.json";
  std::cout << fmt::format("[1/6] simulating {} on {} with a hidden effect (seed {})\n      ", o.trajectory, o.rig, o.seed);
  SimulateArgs sa;
  sa.rig = o.rig;
  sa.trajectory = o.trajectory;
  sa.out = played_dir;
  sa.decimate = o.decimate;
  // The paper's sensor (1.5 N, 0.05 N m steps) with noise; 2 µm poses.
  sa.force_resolution = 1.5;
  sa.force_noise = 0.3;
  sa.moment_resolution = 0.05;
  sa.moment_noise = 0.02;
  sa.position_resolution = 2e-6;
  sa.velocity_resolution = 2e-5;
  sa.seed = static_cast<int>(o.seed);
  sa.inject = {effect};
  sa.effect_seed = o.seed;
  sa.truth_out = truth_file;
  fs::create_directories(fs::path(out).parent_path());
  simulate_run(sa);
  const auto played = format::load_run(played_dir);

  // A partition of its own (unless --dds-partition names one): another participant on the domain
  // (a second demo, a replay) cannot add to what the demo counts, nor take its samples.
  const std::string partition = globals().dds_partition.empty() ? fmt::format("hil-demo-{}", ::getpid()) : globals().dds_partition;
  auto in_partition = [&](const std::string& name) {
    auto po = participant_options(name);
    po.partition = partition;
    return po;
  };
  dds::Participant participant(in_partition("hil-demo-monitor"));
  std::atomic<std::uint64_t> bus_samples{0}, bus_status{0}, bus_estimates{0};
  dds::Reader<hil_msgs::msg::PoseWrenchSample> samples(participant, dds::topics::kPoseWrenchSample,
                                                       [&](const auto&, const auto&) { ++bus_samples; });
  dds::Reader<hil_msgs::msg::DeviceStatus> status(
      participant, dds::topics::kDeviceStatus, [&](const auto&, const auto&) { ++bus_status; }, dds::StreamQos{true, 0, 10});
  dds::Reader<hil_msgs::msg::ContactEstimate> estimates(participant, dds::topics::kContactEstimate,
                                                        [&](const auto&, const auto&) { ++bus_estimates; });
  ContactWorker worker(participant, *played.rig);

  std::cout << fmt::format("[2/6] acquiring from the fake rig (in-process CAN bus, Modbus on 127.0.0.1) into {}\n", out);
  std::cout << fmt::format("      on DDS domain {}, partition {} (watch: hil echo pose_wrench --dds-domain {} --dds-partition {})\n",
                           participant.domain_id(), partition, participant.domain_id(), partition);
  AcquireOptions ao;
  ao.rig = o.rig;
  ao.out = out;
  ao.play = played_dir;
  ao.play_speed = o.speed;
  ao.output_rate_hz = played.info.output_rate_hz;
  ao.progress = false;
  ao.participant = in_partition("hil-acquire");  // the monitor's domain, profile, security and partition
  ao.wait_subscribers = 1;                       // our own monitor sees the run from its first sample
  ao.mcap = true;                                // run.mcap beside the CSV: open it in Foxglove or PlotJuggler (docs/mcap.md)
  std::atomic<std::uint64_t> n{0};
  const double total_s = played.samples.samples.back().t_s / o.speed;
  const auto t0 = std::chrono::steady_clock::now();
  // On a terminal one line redrawn in place; in a log file a plain line every 5 s, not one
  // 1,000-character line of carriage returns.
  const bool tty = isatty(STDOUT_FILENO) != 0;
  double next_line_s = 5.0;
  const auto result = run_acquisition(ao, [&](const acquisition::SyncedSample&) {
    const auto i = ++n;
    if (i % 25 != 0) return;
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto line = fmt::format("      {:5.1f} / {:.1f} s, {} samples, {} seen on the bus, {} contact estimates", el, total_s, i,
                                  bus_samples.load(), bus_estimates.load());
    if (tty) {
      std::cout << '\r' << line << std::flush;
    } else if (el >= next_line_s) {
      std::cout << line << '\n' << std::flush;
      next_line_s += 5.0;
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  worker.flush();
  const auto online = worker.global();
  std::cout << (tty ? "\n" : "")
            << fmt::format("      {}\n      bus: {} PoseWrenchSample, {} DeviceStatus, {} ContactEstimate messages received\n"
                           "      online worker: {} samples, running K = {:.4g} N/m, mu = {:.3f}\n",
                           result.summary, bus_samples.load(), bus_status.load(), bus_estimates.load(), worker.processed(), online.K,
                           online.mu);

  std::cout << fmt::format("[3/6] checking the recorded run {}\n", out);
  const auto rec = format::load_run(out);
  print_samples_summary(std::cout, rec.samples);
  double fz_rec = 0, fz_played = 0;
  for (const auto& s : rec.samples.samples) fz_rec = std::min(fz_rec, s.f_fp_n.z());
  for (const auto& s : played.samples.samples) fz_played = std::min(fz_played, s.f_fp_n.z());
  std::cout << fmt::format("      peak fz played {:.2f} N, recorded {:.2f} N\n", fz_played, fz_rec);

  std::cout << "[4/6] contact identification on the recorded run (K, mu by least squares, paper 2)\n";
  const auto problem = contact::problem_from_run(rec);
  contact::IdentifyOptions io;
  const auto ident = contact::identify(problem, io);
  const auto base = (fs::path(out).parent_path() / fs::path(out).filename()).string();
  contact::write_report(base + "-contact-report", fs::path(out).filename().string(), problem, ident);
  const auto& rig_contact = *rec.rig->model.contact;
  std::cout << fmt::format(
      "      K = {:.4g} +- {:.2g} N/m (rig: {:.4g}), mu = {:.3f} +- {:.2g} (rig: {:.3f}), mean relative force error {:.1f} %\n",
      ident.nominal.K, ident.nominal.K_std, rig_contact.stiffness_n_per_m, ident.nominal.mu, ident.nominal.mu_std,
      rig_contact.friction_coefficient, 100.0 * ident.nominal.relative_force_error);
  std::cout << "      report: " << (fs::path(base + "-contact-report") / "index.html").string() << "\n";

  std::cout << "[5/6] diagnosis of the recorded run (blind: it does not read the hidden truth)\n";
  diagnose::Options dopt;
  // Fold by fold on a terminal; one line per step in a log file.
  dopt.progress_detail = tty;
  dopt.progress = [tty](int step, int total, const std::string& what) {
    if (tty) std::cout << fmt::format("\r      [{}/{}] {:<80}", step, total, what) << std::flush;
    else std::cout << fmt::format("      [{}/{}] {}\n", step, total, what) << std::flush;
  };
  const auto diag = diagnose::diagnose_run(rec, dopt);
  if (tty) std::cout << "\r" << std::string(100, ' ') << "\r";
  std::ostringstream summary;
  diagnose::print_summary(summary, diag);
  std::istringstream lines(summary.str());
  for (std::string line; std::getline(lines, line);) std::cout << "      " << line << "\n";
  // The report marks the hidden truth beside the intervals; the diagnosis above never read it.
  diagnose::write_report(base + "-diagnosis", diag, diagnose::read_truth(truth_file, diag));
  std::cout << "      report: " << (fs::path(base + "-diagnosis") / "index.html").string() << "\n";

  const bool named = diag.result.cause == effect;
  std::cout << fmt::format("[6/6] the hidden effect was {} ({}): {}\n", effect, truth_file,
                           named ? "named by the diagnosis" : "NOT named by the diagnosis (" + diag.result.cause + ")");
  std::cout << "      Replay it with `hil replay " << out << "` and watch with `hil echo pose_wrench`.\n";
  std::cout << "      The recording as MCAP (Foxglove, PlotJuggler, ros2 bag): " << (fs::path(out) / "run.mcap").string() << "\n";
  const bool ok = rec.samples.size() > 0 && bus_samples == rec.samples.size() && std::abs(fz_rec - fz_played) < 5.0 &&
                  worker.processed() > 0 && named;
  if (!ok) std::cout << "demo: the bus, the recording, the played run or the diagnosis disagree (see above)\n";
  return ok ? 0 : 1;
}

void add_demo(CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "Run the main job on the shipped example data (no hardware needed)");
  static DemoOptions o;
  cmd->add_option("--trajectory", o.trajectory, "ee trajectory to simulate the run from")->capture_default_str();
  cmd->add_option("--rig", o.rig, "rig file (with a contact model)")->capture_default_str();
  cmd->add_option("--seed", o.seed, "chooses the hidden effect and its magnitude")->capture_default_str();
  cmd->add_option("--effect", o.effect, "hide this effect instead (a diagnosis candidate the generator can hide)")
      ->check(CLI::IsMember(hil::diagnose::injectable_contact_effects()));
  cmd->add_option("--out", o.out, "where to record (default: a new folder under the temp directory)");
  cmd->add_option("--speed", o.speed, "playback speed")->capture_default_str();
  cmd->add_option("--decimate", o.decimate, "keep every n-th trajectory sample")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->callback([] {
    set_action([] {
      if (o.trajectory.empty()) o.trajectory = data_file("examples/acu/traj_2a.csv").string();
      if (o.rig.empty()) o.rig = data_file("examples/acu/acu.yaml").string();
      return demo(o);
    });
  });
}

}  // namespace hil::cli
