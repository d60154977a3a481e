// The blind suite (issue 12, item 1): `hil diagnose`'s contact family on runs of the independent
// truth (hil::contact_truth), which shares no code with the candidates. The tripod's runs are
// converted to what the rig would record (tripod_scene.hpp) and diagnosed without knowing the
// scenario; the test knows it and checks what the issue demands:
//  * a clean run: `none`;
//  * one effect the library has a candidate for: that cause named first, and its parameters (those
//    the diagnosis calls practically identifiable, PNR >= 5) inside 1.96 std of the truth (95 %);
//  * two effects: both named (cause and second cause), each with its magnitude;
//  * an effect outside the library (a drifting offset, a slip of the tripod): `none`, or a cause
//    whose held-out gain stays clearly partial (< 50 %: it does not claim to explain the misfit).
// Each case runs at the paper's velocity resolution (2e-4 m/s in the reported twist) and a fine one
// (2e-5 m/s); the reported position is quantised to the paper's 2 µm in both.
//
// Not here: robot_compliance. The truth's tripod is exactly where the robot says (only a slip
// moves it against the reported pose, and not with the load): it cannot produce a compliance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include "blind_runs.hpp"

namespace hil::diagnose::test {
namespace {

// Out-of-library effects: a named cause must not explain more than this share of the misfit.
constexpr double kPartialGainPercent = 50.0;

struct Effect {
  std::string name;
  std::function<void(ct::Scenario&, TripodRigOptions&)> apply;
  std::vector<std::string> expected;  ///< the causes the diagnosis must name (empty: none)
  bool out_of_library = false;
};

struct Case {
  Effect effect;
  Resolution resolution;
  std::string known_failure;  ///< non-empty: skipped, with the outcome observed (see known_failure())
};

std::string label(const Case& c) { return c.effect.name + "_" + c.resolution.name; }
void PrintTo(const Case& c, std::ostream* os) { *os << label(c); }

// Effects with fixed magnitudes, each well above the sensor's 0.1 N / 0.005 N m noise on this run.
const Effect kNone{"none", [](ct::Scenario&, TripodRigOptions&) {}, {}};
const Effect kBias{"sensor_bias",
                   [](ct::Scenario& s, TripodRigOptions&) { s.sensor.bias << 0.8, -0.5, 1.5, 0.03, -0.02, 0.01; },
                   {"sensor_bias"}};
const Effect kGain{"sensor_gain",
                   [](ct::Scenario& s, TripodRigOptions&) { s.sensor.gain << 0.04, -0.03, 0.0, 0.03, -0.04, 0.02; },
                   {"sensor_gain"}};
const Effect kDelay{"time_offset", [](ct::Scenario& s, TripodRigOptions&) { s.sensor.delay_s = 0.02; }, {"time_offset"}};
const Effect kViscous{"viscous_friction",
                      [](ct::Scenario& s, TripodRigOptions&) { s.law.viscous_n_s_per_m = 200.0; },
                      {"viscous_friction"}};
// The truth bounds friction by the total normal force (Kelvin-Voigt): μ D δ̇ more than hil's
// contact_damping, whose friction stays μ K δ.
const Effect kDamping{"contact_damping",
                      [](ct::Scenario& s, TripodRigOptions&) {
                        s.law.damping_n_s_per_m = 5000.0;
                        s.law.friction_on_total_normal = true;
                      },
                      {"contact_damping"}};
// The same damping with friction on the elastic force only: hil's candidate exactly.
const Effect kDampingElastic{"contact_damping_elastic_friction",
                             [](ct::Scenario& s, TripodRigOptions&) {
                               s.law.damping_n_s_per_m = 5000.0;
                               s.law.friction_on_total_normal = false;
                             },
                             {"contact_damping"}};
const Effect kExponent{"nonlinear_stiffness", [](ct::Scenario& s, TripodRigOptions&) { s.law.exponent = 1.4; }, {"nonlinear_stiffness"}};
// The rig declares the plate's surface 20 µm below where it is (the truth's o_P).
const Effect kGeometric{"geometric_offset",
                        [](ct::Scenario&, TripodRigOptions& o) { o.declared_plate_height_m = -2e-5; },
                        {"geometric_offset"}};
const Effect kBiasDelay{"sensor_bias_and_time_offset",
                        [](ct::Scenario& s, TripodRigOptions&) {
                          s.sensor.bias << 0.8, -0.5, 1.5, 0.03, -0.02, 0.01;
                          s.sensor.delay_s = 0.02;
                        },
                        {"sensor_bias", "time_offset"}};
// Damping on top of a delay (issue 12: "a second step that can find damping on top of a delay").
// To first order D δ̇ is the normal force D/K earlier, so the sizes differ (a lead of 12.5 ms, a
// lag of 40 ms): with D = 5000 and 20 ms the two cancel (nominal error 0.83 % against 0.66 % noise).
const Effect kDampingDelay{"contact_damping_and_time_offset",
                           [](ct::Scenario& s, TripodRigOptions&) {
                             s.law.damping_n_s_per_m = 2500.0;
                             s.law.friction_on_total_normal = true;
                             s.sensor.delay_s = 0.04;
                           },
                           {"contact_damping", "time_offset"}};
// And the other way round: damping that dominates (D/K = 25 ms of lead) with a 10 ms delay on top.
// Damping is named first (D 2953 alone: it absorbs the delay), then the delay: 0.14 noise
// variances held out, 0.92 in the joint fit; D 5196 ± 299, τ 11.2 ± 1.5 ms. On seeds 2-4 both are
// named with D 5734-5916 and τ 14.1-14.8 ms, high together by up to 2.2 std (docs/diagnosis.md).
const Effect kDelayDamping{"time_offset_and_contact_damping",
                           [](ct::Scenario& s, TripodRigOptions&) {
                             s.law.damping_n_s_per_m = 5000.0;
                             s.law.friction_on_total_normal = true;
                             s.sensor.delay_s = 0.01;
                           },
                           {"contact_damping", "time_offset"}};
const Effect kDrift{"drifting_offset",
                    [](ct::Scenario& s, TripodRigOptions&) { s.sensor.drift_per_s << 0.05, -0.03, 0.15, 0.002, -0.002, 0.001; },
                    {},
                    true};
const Effect kSlip{"slip_event",
                   [](ct::Scenario& s, TripodRigOptions&) {
                     s.slips.push_back({kDuration_s / 2, 1.5e-3, -1e-3, 0.02});
                   },
                   {},
                   true};

class Blind : public ::testing::TestWithParam<Case> {};

TEST_P(Blind, TheRightCauseWithItsMagnitude) {
  const Case& c = GetParam();
  // Known failures are skipped, with their observed outcome, unless HIL_RUN_KNOWN_FAILURES is set
  // (a DISABLED_ name in the middle of a parameterised test's name is not seen as disabled by
  // ctest's test discovery, which then runs it).
  if (!c.known_failure.empty() && !std::getenv("HIL_RUN_KNOWN_FAILURES"))
    GTEST_SKIP() << "known failure: " << c.known_failure << " (HIL_RUN_KNOWN_FAILURES=1 runs it)";
  ct::Scenario sc = pressing_and_sliding(kDuration_s);
  // HIL_BLIND_SEED=N reruns the suite on another noise draw (the recorded results are the default's).
  if (const char* seed = std::getenv("HIL_BLIND_SEED")) sc.sensor.seed = static_cast<unsigned>(std::stoul(seed));
  TripodRigOptions rig;
  c.effect.apply(sc, rig);
  const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, rig);
  const auto data = make_contact_data(scene, kVtm_m_per_s,
                                      to_measurements(ct::simulate(sc), {c.resolution.position_m, c.resolution.velocity_m_per_s}));
  const ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(data, x); };
  const Diagnosis d = diagnose(make, contact_extensions(), data.obs, {});

