// Benchmarks of issue 4 (figures in docs/calibration.md):
//  * the full pipeline for 1,000 configurations (6-D measurements): complete model, reduction
//    M1-M6, identification and covariance; target < 200 ms on one core;
//  * the online update per new configuration (Givens QR update + estimate); target < 1 ms, also
//    when the physical model is reduced online (issue 29).
#include <benchmark/benchmark.h>

#include <memory>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/online.hpp>

namespace hc = hil::calibration;

namespace {

struct Fixture {
  hc::VjmModel model{hc::kr270_like()};
  std::vector<hc::Measurement> data;
  hc::NoiseModel noise{10e-6, 10e-6};
  explicit Fixture(int configs) {
    hc::ExperimentPlan plan;
    plan.configurations = configs;
    plan.moment_nm = 300.0;
    plan.seed = 2024;
    data = hc::simulate(model, hc::example_compliance(model), plan, noise);
  }
};

const Fixture& fixture1000() {
  static const Fixture f(1000);
  return f;
}

void BM_FullPipeline(benchmark::State& state) {
  const Fixture& f = fixture1000();
  hc::PipelineOptions opt;
  opt.complete_ranks = state.range(0) != 0;
  std::size_t kept = 0;
  for (auto _ : state) {
    const auto r = hc::calibrate(f.model, f.data, f.noise, opt);
    kept = r.kept.size();
    benchmark::DoNotOptimize(r.solution.covariance.data());
  }
  state.counters["configs"] = static_cast<double>(f.data.size());
  state.counters["kept"] = static_cast<double>(kept);
}
// 0: data matrix built for the sparsed model (62 columns) after the data-free steps M1-M3;
// 1: also the complete (258) and symmetrised (153) observation matrices factorised for their ranks.
BENCHMARK(BM_FullPipeline)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_OnlineUpdate(benchmark::State& state) {
  const Fixture& f = fixture1000();
  const bool reduce = state.range(0) != 0;
  hc::PipelineOptions opt;
  std::unique_ptr<hc::OnlineIdentifier> id;
  if (reduce) {
    std::vector<hc::ReductionLine> lines;
    id = std::make_unique<hc::OnlineIdentifier>(f.model, hc::physical_reduction(f.model, opt, lines), hc::ParameterSet{}, Eigen::VectorXd(),
                                                f.noise, opt, true);
    id->set_reuse_reduction(state.range(0) == 1);
  } else {
    // The reduced model of a batch identification, kept fixed online.
    const std::vector<hc::Measurement> first(f.data.begin(), f.data.begin() + 200);
    const auto r = hc::calibrate(f.model, first, f.noise, opt);
    hc::ParameterSet free, fixed;
    Eigen::VectorXd vals(static_cast<Eigen::Index>(r.fixed.size()));
    for (const auto& k : r.kept) free.push_back(k.parameter);
    for (std::size_t i = 0; i < r.fixed.size(); ++i) {
      fixed.push_back(r.fixed[i].parameter);
      vals[static_cast<Eigen::Index>(i)] = r.fixed[i].value;
    }
    id = std::make_unique<hc::OnlineIdentifier>(f.model, free, fixed, vals, f.noise, opt, false);
  }
  // Warm up with 100 configurations so that the estimate is full rank.
  for (std::size_t i = 0; i < 100; ++i) id->add(f.data[i]);
  std::size_t i = 100;
  for (auto _ : state) {
    id->add(f.data[i]);
    const auto e = id->estimate();
    benchmark::DoNotOptimize(e.kept.data());
    if (++i == f.data.size()) i = 100;
  }
  state.counters["params"] = static_cast<double>(id->parameters().size());
  if (reduce) {
    // Estimates whose reduction was a full M4-M6 run / a re-verified cached structure.
    state.counters["full"] = static_cast<double>(id->reduction_stats().full);
    state.counters["verified"] = static_cast<double>(id->reduction_stats().verified);
  }
}
// 0: fixed reduced model (add + estimate); 1: physical model (56) reduced online at each estimate
// (the last reduction re-verified, M4-M6 re-run in full when it fails); 2: the same with the full
// M4-M6 at every estimate (no cache: the figure before issue 29).
BENCHMARK(BM_OnlineUpdate)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_ObservationMatrix(benchmark::State& state) {
  const Fixture& f = fixture1000();
  const auto set = hc::complete_parameters(f.model);
  for (auto _ : state) {
    const auto sys = hc::build_system(f.model, set, f.data, f.noise);
    benchmark::DoNotOptimize(sys.A_w.data());
  }
}
BENCHMARK(BM_ObservationMatrix)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
