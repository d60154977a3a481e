// Issue 29, item 2: do the online workers keep up with a 1 kHz bus on one core, in bounded memory,
// for an hour? Two parts (figures in docs/performance.md):
//
// numerics (--hour-s, default 3600): an hour of 1 kHz samples through the workers' numerics on
// this one thread, as fast as they go: the contact estimator (contact_id::OnlineEstimator) on the
// re-created ACU test 2a at 1 kHz (32 s), looped with its times continuing; the stiffness identifier (calibration::OnlineIdentifier, the
// physical set reduced online) on 1,000 simulated KR-270 configurations over and over, an estimate every 50 samples (the worker's
// --estimate-period-ms 50 at 1 kHz). Prints each part's CPU per sample (at 1 kHz a core has 1,000 us per sample) and the process's resident
// memory after every simulated 10 minutes: bounded means it stops growing once the buffers have reached their size.
//
// bus (--bus-s, default 20): the real workers on a Fast DDS participant (SHM + UDP on 127.0.0.1).
// The contact worker's PoseWrenchSamples come from the fake rig: `hil acquire --play` in-process
// (rig_service::run_acquisition: the fake NETCANOEM plate on a loopback CAN bus and the fake robot
// controller on Modbus/TCP at 127.0.0.1, both playing the ACU test 2a run looped, the drivers, the
// synchronisation at 1 kHz, the recording and the publishing). The stiffness worker's
// StiffnessMeasurements come from a publisher thread, one every millisecond: the rig has no source
// of them (a measurement is a posture, a load and a measured displacement, which a stiffness
// experiment writes). Counts published, processed and estimates received, the worst backlog of the
// stiffness worker, the process's CPU share (fakes, rig service, publisher, DDS and both workers)
// and resident memory at the start and the end.
//
// Usage: bench_workers [--hour-s S] [--bus-s S]   (0 leaves a part out)
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/online.hpp>
#include <hil/contact_id/online.hpp>
#include <hil/dds/topics.hpp>
#include <hil/format/rig.hpp>
#include <hil/rig_service/acquire.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/models/contact.hpp>
#include <hil/services/contact_worker.hpp>
#include <hil/services/stiffness_worker.hpp>
#include <hil/test/acu.hpp>

namespace hc = hil::calibration;
namespace cid = hil::contact_id;