  std::ostringstream table;
  table << std::setprecision(4);
  for (const auto& k : d.candidates)
    table << "  " << k.name << ": " << 100 * k.score.cv_error << " % (noise fraction " << k.noise_fraction << ") " << k.verdict << "\n";
  for (const auto& k : d.second_step) {
    table << "  + " << k.name << ": " << k.verdict << " nf " << k.noise_fraction << " ef " << k.effect_fraction << " (in-sample "
          << k.effect_fraction_in_sample << ") |";
    for (const auto& q : k.score.full.reported)
      if (q.extension)
        table << " " << q.name << "=" << q.value << "±" << q.std << " [a " << q.std_asymptotic << " f " << q.std_folds << " m "
              << q.std_model_form << "]";
    table << "\n";
  }
  if (std::getenv("HIL_DEBUG_TABLE")) std::cout << table.str();
  SCOPED_TRACE("nominal " + std::to_string(100 * d.nominal.cv_error) + " %, noise " + std::to_string(100 * d.noise_relative) +
               " %, candidates:\n" + table.str());
  // One line per case for the report: the named causes, the gain, each checked parameter.
  std::ostringstream line;
  line << std::setprecision(4) << "BLIND " << label(c) << ": cause " << d.cause << (d.second_cause.empty() ? "" : " + " + d.second_cause)
       << ", gain " << d.gain_percent << " % (nominal " << 100 * d.nominal.cv_error << " %, noise " << 100 * d.noise_relative << " %)";

