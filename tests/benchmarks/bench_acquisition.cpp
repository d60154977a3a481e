// Pipeline throughput on one core: readings in, synchronized samples recorded and serialized out.
#include <benchmark/benchmark.h>

#include <filesystem>

#include <fastrtps/rtps/common/SerializedPayload.h>

#include <hil/acquisition/recorder.hpp>
#include <hil/messages/sample_msg.hpp>
#include <hil/acquisition/sync.hpp>

using namespace hil::acquisition;

namespace {

// One force-plate reading per iteration (1 kHz stream), a robot pose every 8th (125 Hz); every
// output sample is recorded (samples.csv) and built and serialized as a PoseWrenchSample.
void run_pipeline(benchmark::State& state, double output_rate_hz) {
  const auto dir = std::filesystem::temp_directory_path() / ("hil-bench-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  const std::int64_t t0 = 1'763'715'600'000'000'000;
  RunRecorder rec(dir.string(), {}, "", t0, 6);
  hil_msgs::msg::PoseWrenchSamplePubSubType ts;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(4096);
  std::uint64_t outputs = 0;
  Synchronizer sync({1000.0, output_rate_hz}, [&](const SyncedSample& s) {
    rec.append(s);
    auto m = hil::messages::to_message(to_row(s, static_cast<double>(s.t_ns - t0) * 1e-9), s.index, s.joints_rad.transpose());
    payload.length = 0;
    ts.serialize(&m, &payload);
    ++outputs;
  });
  std::int64_t i = 0;
  for (auto _ : state) {
    const std::int64_t t = t0 + i * 1'000'000;
    if (i % 8 == 0) {
      PoseReading p;
      p.t_ns = t;
      p.seq = static_cast<std::uint64_t>(i);
      p.p_world_ee_m = {1e-5 * static_cast<double>(i), 0.2, 0.3};
      p.joints_rad = Eigen::VectorXd::Constant(6, 0.1);
      sync.push_pose(p);
    }
    WrenchReading w;
    w.t_ns = t;
    w.seq = static_cast<std::uint64_t>(i);
    w.wrench_fp << 1, 2, -300 + 0.001 * static_cast<double>(i % 1000), 0.1, 0.2, 0.3;
    sync.push_wrench(w);
    ++i;
  }
  rec.close();
  state.SetItemsProcessed(state.iterations());
  state.counters["outputs"] = static_cast<double>(outputs);
  std::filesystem::remove_all(dir);
}

void BM_Pipeline_1kHzOut(benchmark::State& state) { run_pipeline(state, 1000.0); }
void BM_Pipeline_50HzOut(benchmark::State& state) { run_pipeline(state, 50.0); }
BENCHMARK(BM_Pipeline_1kHzOut);
BENCHMARK(BM_Pipeline_50HzOut);

}  // namespace