namespace {

/// Resident memory of this process, KiB (/proc/self/status VmRSS).
long rss_kib() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// A physical-set identifier reduced online, as `hil stiffness worker` without --model builds it.
std::unique_ptr<hc::OnlineIdentifier> stiffness_identifier(const hc::VjmModel& model, const hc::NoiseModel& noise) {
  hc::PipelineOptions opt;
  std::vector<hc::ReductionLine> lines;
  return std::make_unique<hc::OnlineIdentifier>(model, hc::physical_reduction(model, opt, lines), hc::ParameterSet{}, Eigen::VectorXd(),
                                                noise, opt, true);
}

struct Stiffness {
  hc::VjmModel model{hc::kr270_like()};
  hc::NoiseModel noise{10e-6, 10e-6};
  std::vector<hc::Measurement> data;
  Stiffness() {
    hc::ExperimentPlan plan;
    plan.configurations = 1000;
    plan.moment_nm = 300.0;
    plan.seed = 2911;
    data = hc::simulate(model, hc::example_compliance(model), plan, noise);
  }
};

void numerics(double seconds, const cid::test::AcuRun& acu, const Stiffness& st) {
  const std::vector<cid::Measurement>& loop = acu.data;
  const auto n = static_cast<std::size_t>(seconds * 1000.0);
  const std::size_t block = 600'000;  // 10 minutes at 1 kHz
  cid::OnlineEstimator contact(acu.scene, acu.options.v_tm, acu.options.force_scale_n, acu.options.moment_scale_nm);
  auto stiffness = stiffness_identifier(st.model, st.noise);
  const double period = loop.back().t_s - loop.front().t_s + (loop[1].t_s - loop[0].t_s);
  std::printf("numerics: %zu samples (%.0f s at 1 kHz), one thread; RSS at start %ld KiB\n", n, seconds, rss_kib());
  std::printf("%10s %14s %14s %16s %18s %10s %12s\n", "minutes", "contact us/s.", "stiff. us/s.", "stiff. estimates", "full / re-verified",
              "RSS KiB", "K (N/m)");
  hc::OnlineIdentifier::ReductionStats before;
  double c_cpu = 0, s_cpu = 0, c_block = 0, s_block = 0;
  std::size_t estimates = 0;
  cid::OnlineEstimate last;
  for (std::size_t i = 0; i < n; ++i) {
    cid::Measurement m = loop[i % loop.size()];
    m.t_s += period * static_cast<double>(i / loop.size());
    double t0 = thread_cpu_s();
    last = contact.update(m);
    double t1 = thread_cpu_s();
    c_block += t1 - t0;
    stiffness->add(st.data[i % st.data.size()]);
    if (i % 50 == 49) {
      const auto e = stiffness->estimate();
      if (e.kept.empty()) std::fprintf(stderr, "numerics: an estimate with no parameter at sample %zu\n", i);
      ++estimates;
    }
    s_block += thread_cpu_s() - t1;
    if ((i + 1) % block == 0 || i + 1 == n) {
      const double k = static_cast<double>((i % block) + 1);
      // The reductions of this block's estimates: M4-M6 re-run in full, or the cached one re-verified.
      const auto& now = stiffness->reduction_stats();
      std::printf("%10.1f %14.2f %14.2f %16zu %8zu / %7zu %10ld %12.4g\n", static_cast<double>(i + 1) / 60000.0, 1e6 * c_block / k,
                  1e6 * s_block / k, estimates, now.full - before.full, now.verified - before.verified, rss_kib(), last.global.K);
      before = now;
      std::fflush(stdout);
      c_cpu += c_block, s_cpu += s_block, c_block = s_block = 0;
    }
  }
  std::printf("numerics: contact %.2f us/sample, stiffness %.2f us/sample (add + an estimate every 50): %.1f %% of one core at 1 kHz\n",
              1e6 * c_cpu / static_cast<double>(n), 1e6 * s_cpu / static_cast<double>(n),
              100.0 * (c_cpu + s_cpu) / (static_cast<double>(n) * 1e-3));
  std::fflush(stdout);
}

int bus(double seconds, const Stiffness& st) {
  namespace sv = hil::services;
  const auto rig = hil::format::load_rig(std::string(HIL_SOURCE_DIR) + "/examples/acu/acu.yaml");
  const int domain = 120 + static_cast<int>(getpid() % 60);
  hil::dds::Participant p({domain, "", "hil_localhost", "bench-workers"});
  sv::ContactWorker contact(p, rig);
  sv::stiffness::StiffnessWorker stiffness(p, stiffness_identifier(st.model, st.noise), std::chrono::milliseconds(50));
  std::atomic<long> contact_estimates{0}, stiffness_estimates{0};
  hil::dds::Reader<hil_msgs::msg::ContactEstimate> ce(p, hil::dds::topics::kContactEstimate,
                                                      [&](const hil_msgs::msg::ContactEstimate&, const auto&) { ++contact_estimates; });
  hil::dds::Reader<hil_msgs::msg::StiffnessEstimate> se(p, hil::dds::topics::kStiffnessEstimate,
                                                        [&](const hil_msgs::msg::StiffnessEstimate&, const auto&) {
                                                          ++stiffness_estimates;
                                                        });
  hil::dds::Writer<hil_msgs::msg::StiffnessMeasurement> mw(p, hil::dds::topics::kStiffnessMeasurement);
  if (!mw.wait_for_readers(1, std::chrono::seconds(10))) {
    std::fprintf(stderr, "bus: the stiffness worker's reader did not match\n");
    return 3;
  }
  const long rss0 = rss_kib();
  const double cpu0 = process_cpu_s();
  const auto n = static_cast<std::size_t>(seconds * 1000.0);
  // The fake rig, as `hil acquire --play examples/acu/runs/test_2a --duration S` with the run looped.
  hil::rig_service::AcquireOptions ao;
  ao.rig = std::string(HIL_SOURCE_DIR) + "/examples/acu/acu.yaml";
  ao.play = std::string(HIL_SOURCE_DIR) + "/examples/acu/runs/test_2a";
  ao.play_loop = true;
  ao.duration_s = seconds;
  ao.output_rate_hz = 1000.0;
  ao.progress = false;
  ao.wait_subscribers = 1;
  ao.participant = {domain, "", "hil_localhost", "bench-rig"};
  const auto out = std::filesystem::temp_directory_path() / ("hil-bench-workers-" + std::to_string(getpid()));
  std::filesystem::remove_all(out);
  ao.out = out.string();
  hil::rig_service::AcquireResult acquired;
  std::string rig_error;
  std::atomic<bool> rig_done{false}, done{false};
  std::thread fake_rig([&] {
    try {
      acquired = hil::rig_service::run_acquisition(ao, nullptr);
    } catch (const std::exception& e) {
      rig_error = e.what();
    }
    rig_done = true;
  });
  std::size_t published = 0;
  std::thread publisher([&] {
    auto next = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < n && !rig_done; ++i) {
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
      mw.write(sv::stiffness::to_message(st.data[i % st.data.size()]));
      ++published;
    }
    done = true;
  });
  const auto start = std::chrono::steady_clock::now();
  auto next_rss = start + std::chrono::seconds(60);
  while (!done || !rig_done || stiffness.processed() < published) {
    stiffness.spin(std::chrono::milliseconds(100));
    if (std::chrono::steady_clock::now() >= next_rss) {
      std::printf("bus: after %.0f s, RSS %ld KiB, contact worker %ld, stiffness worker %zu processed\n",
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), rss_kib(), contact.processed(),
                  stiffness.processed());
      std::fflush(stdout);
      next_rss += std::chrono::seconds(60);
    }
    if (std::chrono::steady_clock::now() - start > std::chrono::duration<double>(seconds + 30.0)) break;
  }
  publisher.join();
  fake_rig.join();
  stiffness.publish_pending();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = process_cpu_s() - cpu0;
  const auto wait_until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while ((contact.processed() < static_cast<long>(acquired.samples)) && std::chrono::steady_clock::now() < wait_until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  contact.flush();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  std::filesystem::remove_all(out);
  if (!rig_error.empty()) {
    std::fprintf(stderr, "bus: the fake rig failed: %s\n", rig_error.c_str());
    return 3;
  }
  std::printf("bus: the fake rig published %llu samples (%llu gaps) and the publisher %zu stiffness measurements, at 1 kHz over %.1f s\n",
              static_cast<unsigned long long>(acquired.samples), static_cast<unsigned long long>(acquired.gaps), published, wall);
  std::printf("bus: contact worker processed %ld, estimates received %ld\n", contact.processed(), contact_estimates.load());
  std::printf("bus: stiffness worker processed %zu, rejected %zu, estimates %zu (received %ld), worst backlog %zu measurements\n",
              stiffness.processed(), stiffness.rejected(), stiffness.estimates(), stiffness_estimates.load(), stiffness.max_backlog());
  std::printf("bus: process CPU %.1f s = %.1f %% of one core (fake rig, rig service, publisher, DDS, both workers); RSS %ld -> %ld KiB\n",
              cpu, 100.0 * cpu / wall, rss0, rss_kib());
  const bool kept_up = acquired.samples > 0 && contact.processed() == static_cast<long>(acquired.samples) &&
                       stiffness.processed() == published;
  std::printf("bus: %s\n", kept_up ? "every sample and measurement processed" : "SAMPLES MISSING");
  return kept_up ? 0 : 4;
}

}  // namespace

int main(int argc, char** argv) {
  double hour_s = 3600.0, bus_s = 20.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--hour-s" || a == "--bus-s") && i + 1 < argc) (a == "--hour-s" ? hour_s : bus_s) = std::stod(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_workers [--hour-s S] [--bus-s S]\n");
      return 2;
    }
  }
  spdlog::set_level(spdlog::level::warn);
  const auto acu = cid::test::acu_run("2a", 1);
  const Stiffness st;
  if (hour_s > 0) numerics(hour_s, acu, st);
  return bus_s > 0 ? bus(bus_s, st) : 0;
}
