// Issue 29: a lab's 10-minute run at 1 kHz (600,000 samples, the ACU 2a trajectory looped, a hidden
// sensor bias) through `hil diagnose`'s path with its defaults: diagnosed on one sample in 60, with
// the verdict of its copy decimated by 16, and the bias inside the intervals of both. Rules written
// before the first run (2026-11-28): same cause, no second cause, each bias component of the two
// diagnoses within 3 combined standard deviations of each other. The timing is bench_diagnose's
// (BM_DiagnoseTenMinutes, docs/performance.md), not this test's.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include <hil/services/diagnose_run.hpp>
#include "scenes.hpp"

namespace dg = hil::diagnose;
namespace sv = hil::services::diagnose;

namespace {

std::map<std::string, dg::Reported> biases(const sv::RunDiagnosis& d) {
  std::map<std::string, dg::Reported> out;
  if (!d.result.extended) return out;
  for (const auto& r : d.result.extended->full.reported)
    if (r.name.rfind("bias_", 0) == 0) out[r.name] = r;
  return out;
}

}  // namespace

TEST(LongRun, TenMinutesAt1kHzAreDiagnosedOnOneSampleIn60WithTheVerdictOfTheDecimatedCopy) {
  const auto run = dg::test::looped_acu_run(600'000, "sensor_bias", 29);
  const sv::Options o;  // the defaults of `hil diagnose`: at most 10,000 samples, every core
  const auto full = sv::diagnose_run(run, o);
  EXPECT_EQ(full.samples_in_run, 600'000u);
  EXPECT_EQ(full.every, 60u);
  EXPECT_EQ(full.obs().size(), 10'000u);
  const auto copy = sv::diagnose_run(sv::every_nth(run, 16), o);  // 37,500 samples: one in 4 of them
  EXPECT_EQ(copy.every, 4u);
  EXPECT_EQ(full.result.cause, "sensor_bias");
  EXPECT_EQ(copy.result.cause, full.result.cause);
  EXPECT_EQ(full.result.second_cause, "");
  EXPECT_EQ(copy.result.second_cause, "");
  const auto a = biases(full), b = biases(copy);
  ASSERT_EQ(a.size(), 6u);
  ASSERT_EQ(b.size(), 6u);
  for (const auto& [name, p] : a) {
    const auto& q = b.at(name);
    EXPECT_LE(std::abs(p.value - q.value), 3.0 * std::hypot(p.std, q.std))
        << name << ": " << p.value << " ± " << p.std << " vs " << q.value << " ± " << q.std;
  }
}