  // The parameters of a named cause the scenario did not hide (the expected ones are listed below).
  if (d.extended)
    for (const auto& cause : {d.cause, d.second_cause})
      if (std::find(c.effect.expected.begin(), c.effect.expected.end(), cause) == c.effect.expected.end())
        for (const auto& q : d.extended->full.reported)
          if (q.extension && belongs_to(q.name, cause)) line << "; " << q.name << " = " << q.value << " ± " << q.std;

  if (!c.known_failure.empty()) line << " [known failure: " << c.known_failure << "]";
  line << " [" << data.rate_source() << "]";

  const std::vector<std::string>& want = c.effect.expected;
  if (c.effect.out_of_library) {
    std::cout << line.str() << "\n";
    // Else the case would test nothing: the effect must leave a misfit well above the noise.
    EXPECT_GT(d.nominal.cv_error, 2.0 * d.noise_relative) << "the effect is not visible in the nominal model's error";
    EXPECT_TRUE(d.cause == "none" || d.gain_percent < kPartialGainPercent)
        << "an effect outside the library named " << d.cause << " with a held-out gain of " << d.gain_percent << " %";
    return;
  }
  if (want.empty()) {
    std::cout << line.str() << "\n";
    EXPECT_EQ(d.cause, "none");
    EXPECT_EQ(d.second_cause, "");
    EXPECT_EQ(d.gain_percent, 0.0);
    return;
  }
  if (want.size() == 2) EXPECT_EQ((std::set<std::string>{d.cause, d.second_cause}), std::set<std::string>(want.begin(), want.end()));
  else EXPECT_EQ(d.cause, want.front());
  EXPECT_GT(d.gain_percent, 0.0);
  ASSERT_TRUE(d.extended.has_value());
  // Each expected cause's parameters that the diagnosis calls practically identifiable: the truth
  // inside the reported intervals, jointly at 95 % (Bonferroni: m parameters at 1 - 0.05/m each;
  // m = 1: ± 1.96 std). Each parameter alone at 95 % would let a case with m of them fail in
  // 1 - 0.95^m of the runs (19 % for the four gains) although every interval is honest: the
  // coverage suite checks the single intervals over 20 seeds. At least one per expected cause.
  struct Checked {
    std::string name;
    double value, std, truth;
  };
  std::vector<Checked> checked;
  for (const auto& cause : want) {
    if (cause != d.cause && cause != d.second_cause) continue;
    int of_cause = 0;
    for (const auto& q : d.extended->full.reported) {
      if (!q.extension || !belongs_to(q.name, cause)) continue;
      const auto t = truth_of(q.name, sc, d.extended->full, c.resolution.velocity_m_per_s);
      if (!t) continue;
      line << "; " << q.name << " = " << q.value << " ± " << q.std << " (truth " << *t << ", pnr " << q.pnr() << ")";
      if (q.pnr() < 5.0) continue;
      ++of_cause;
      checked.push_back({q.name, q.value, q.std, *t});
    }
    EXPECT_GE(of_cause, 1) << cause << ": no parameter is practically identifiable";
  }
  const double z = joint_z(checked.size());
  for (const auto& q : checked)
    EXPECT_LE(std::abs(q.value - q.truth), z * q.std)
        << q.name << " = " << q.value << " ± " << q.std << ", truth " << q.truth << " (" << checked.size() << " checked, z = " << z << ")";
  std::cout << line.str() << "\n";
}

