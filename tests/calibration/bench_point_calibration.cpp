// Benchmark of issue 28 item 7 (figures in docs/performance.md): the whole point-calibration
// comparison — every candidate, leave one station out, the second cause — on 500 postures of a
// 7-joint arm measured from 3 stations. Target: under 10 s on the 2-core machine. The data come
// from the KDL-based generator of the tests (kdl_point_truth.cpp), with joint offsets and joint
// compliance hidden in them.
#include <benchmark/benchmark.h>

#include <random>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>

#include "kdl_point_truth.hpp"

namespace hc = hil::calibration;

namespace {

const std::string kArm7 = std::string(HIL_SOURCE_DIR) + "/examples/robots/arm7_like.urdf";

struct Fixture {
  hc::SerialRobot robot;
  std::vector<hc::PointObservation> obs;
  explicit Fixture(int postures) {
    robot = hil::models::to_serial_robot(hil::format::read_urdf_robot(kArm7, "base_link", "flange"));
    std::mt19937 rng(2811);
    hil::test::PointTruth t;
    for (int s = 0; s < 3; ++s) t.T_station_base.push_back(hil::test::random_station(rng, 3.0, 3.0));
    t.tool_point_m = Eigen::Vector3d(0.03, -0.02, 0.12);
    t.noise_m = 50e-6;
    t.joint_offset_rad = Eigen::VectorXd(7);
    t.joint_compliance = Eigen::VectorXd(7);
    for (int j = 0; j < 7; ++j) {
      t.joint_offset_rad[j] = std::uniform_real_distribution<double>(-2e-3, 2e-3)(rng);
      t.joint_compliance[j] = std::uniform_real_distribution<double>(1e-6, 5e-6)(rng);
    }
    std::vector<std::pair<double, double>> range;
    for (const auto& row : robot.joints) range.emplace_back(0.95 * row.lower, 0.95 * row.upper);
    for (const auto& s : hil::test::generate_points(kArm7, "base_link", "flange", t, postures, rng, range)) {
      hc::PointObservation p;
      p.q = s.q;
      p.station = s.station;
      p.p_station_m = s.p_station_m;
      obs.push_back(p);
    }
  }
};

void BM_PointComparison(benchmark::State& state) {
  const Fixture f(static_cast<int>(state.range(0)));
  hc::PointFitOptions opt;
  opt.threads = static_cast<int>(state.range(1));  // 0: every core
  std::string verdict;
  for (auto _ : state) {
    const auto c = hc::compare_point_candidates(f.robot, f.obs, 3, hc::point_candidates(), 0, opt);
    verdict = c.verdict;
    benchmark::DoNotOptimize(c.cause);
  }
  state.SetLabel(verdict);
}
BENCHMARK(BM_PointComparison)
    ->ArgNames({"postures", "threads"})
    ->Args({500, 1})
    ->Args({500, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_PointFitGeometric(benchmark::State& state) {
  const Fixture f(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(hc::fit_points(f.robot, f.obs, 3, {hc::PointCandidate::geometric}).rms_m);
}
BENCHMARK(BM_PointFitGeometric)->Arg(500)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
