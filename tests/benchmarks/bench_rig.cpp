// The rig service at a sustained rate, measured from outside: the fake rig plays the example run
// (looped) on an in-process CAN bus and a Modbus server on 127.0.0.1; the Acquirer records and
// publishes; a subscriber in ANOTHER process measures, for every rt/hil/wrench message, the time
// from the CAN receive stamp to its delivery, and checks that no PoseWrenchSample is lost.
// Prints latency p50/p99/max, the CPU share of the service's device threads and of the whole
// process (fakes included), and the loss count.
//
// --faults: the fault soak. Every fault kind the fakes can inject is switched on in turn (CAN frames
// dropped, corrupted, error frames, bus-off, a silent plate, late answers; Modbus exceptions,
// exception bursts, slow answers, a silent controller, late answers; the device clocks offset and
// drifting throughout), each for --fault-s seconds followed by as long without faults, while the run
// is recorded. Then every reading a device delivered is accounted for: the plate's intact answers
// (counted by the fake) = readings recorded in raw/force_plate.csv + answers the driver reported as
// late; raw rows = the driver's readings = rt/hil/wrench messages received in the other process;
// the controller's readings = raw/robot.csv rows; PoseWrenchSamples published = samples.csv rows =
// received, no index break. Exit status 4 when anything delivered is missing.
//
// --netft: the force plate is a Net F/T box streaming RDT over UDP on 127.0.0.1 (the fake box at
// 1 kHz) instead of the NETCANOEM board on the in-process CAN bus; latency is then from the UDP
// receive stamp (SO_TIMESTAMPNS). Not with --faults (the RDT faults are accounted in
// tests/drivers/test_netft.cpp and tests/acquisition/rig_service/test_netft_acquire.cpp).
//
// Usage: bench_rig [--seconds N] [--output-rate HZ] [--rt-priority P] [--faults] [--fault-s S] [--netft]
//   --faults runs whole cycles of the fault list: at least one, as many as fit in --seconds.
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include <hil/acquisition/acquirer.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/dds/topics.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/drivers/netft_driver.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/drivers_from_rig.hpp>

namespace {

struct ChildResult {
  std::uint64_t wrench_messages = 0, wrench_received = 0;
  double p50_us = 0, p99_us = 0, max_us = 0;
  std::uint64_t samples = 0, index_breaks = 0;
};

// Lines after the header of a CSV the recorder wrote.
std::uint64_t data_lines(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "bench_rig: cannot read %s\n", path.c_str());
    return 0;
  }
  std::string line;
  std::uint64_t n = 0;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    ++n;
  }
  return n;
}

// One fault kind: what each fake is switched to (t_rel_s: now, in the fakes' time, for windows).
struct FaultKind {
  std::string name;
  std::function<hil::drivers::CanFaults(double)> plate;
  std::function<hil::drivers::ModbusFaults(double)> robot;
};

