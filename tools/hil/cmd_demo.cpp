// `hil demo`: the README's main job. See the issue tracker: it grows into the whole pipeline
// (fake rig -> acquisition -> DDS -> online workers -> diagnosis) as those parts land.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <iostream>

#include "commands.hpp"
#include "hil/dds/bus.hpp"
#include "hil/dds/topics.hpp"
#include "hil/format/run.hpp"
#include "hil/acquisition/sample_msg.hpp"
#include "summary.hpp"

namespace hil::cli {

int demo(const std::string& run_dir) {
  std::cout << "hil demo: what exists so far runs on the shipped example run.\n"
               "  (the fake rig, acquisition, online workers and diagnosis join this demo as they are built)\n\n";
  std::cout << fmt::format("[1/3] validating {}\n", run_dir);
  const auto run = format::load_run(run_dir);
  print_run_summary(std::cout, run);

  std::cout << "\n[2/3] publishing the run as PoseWrenchSample on DDS (host-only profile) and subscribing to it\n";
  auto& g = globals();
  dds::Participant participant({g.dds_domain >= 0 ? g.dds_domain : dds::domain_from_env(), g.dds_profile,
                                g.dds_profile_name, "hil-demo"});
  std::atomic<std::size_t> received{0};
  std::atomic<double> max_error{0.0};
  dds::Reader<hil_msgs::msg::PoseWrenchSample> reader(
      participant, dds::topics::kPoseWrenchSample, [&](const hil_msgs::msg::PoseWrenchSample& m, const auto&) {
        const auto i = static_cast<std::size_t>(m.sample_index());
        if (i < run.samples.size()) {
          const double e = std::abs(m.wrench_fp().force().z() - run.samples.samples[i].f_fp_n.z());
          if (e > max_error) max_error = e;
        }
        ++received;
      });
  dds::Writer<hil_msgs::msg::PoseWrenchSample> writer(participant, dds::topics::kPoseWrenchSample);
  if (!writer.wait_for_readers(1, std::chrono::seconds(5))) throw std::runtime_error("DDS: the demo reader did not match");
  for (std::size_t i = 0; i < run.samples.size(); ++i) {
    writer.write(acquisition::to_message(run.samples.samples[i], i, run.samples.joints_rad.row(static_cast<Eigen::Index>(i))));
  }
  writer.wait_for_acknowledgments(std::chrono::seconds(5));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (received < run.samples.size() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::cout << fmt::format("  published {}, received {}, largest fz difference {:.3g} N\n", run.samples.size(),
                           received.load(), max_error.load());

  std::cout << "\n[3/3] done. Next: hil validate, and the issue tracker for what is still to come.\n";
  return received == run.samples.size() ? 0 : 1;
}

void add_demo(CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "Run the main job on the shipped example data");
  static std::string run_dir = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";
  cmd->add_option("--run", run_dir, "run folder to use")->capture_default_str();
  cmd->callback([] { set_action([] { return demo(run_dir); }); });
}

}  // namespace hil::cli