TEST(BlindSuite, JointQuantileIsBonferronisNormalQuantile) {
  EXPECT_NEAR(joint_z(1), 1.95996, 1e-4);
  EXPECT_NEAR(joint_z(4), 2.49771, 1e-4);  // Φ⁻¹(1 - 0.00625)
  EXPECT_NEAR(joint_z(6), 2.63826, 1e-4);
  EXPECT_EQ(joint_z(0), joint_z(1));
}

// Cases that fail because of the diagnosis engine, not of the scene or the converter (TripodScene.*
// checks those: per sample the nominal model is the truth's law to 0.01 N / 3e-3 N m, and a clean
// run's nominal fit returns K and μ within 0.05 %). Disabled so that the suite passes; each entry
// is the outcome observed on the 15 s runs (run them with HIL_RUN_KNOWN_FAILURES=1).
// Measured causes (2026-11-26, one change at a time on the 15 s runs): hil's contact point is the
// centroid of the interference volume, 3δ/4 above the truth's point foot, where the truth applies
// its friction. That lever moves the friction's moments in mx, my, which biased the delay (τ 20.95
// ms for 20) and the tilting moments' gains; with μ = 0 in the truth both come out right. Where the
// friction acts is a model form the run cannot decide (on a level plate its lever is exactly
// collinear with muK and the friction gains), so the intervals account for it: the fit is repeated
// with the friction's line of action ± 3δ/4 from the centroid and the shifts widen the intervals
// (ModelFamily::model_forms, docs/diagnosis.md). The delay and the tilting gains now pass.
// sensor_gain: gain_fy is fixed as not identifiable (friction lives in fx, fy and mz only, so a
// common factor of their gains trades against μ) and the others come out relative to it; gain_mz is
// 0.0473 ± 0.0019 for 0.0515, 2.2 std, inside the joint interval of the four gains (z = 2.50). Over
// 20 seeds of 15 s runs its single interval covers 19 of 20 (test_coverage's gain_mz: 20 of 20 on
// 8 s runs): a miss at the rate a 95 % interval has, not a bias.
// contact_damping (2026-11-26, fourth session): named at both resolutions with D 4939-4941 ± 39 for
// 5000 (1.5 std) since its penetration rates come from the slope of the reported positions where
// that beats the reported twist (ContactData::v_rate_world). Before, the paper's 2e-4 m/s twist
// hardly carried the rate (<= 1.7e-4 m/s) and a delay of about D/K = 25 ms was named instead, and
// at the fine resolution the twist's quantisation attenuated D to 4913 (2.2 std).
// contact_damping + time_offset (2026-11-26, sixth session): a 40 ms delay with D = 2500 N s/m (a
// 12.5 ms lead to first order). time_offset is named first with τ 30.2 ms — the delay absorbs the
// damping's first order — and the damping added to it explains only 0.14 of the noise variance held
// out (the delay leaves 0.18 of misfit; the two differ only in the tangential forces and the contact
// points), below the 0.25 a cause must explain. Its effect in the joint fit is 1.0-1.1 noise
// variances (robot_compliance's 0.18, sensor_gain's 0.06; held out, as sized since 2026-12-05:
// 0.98-1.02), and a second cause's size is now the larger of the two
// (DiagnoseOptions::min_noise_fraction): both named, τ 43.7 ± 4.6 ms for 40,
// D 3174 ± 937 for 2500 (paper), 42.4 ms and 2931 ± 774 (fine).
std::string known_failure(const std::string& effect) {
  (void)effect;  // none at present; an entry returns the observed outcome and skips the case
  return "";
}

std::vector<Case> cases(const Resolution& r) {
  std::vector<Case> out;
  for (const Effect* e : {&kNone, &kBias, &kGain, &kDelay, &kViscous, &kDamping, &kDampingElastic, &kExponent, &kGeometric, &kBiasDelay,
                          &kDampingDelay, &kDelayDamping, &kDrift, &kSlip})
    out.push_back({*e, r, known_failure(e->name)});
  return out;
}

std::string case_name(const ::testing::TestParamInfo<Case>& i) { return label(i.param); }

INSTANTIATE_TEST_SUITE_P(Paper, Blind, ::testing::ValuesIn(cases(kPaper)), case_name);
INSTANTIATE_TEST_SUITE_P(Fine, Blind, ::testing::ValuesIn(cases(kFine)), case_name);

}  // namespace
}  // namespace hil::diagnose::test
