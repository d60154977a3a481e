// `hil contact worker`: the online contact worker (hil::services::ContactWorker) until Ctrl-C,
// a sample count or a duration.
#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/format/rig.hpp>
#include "contact_commands.hpp"
#include <hil/services/contact_worker.hpp>

namespace hil::cli {

using services::ContactWorker;

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct WorkerArgs {
  std::string rig;
  long count = 0;       ///< stop after this many samples (0: run until interrupted)
  double duration = 0;  ///< stop after this many seconds (0: no limit)
};

int worker(const WorkerArgs& a) {
  const auto rig = format::load_rig(a.rig);
  dds::Participant participant(participant_options("hil-contact-worker"));
  ContactWorker w(participant, rig);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto t0 = std::chrono::steady_clock::now();
  while (!g_stop && (a.count <= 0 || w.processed() < a.count) &&
         (a.duration <= 0 || std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < a.duration))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  w.flush();
  const auto e = w.global();
  std::cout << fmt::format("contact worker: {} samples, running global K = {:.5g} ± {:.3g} N/m, mu = {:.4g} ± {:.3g}\n", w.processed(), e.K,
                           e.K_std, e.mu, e.mu_std);
  return 0;
}
}  // namespace

void add_contact_worker(CLI::App& contact) {
  static WorkerArgs wa;
  auto* w = contact.add_subcommand("worker", "Online estimates: subscribe to PoseWrenchSample, publish ContactEstimate");
  w->add_option("--rig", wa.rig, "rig file (geometry, contact model, F_max/M_max)")->required();
  w->add_option("--count", wa.count, "stop after this many samples (0: until interrupted)")->capture_default_str();
  w->add_option("--duration", wa.duration, "stop after this many seconds (0: no limit)")->capture_default_str();
  w->callback([] { set_action([] { return worker(wa); }); });
}

}  // namespace hil::cli
