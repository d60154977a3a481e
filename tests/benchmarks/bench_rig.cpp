// The rig service at a sustained rate, measured from outside: the fake rig plays the example run
// (looped) on an in-process CAN bus and a Modbus server on 127.0.0.1; the Acquirer records and
// publishes; a subscriber in ANOTHER process measures, for every rt/hil/wrench message, the time
// from the CAN receive stamp to its delivery, and checks that no PoseWrenchSample is lost.
// Prints latency p50/p99/max, the CPU share of the service's device threads and of the whole
// process (fakes included), and the loss count. Usage: bench_rig [--seconds N] [--output-rate HZ]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hil/acquisition/acquirer.hpp"
#include "hil/acquisition/sample_msg.hpp"
#include "hil/dds/topics.hpp"
#include "hil/drivers/fake_rig.hpp"
#include "hil/format/run.hpp"
#include "drivers_from_rig.hpp"

namespace {

struct ChildResult {
  std::uint64_t wrench_messages = 0;
  double p50_us = 0, p99_us = 0, max_us = 0;
  std::uint64_t samples = 0, index_breaks = 0;
};

std::shared_ptr<const hil::drivers::Scenario> scenario() {
  const auto run = hil::format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  return std::make_shared<const hil::drivers::Scenario>(hil::rig::scenario_from_run(run, Eigen::Isometry3d::Identity(), true));
}

int subscriber(int domain, int done_fd, int result_fd) {
  hil::dds::Participant p({domain, "", "hil_localhost", "bench-subscriber"});
  std::mutex m;
  std::vector<double> latency_us;
  latency_us.reserve(1 << 20);
  ChildResult r;
  std::int64_t last_index = -1;
  hil::dds::Reader<geometry_msgs::msg::WrenchStamped> wr(p, hil::dds::topics::kWrench, [&](const auto& msg, const auto&) {
    const auto now = hil::acquisition::realtime_ns();
    const double stamp_s = hil::acquisition::from_time(msg.header().stamp());
    std::lock_guard<std::mutex> lock(m);
    latency_us.push_back((static_cast<double>(now) * 1e-9 - stamp_s) * 1e6);
  });
  hil::dds::Reader<hil_msgs::msg::PoseWrenchSample> sr(p, hil::dds::topics::kPoseWrenchSample, [&](const auto& msg, const auto&) {
    std::lock_guard<std::mutex> lock(m);
    ++r.samples;
    if (static_cast<std::int64_t>(msg.sample_index()) != last_index + 1) ++r.index_breaks;
    last_index = static_cast<std::int64_t>(msg.sample_index());
  });
  char c;
  if (read(done_fd, &c, 1) != 1) return 2;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::lock_guard<std::mutex> lock(m);
  std::sort(latency_us.begin(), latency_us.end());
  r.wrench_messages = latency_us.size();
  if (!latency_us.empty()) {
    r.p50_us = latency_us[latency_us.size() / 2];
    r.p99_us = latency_us[std::min(latency_us.size() - 1, latency_us.size() * 99 / 100)];
    r.max_us = latency_us.back();
  }
  return write(result_fd, &r, sizeof r) == sizeof r ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10.0, output_rate = 1000.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--output-rate")) output_rate = std::atof(argv[i + 1]);
  }
  const int domain = 50 + static_cast<int>(getpid() % 50);
  int done[2], result[2];
  if (pipe(done) != 0 || pipe(result) != 0) return 1;
  const pid_t child = fork();
  if (child == 0) {
    close(done[1]);
    close(result[0]);
    _exit(subscriber(domain, done[0], result[1]));
  }
  close(done[0]);
  close(result[1]);

  using namespace hil;
  auto sc = scenario();
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeAtiForcePlate fake_plate(drivers::FakeAtiConfig{}, bus->open(), sc);
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  drivers::FakeRobotController fake_robot(rc, sc);
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  hil::dds::Participant participant({domain, "", "hil_localhost", "bench-acquire"});
  const auto dir = std::filesystem::temp_directory_path() / ("hil-bench-rig-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::uint64_t samples = 0;
  double device_cpu_s = 0, process_cpu_s = 0;
  {
    acquisition::RunRecorder rec(dir.string(), {}, "", acquisition::realtime_ns(), 6);
    acquisition::AcquirerOptions ao;
    ao.sync.output_rate_hz = output_rate;
    acquisition::Acquirer acq(ao, drivers::make_force_plate({}, bus->open()), std::make_unique<drivers::RobotControllerDriver>(mc),
                              &participant, &rec);
    fake_plate.start();
    fake_robot.start();
    std::this_thread::sleep_for(std::chrono::seconds(2));  // let the subscriber match first
    rusage ru0{};
    getrusage(RUSAGE_SELF, &ru0);
    acq.start();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    acq.stop();
    rusage ru1{};
    getrusage(RUSAGE_SELF, &ru1);
    auto secs = [](const timeval& tv) { return static_cast<double>(tv.tv_sec) + tv.tv_usec * 1e-6; };
    process_cpu_s = secs(ru1.ru_utime) + secs(ru1.ru_stime) - secs(ru0.ru_utime) - secs(ru0.ru_stime);
    device_cpu_s = acq.device_threads_cpu_s();
    samples = acq.samples();
    fake_plate.stop();
    fake_robot.stop();
  }
  std::filesystem::remove_all(dir);
  char c = 'x';
  if (write(done[1], &c, 1) != 1) return 1;
  ChildResult r{};
  const bool got = read(result[0], &r, sizeof r) == sizeof r;
  int status = 0;
  waitpid(child, &status, 0);
  if (!got) {
    std::fprintf(stderr, "bench_rig: the subscriber process failed\n");
    return 1;
  }
  std::printf("seconds %.1f, output rate %.0f Hz\n", seconds, output_rate);
  std::printf("rt/hil/wrench receive->delivery (other process): n=%llu p50=%.1f us p99=%.1f us max=%.1f us\n",
              static_cast<unsigned long long>(r.wrench_messages), r.p50_us, r.p99_us, r.max_us);
  std::printf("PoseWrenchSample: published %llu, received %llu, lost %lld, index breaks %llu\n",
              static_cast<unsigned long long>(samples), static_cast<unsigned long long>(r.samples),
              static_cast<long long>(samples) - static_cast<long long>(r.samples), static_cast<unsigned long long>(r.index_breaks));
  std::printf("CPU: device threads %.1f %% of one core, whole process (fakes included) %.1f %%\n", 100.0 * device_cpu_s / seconds,
              100.0 * process_cpu_s / seconds);
  const bool lost = r.samples != samples || r.index_breaks != 0 || samples == 0;
  return lost ? 4 : 0;
}
