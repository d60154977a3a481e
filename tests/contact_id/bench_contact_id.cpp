// Benchmarks of issue 5 (figures recorded in docs/performance.md):
//   mindist per sample on the ACU scene (target < 50 µs),
//   global identification over 2,000 samples (target < 20 ms),
//   geometric identification with 9 uncertainties over 2,000 samples: LM (target < 2 s) against
//   Nelder-Mead on the same objective (target >= 10x fewer evaluations),
//   the L-curve with 30 values of λ (target < 30 s).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include <hil/test/acu.hpp>

namespace cid = hil::contact_id;

namespace {

/// 2,000 samples of test 2a in contact (1 kHz trajectory, every 8th sample from the contact phase).
const cid::test::AcuRun& acu2000() {
  static const cid::test::AcuRun r = [] {
    auto run = cid::test::acu_run("2a", 8);
    std::vector<cid::Measurement> in;
    cid::MindistWorkspace ws;
    std::vector<cid::ContactPoint> c;
    for (const auto& m : run.data) {
      cid::mindist(run.scene, m.kin, run.scene.design(), run.nominal.v_tm, c, ws);
      if (!c.empty()) in.push_back(m);
    }
    if (in.size() > 2000) in.resize(2000);
    run.data = in;
    return run;
  }();
  return r;
}

void BM_MindistAcuPerSample(benchmark::State& st) {
  const auto& r = acu2000();
  cid::MindistWorkspace ws;
  std::vector<cid::ContactPoint> c;
  const Eigen::VectorXd x = r.scene.design();
  std::size_t i = 0, contacts = 0;
  for (auto _ : st) {
    cid::mindist(r.scene, r.data[i].kin, x, r.nominal.v_tm, c, ws);
    contacts += c.size();
    benchmark::DoNotOptimize(c.data());
    i = (i + 1) % r.data.size();
  }
  st.counters["contacts_per_sample"] = benchmark::Counter(static_cast<double>(contacts) / static_cast<double>(st.iterations()));
}
BENCHMARK(BM_MindistAcuPerSample)->Unit(benchmark::kMicrosecond);

void BM_GlobalIdentification2000(benchmark::State& st) {
  const auto& r = acu2000();
  for (auto _ : st) {
    cid::ContactProblem p(r.scene, r.data, r.options);  // mindist on every sample + weighting
    const auto e = cid::global_estimate(p, r.scene.design());
    benchmark::DoNotOptimize(static_cast<const double&>(e.K));
  }
  st.counters["samples"] = static_cast<double>(r.data.size());
}
BENCHMARK(BM_GlobalIdentification2000)->Unit(benchmark::kMillisecond);

/// Which uncertainties to fit: all nine (range bit 2 clear) or the five observable ones (the
/// shifts and the grooves' depth; the rotations are weakly observable in test 2a).
std::vector<bool> fit_mask(bool five) {
  std::vector<bool> m(9, true);
  if (five)
    for (int j = 5; j < 9; ++j) m[static_cast<std::size_t>(j)] = false;
  return m;
}

/// LM's optimum (the target Nelder-Mead must reach).
double lm_objective(const cid::ContactProblem& p, bool five) {
  cid::GeometricOptions o;
  o.lambda = 0.02;
  o.fit = fit_mask(five);
  return cid::identify_geometry(p, o).objective;
}

void BM_Geometric9(benchmark::State& st) {
  const auto& r = acu2000();
  const cid::ContactProblem p(r.scene, r.data, r.options);
  cid::GeometricOptions o;
  o.lambda = 0.02;
  // 0: LM; 1: one Nelder-Mead run; 2: Nelder-Mead restarted when its simplex collapses.
  const bool nm = st.range(0) >= 1, restarted = st.range(0) == 2, five = st.range(1) == 5;
  o.solver = nm ? cid::Solver::nelder_mead : cid::Solver::levenberg_marquardt;
  o.fit = fit_mask(five);
  // Nelder-Mead: until it reaches LM's objective (or its own convergence if it cannot).
  if (nm) o.stop_at_objective = lm_objective(p, five) * (1.0 + 1e-6);
  if (restarted) {
    o.nelder_mead_restarts = 20;
    o.max_evaluations = 6000;
  }
  cid::GeometricEstimate g;
  for (auto _ : st) {
    g = cid::identify_geometry(p, o);
    benchmark::DoNotOptimize(static_cast<const double&>(g.objective));
  }
  char obj[64];
  std::snprintf(obj, sizeof obj, ", objective %.8g", g.objective);
  const bool reached = g.objective <= o.stop_at_objective;
  st.SetLabel(std::string(!nm         ? "Levenberg-Marquardt (Golub-Pereyra)"
                          : restarted ? (reached ? "restarted Nelder-Mead, reached LM's objective"
                                                 : "restarted Nelder-Mead, did NOT reach LM's objective")
                                      : (reached ? "Nelder-Mead, reached LM's objective"
                                                 : "Nelder-Mead, converged without reaching LM's objective")) +
              obj);
  if (restarted) st.counters["restarts"] = g.restarts;
  st.counters["evaluations"] = g.evaluations;
  st.counters["jacobians"] = g.jacobian_evaluations;
  st.counters["fitted"] = five ? 5 : 9;
}
BENCHMARK(BM_Geometric9)
    ->Args({0, 9})
    ->Args({1, 9})
    ->Args({2, 9})
    ->Args({0, 5})
    ->Args({1, 5})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

void BM_LCurve30(benchmark::State& st) {
  const auto& r = acu2000();
  const cid::ContactProblem p(r.scene, r.data, r.options);
  for (auto _ : st) {
    cid::GeometricOptions o;
    o.fit = fit_mask(true);  // as `identify --geometric`: the observable uncertainties
    const auto c = cid::l_curve(p, o, 1e-4, 1e3, 30);
    benchmark::DoNotOptimize(c.corner);
    st.counters["corner_lambda"] = c.lambda[c.corner];
  }
}
BENCHMARK(BM_LCurve30)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
