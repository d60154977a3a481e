// Benchmark of issue 6 (figure recorded in docs/performance.md): `hil diagnose` on a 2,000-sample
// run of the re-created ACU experiment (test 2a, 1 kHz trajectory decimated by 16) with a hidden
// effect, all eight candidates, 5 folds and the greedy second step (target < 30 s); the second
// argument is the folds' threads (CvOptions::threads: 1, or 2 = both cores of the target machine).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <set>
#include <string>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include "scenes.hpp"

namespace dg = hil::diagnose;

namespace {

/// The hidden effects benchmarked (index = the benchmark's argument); seeds as in test_hidden.cpp.
struct Hidden {
  const char* effect;  ///< empty: a clean run
  unsigned seed;
};
constexpr Hidden kHidden[] = {{"geometric_offset", 19}, {"sensor_bias", 12}, {"", 11}};

void BM_DiagnoseAcu2000(benchmark::State& st) {
  const Hidden h = kHidden[st.range(0)];
  dg::DiagnoseOptions o;
  o.cv.threads = static_cast<int>(st.range(1));
  const auto r = dg::test::scene_run("acu_2a", 16);
  dg::Effects e;
  if (*h.effect) dg::draw_effect(h.effect, h.seed, r.scene, e);
  const auto data = dg::make_contact_data(r.scene, r.model.v_tm, dg::test::measure(r, e, h.seed), r.force_scale_n, r.moment_scale_nm);
  const dg::ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<dg::ContactFamily>(data, x); };
  dg::Diagnosis d;
  for (auto _ : st) {
    d = dg::diagnose(make, dg::contact_extensions(), data.obs, {}, o);
    benchmark::DoNotOptimize(d.cause.data());  // (not a double: with GCC the "+r" constraint may clobber it)
  }
  char gain[32];
  std::snprintf(gain, sizeof gain, ", gain %.1f %%", d.gain_percent);
  st.SetLabel(std::string("hidden ") + (*h.effect ? h.effect : "none") + ", named " + d.cause +
              (d.second_cause.empty() ? "" : " + " + d.second_cause) + gain);
  st.counters["samples"] = static_cast<double>(data.obs.size());
  st.counters["seconds"] = d.seconds;
  st.counters["named_hidden"] = d.cause == (*h.effect ? h.effect : "none") ? 1 : 0;
  // Where the time goes: each candidate's score (full fit and the 5 folds), s2_: the second step's.
  for (const auto& c : d.candidates) st.counters["s_" + c.name] = c.score.seconds;
  for (const auto& c : d.second_step) st.counters["s2_" + c.name] = c.score.seconds;  // the cause + c
}
BENCHMARK(BM_DiagnoseAcu2000)
    ->ArgsProduct({{0, 1, 2}, {1, 2}})
    ->ArgNames({"hidden", "threads"})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