std::vector<FaultKind> fault_kinds(double fault_s) {
  using hil::drivers::CanFaults;
  using hil::drivers::ModbusFaults;
  std::vector<FaultKind> k;
  k.push_back({"CAN frames dropped (20 %)",
               [](double) {
                 CanFaults f;
                 f.drop_fraction = 0.2;
                 return f;
               },
               nullptr});
  k.push_back({"CAN answers corrupted (20 %)",
               [](double) {
                 CanFaults f;
                 f.corrupt_fraction = 0.2;
                 return f;
               },
               nullptr});
  k.push_back({"CAN error frames (100/s, error passive)",
               [](double) {
                 CanFaults f;
                 f.error_frame_rate_hz = 100;
                 return f;
               },
               nullptr});
  k.push_back({"CAN bus-off",
               [fault_s](double t) {
                 CanFaults f;
                 f.bus_off.push_back({t, fault_s});
                 return f;
               },
               nullptr});
  k.push_back({"plate silent",
               [](double) {
                 CanFaults f;
                 f.silent_now = true;
                 return f;
               },
               nullptr});
  // Late, but inside the driver's 0.9-period timeout: every answer must still be recorded.
  k.push_back({"plate answers 0.3 ms late",
               [](double) {
                 CanFaults f;
                 f.extra_delay_s = 3e-4;
                 return f;
               },
               nullptr});
  k.push_back({"Modbus exceptions (20 %)", nullptr, [](double) {
                 ModbusFaults f;
                 f.exception_fraction = 0.2;
                 return f;
               }});
  k.push_back({"Modbus exception burst", nullptr, [fault_s](double t) {
                 ModbusFaults f;
                 f.exception_windows.push_back({t, fault_s});
                 return f;
               }});
  k.push_back({"Modbus slow answers (50 %, +20 ms)", nullptr, [](double) {
                 ModbusFaults f;
                 f.slow_fraction = 0.5;
                 f.slow_delay_s = 0.02;
                 return f;
               }});
  k.push_back({"controller silent", nullptr, [](double) {
                 ModbusFaults f;
                 f.silent_now = true;
                 return f;
               }});
  k.push_back({"controller answers 5 ms late", nullptr, [](double) {
                 ModbusFaults f;
                 f.extra_delay_s = 0.005;
                 return f;
               }});
  return k;
}

// Every reading delivered, followed from the device to the recording and the bus.
struct Accounts {
  std::uint64_t plate_delivered = 0, plate_readings = 0, plate_monitor = 0, plate_raw_rows = 0, plate_late_frames = 0, plate_bad_frames = 0,
                plate_timeouts = 0, plate_error_frames = 0;
  std::uint64_t robot_replies = 0, robot_readings = 0, robot_monitor = 0, robot_raw_rows = 0, robot_exceptions = 0, robot_timeouts = 0;
  std::uint64_t samples_rows = 0;

  // Prints the balance; false when something delivered is missing.
  bool report(std::uint64_t wrench_received, std::uint64_t published) const {
    bool ok = true;
    auto check = [&ok](bool c, const char* what) {
      if (!c) {
        std::printf("  LOST: %s\n", what);
        ok = false;
      }
    };
    // An intact answer that reached the driver after its poll gave up (timeout, or an error frame
    // ended the poll) is not a reading: the driver reports at least one of its frames as late.
    std::printf("force plate: delivered intact %llu, recorded %llu, the other %llu reported late (%llu late frames in all); "
                "driver readings %llu, monitor %llu, rt/hil/wrench received %llu; timeouts %llu, bad frames %llu, "
                "error frames %llu\n",
                ull(plate_delivered), ull(plate_raw_rows), ull(plate_delivered - std::min(plate_delivered, plate_raw_rows)),
                ull(plate_late_frames), ull(plate_readings), ull(plate_monitor), ull(wrench_received), ull(plate_timeouts),
                ull(plate_bad_frames), ull(plate_error_frames));
    check(plate_raw_rows == plate_readings && plate_monitor == plate_readings, "plate readings not all recorded");
    check(plate_readings <= plate_delivered && plate_delivered <= plate_readings + plate_late_frames,
          "plate answers delivered but neither recorded nor reported late");
    check(wrench_received == plate_readings, "plate readings not all received on rt/hil/wrench");
    std::printf("robot controller: readings %llu = raw rows %llu = monitor %llu (replies served %llu, exceptions %llu, "
                "timeouts %llu)\n",
                ull(robot_readings), ull(robot_raw_rows), ull(robot_monitor), ull(robot_replies), ull(robot_exceptions),
                ull(robot_timeouts));
    check(robot_raw_rows == robot_readings && robot_monitor == robot_readings && robot_readings > 0,
          "controller readings not all recorded");
    check(robot_readings <= robot_replies, "more controller readings than replies served");
    std::printf("PoseWrenchSample: published %llu = samples.csv rows %llu\n", ull(published), ull(samples_rows));
    check(samples_rows == published, "synchronized samples not all in samples.csv");
    std::printf("accounting: %s\n", ok ? "nothing delivered was lost" : "LOSS");
    return ok;
  }
  static unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }
};

std::shared_ptr<const hil::drivers::Scenario> scenario() {
  const auto run = hil::format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  return std::make_shared<const hil::drivers::Scenario>(hil::rig_service::scenario_from_run(run, Eigen::Isometry3d::Identity(), true));
}

// SCHED_FIFO at `priority` for the calling thread and the threads it starts from now on (they
// inherit it); SCHED_OTHER when 0. False when not permitted.
bool set_fifo(int priority) {
  sched_param sp{};
  sp.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), priority > 0 ? SCHED_FIFO : SCHED_OTHER, &sp) == 0;
}

int subscriber(int domain, int done_fd, int result_fd, int rt_priority) {
  // With --rt-priority the monitor is real-time too (its Fast DDS threads inherit the policy): the
  // measured path ends in this process's shared-memory listener.
  if (rt_priority > 0 && !set_fifo(rt_priority)) std::fprintf(stderr, "bench_rig: subscriber: real-time priority not permitted\n");
  hil::dds::Participant p({domain, "", "hil_localhost", "bench-subscriber"});
  std::mutex m;
  std::vector<double> latency_us;
  latency_us.reserve(1 << 20);
  ChildResult r;
  std::int64_t last_index = -1;
  hil::dds::Reader<geometry_msgs::msg::WrenchStamped> wr(p, hil::dds::topics::kWrench, [&](const auto& msg, const auto&) {
    const auto now = hil::acquisition::realtime_ns();
    const double stamp_s = hil::messages::from_time(msg.header().stamp());
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
  r.wrench_received = latency_us.size();
  if (!latency_us.empty()) {
    r.p50_us = latency_us[latency_us.size() / 2];
    r.p99_us = latency_us[std::min(latency_us.size() - 1, latency_us.size() * 99 / 100)];
    r.max_us = latency_us.back();
  }
  return write(result_fd, &r, sizeof r) == sizeof r ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10.0, output_rate = 1000.0, fault_s = 5.0;
  int rt_priority = 0;
  bool faults = false, netft = false;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--faults")) faults = true;
    else if (!std::strcmp(argv[i], "--netft")) netft = true;
    else if (has_value && !std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[++i]);
    else if (has_value && !std::strcmp(argv[i], "--output-rate")) output_rate = std::atof(argv[++i]);
    else if (has_value && !std::strcmp(argv[i], "--rt-priority")) rt_priority = std::atoi(argv[++i]);
    else if (has_value && !std::strcmp(argv[i], "--fault-s")) fault_s = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "bench_rig: unknown or incomplete argument '%s'\n", argv[i]);
      return 2;
    }
  }
  // The soak provokes thousands of device faults; their log lines say nothing the accounting
  // does not.
  if (faults) spdlog::set_level(spdlog::level::err);
  if (!(seconds > 0) || !(output_rate > 0) || !(fault_s > 0) || rt_priority < 0 || rt_priority > 99) {
    std::fprintf(stderr, "bench_rig: --seconds, --output-rate, --fault-s must be > 0 and --rt-priority 0..99\n");
    return 2;
  }
  // 90-99: no other test uses them (50-89 are the MCAP, time-base and interop tests').
  const int domain = 90 + static_cast<int>(getpid() % 10);
  int done[2], result[2];
  if (pipe(done) != 0 || pipe(result) != 0) return 1;
  const pid_t child = fork();
  if (child == 0) {
    close(done[1]);
    close(result[0]);
    _exit(subscriber(domain, done[0], result[1], rt_priority));
  }
  close(done[0]);
  close(result[1]);

  using namespace hil;
  auto sc = scenario();
  auto bus = drivers::CanLoopbackBus::create();
  drivers::FakeNetCanOemConfig pc;
  drivers::FakeRobotConfig rc;
  rc.map = drivers::float32_register_map();
  if (faults) {  // the clock faults hold throughout the soak
    pc.clock.drift_ppm = 150.0;
    pc.clock.offset_s = 0.004;
    rc.clock.drift_ppm = -80.0;
    rc.clock.offset_s = -0.003;
  }
  drivers::FakeNetCanOemBoard fake_plate(pc, bus->open(), sc);
  std::unique_ptr<drivers::FakeNetFtRdt> fake_netft;
  drivers::ForcePlateConfig netft_cfg;
  if (netft) {
    if (faults) {
      std::fprintf(stderr, "bench_rig: --netft runs without --faults\n");
      return 2;
    }
    fake_netft = std::make_unique<drivers::FakeNetFtRdt>(drivers::FakeNetFtConfig{}, sc);
    netft_cfg.protocol = drivers::ForcePlateProtocol::ati_netft_rdt;
    netft_cfg.host = "127.0.0.1";
    netft_cfg.port = fake_netft->port();
    netft_cfg.netft_calibration = drivers::FakeNetFtConfig{}.calibration;
  }
  drivers::FakeRobotController fake_robot(rc, sc);
  drivers::ModbusConfig mc;
  mc.port = fake_robot.port();
  mc.map = drivers::float32_register_map();
  hil::dds::Participant participant({domain, "", "hil_localhost", "bench-acquire"});
  const auto dir = std::filesystem::temp_directory_path() / ("hil-bench-rig-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::uint64_t samples = 0;
  double device_cpu_s = 0, process_cpu_s = 0;
  int rt_threads = 0;
  Accounts acc;
  std::vector<std::string> fault_log;
  {
    acquisition::RunRecorder rec(dir.string(), {}, "", acquisition::realtime_ns(), 6);
    acquisition::AcquirerOptions ao;
    ao.sync.output_rate_hz = output_rate;
    ao.rt_priority = rt_priority;
    std::unique_ptr<drivers::ForcePlate> plate;
    if (netft) plate = std::make_unique<drivers::NetFtRdtDriver>(netft_cfg);
    else plate = drivers::make_force_plate({}, bus->open());
    auto robot = std::make_unique<drivers::RobotControllerDriver>(mc);
    const drivers::ForcePlate* plate_driver = plate.get();  // owned by acq below
    const drivers::RobotControllerDriver* robot_driver = robot.get();
    acquisition::Acquirer acq(ao, std::move(plate), std::move(robot), &participant, &rec);
    const auto fakes_t0 = std::chrono::steady_clock::now();
    // With --rt-priority the fakes answer at a priority above the device threads: they stand for
    // hardware, which answers on its own, and a device thread woken by the first frame of an answer
    // must not preempt the plate before it sends the second.
    if (rt_priority > 0 && !set_fifo(std::min(99, rt_priority + 1)))
      std::fprintf(stderr, "bench_rig: real-time priority not permitted for the fakes\n");
    if (fake_netft) fake_netft->start();
    else fake_plate.start();
    fake_robot.start();
    if (rt_priority > 0) set_fifo(0);
    std::this_thread::sleep_for(std::chrono::seconds(2));  // let the subscriber match first
    rusage ru0{};
    getrusage(RUSAGE_SELF, &ru0);
    acq.start();
    if (faults) {
      // Whole cycles of the fault list, as many as fit (at least one).
      const auto kinds = fault_kinds(fault_s);
      const double cycle_s = 2.0 * fault_s * static_cast<double>(kinds.size());
      const int cycles = std::max(1, static_cast<int>(seconds / cycle_s));
      seconds = cycles * cycle_s;
      for (int c = 0; c < cycles; ++c)
        for (const auto& k : kinds) {
          const double t_rel = std::chrono::duration<double>(std::chrono::steady_clock::now() - fakes_t0).count();
          if (k.plate) fake_plate.set_faults(k.plate(t_rel));
          if (k.robot) fake_robot.set_faults(k.robot(t_rel));
          if (c == 0) fault_log.push_back(k.name);
          std::this_thread::sleep_for(std::chrono::duration<double>(fault_s));
          fake_plate.set_faults({});
          fake_robot.set_faults({});
          std::this_thread::sleep_for(std::chrono::duration<double>(fault_s));
        }
      // Stop the devices first: every answer they deliver from here on reaches a running driver.
      fake_plate.stop();
      fake_robot.stop();
    } else {
      std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    }
    acq.stop();
    rusage ru1{};
    getrusage(RUSAGE_SELF, &ru1);
    auto secs = [](const timeval& tv) { return static_cast<double>(tv.tv_sec) + tv.tv_usec * 1e-6; };
    process_cpu_s = secs(ru1.ru_utime) + secs(ru1.ru_stime) - secs(ru0.ru_utime) - secs(ru0.ru_stime);
    device_cpu_s = acq.device_threads_cpu_s();
    samples = acq.samples();
    rt_threads = acq.rt_threads();
    fake_plate.stop();
    if (fake_netft) fake_netft->stop();
    fake_robot.stop();
    const auto ps = fake_plate.stats();
    acc.plate_delivered = ps.gauge_answers_delivered;
    acc.plate_readings = plate_driver->counters().samples;
    acc.plate_late_frames = plate_driver->counters().late_frames;
    acc.plate_bad_frames = plate_driver->counters().bad_frames;
    acc.plate_timeouts = plate_driver->counters().timeouts;
    acc.plate_error_frames = plate_driver->counters().error_frames;
    acc.robot_replies = fake_robot.stats().replies;
    acc.robot_readings = robot_driver->counters().samples;
    acc.robot_exceptions = robot_driver->counters().exceptions;
    acc.robot_timeouts = robot_driver->counters().timeouts;
    for (const auto& h : acq.health()) (h.device == ao.force_plate_name ? acc.plate_monitor : acc.robot_monitor) = h.samples;
    rec.close();
    acc.plate_raw_rows = data_lines(rec.raw_path("force_plate.csv"));
    acc.robot_raw_rows = data_lines(rec.raw_path("robot.csv"));
    acc.samples_rows = data_lines((dir / "samples.csv").string());
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
  std::printf("force plate %s\n", netft ? "Net F/T RDT on UDP 127.0.0.1 (1 kHz)" : "NETCANOEM on the in-process CAN bus (1 kHz)");
  std::printf("seconds %.1f, output rate %.0f Hz, device threads %s\n", seconds, output_rate,
              rt_priority == 0  ? "at normal priority"
              : rt_threads == 2 ? ("at SCHED_FIFO " + std::to_string(rt_priority)).c_str()
                                : "at normal priority (real-time not permitted)");
  std::printf("rt/hil/wrench receive->delivery (other process): n=%llu p50=%.1f us p99=%.1f us max=%.1f us\n",
              static_cast<unsigned long long>(r.wrench_messages), r.p50_us, r.p99_us, r.max_us);
  std::printf("PoseWrenchSample: published %llu, received %llu, lost %lld, index breaks %llu\n", static_cast<unsigned long long>(samples),
              static_cast<unsigned long long>(r.samples), static_cast<long long>(samples) - static_cast<long long>(r.samples),
              static_cast<unsigned long long>(r.index_breaks));
  std::printf("CPU: device threads %.1f %% of one core, whole process (fakes included) %.1f %%\n", 100.0 * device_cpu_s / seconds,
              100.0 * process_cpu_s / seconds);
  bool lost = r.samples != samples || r.index_breaks != 0 || samples == 0;
  if (faults) {
    std::printf("faults in turn (%.1f s each, then %.1f s without): ", fault_s, fault_s);
    for (std::size_t i = 0; i < fault_log.size(); ++i) std::printf("%s%s", i ? ", " : "", fault_log[i].c_str());
    std::printf("; clocks offset and drifting throughout\n");
    lost = !acc.report(r.wrench_received, samples) || lost;
  }
  return lost ? 4 : 0;
}
