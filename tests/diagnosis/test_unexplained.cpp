// `none` means none (issue 32, item 3): the diagnosis calls a run `none` only when the nominal
// model's residual is unstructured, and `unexplained`, naming the structure, when no candidate
// explains what is left. On runs of the independent truth (hil::contact_truth), converted as the
// rig would record them (tripod_scene.hpp), never from the candidates' code.
//
// Blind draws (below): the rules were committed before any of their draws ran.
//
// CleanRuns: no effect, several motion families (the blind suite's circle, a two-tone normal
// motion, piecewise-linear moves with stops at two speeds), both velocity resolutions. These runs
// calibrated StructureOptions' thresholds (docs/diagnosis.md, "Structure left in the residual");
// they must all say `none`, with no structure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/test/eigen.hpp>
#include "blind_runs.hpp"

namespace hil::diagnose::test {
namespace {

/// The reported value named `name` (NaN if none).
double value(const std::vector<Reported>& reported, const std::string& name) {
  for (const auto& q : reported)
    if (q.name == name) return q.value;
  return std::numeric_limits<double>::quiet_NaN();
}

struct CleanCase {
  Motion motion;
  Resolution resolution;
  unsigned seed;
};
std::string clean_name(const ::testing::TestParamInfo<CleanCase>& i) {
  return i.param.motion.name + "_" + i.param.resolution.name + "_seed" + std::to_string(i.param.seed);
}
void PrintTo(const CleanCase& c, std::ostream* os) { *os << clean_name({c, 0}); }

class CleanRuns : public ::testing::TestWithParam<CleanCase> {};

TEST_P(CleanRuns, SayNoneWithNoStructure) {
  const auto& c = GetParam();
  ct::Scenario sc = clean_scenario();
  c.motion.apply(sc);
  sc.sensor.seed = c.seed;
  const Diagnosed run = diagnose_scenario(sc, {}, c.resolution);
  std::cout << "CLEAN " << clean_name({c, 0}) << ": " << run.line << "\n";
  EXPECT_EQ(run.d.cause, "none") << run.line;
  EXPECT_FALSE(run.d.nominal_residuals.structured()) << run.d.nominal_residuals.structure_text();
}

std::vector<CleanCase> clean_cases() {
  std::vector<CleanCase> out;
  // HIL_CLEAN_SEEDS=N: the calibration's draw (seeds 1..N); CI runs seed 1.
  const unsigned seeds = std::getenv("HIL_CLEAN_SEEDS") ? static_cast<unsigned>(std::stoul(std::getenv("HIL_CLEAN_SEEDS"))) : 1u;
  // Straight moves at the paper's twist resolution are not clean (QuantisedTwist below).
  for (const Motion* m : {&kCircle, &kTwoTone, &kMoves, &kSlowMoves})
    for (const Resolution* r : {&kPaper, &kFine})
      for (unsigned s = 1; s <= seeds; ++s)
        if (r == &kFine || m == &kCircle || m == &kTwoTone) out.push_back({*m, *r, s});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Calibration, CleanRuns, ::testing::ValuesIn(clean_cases()), clean_name);

// Found while calibrating: the rig reports the twist quantised per world component (0.2 mm/s at the
// paper's resolution). On a yawed, tilted plate a straight move at 4 mm/s then has a slip direction
// off by a constant angle along each side, so the friction leaks into the other in-plane component
// as long as the side lasts: structure, which the check names. The same run on a level, unyawed
// plate (the sides along the quantisation's axes) is clean.
TEST(QuantisedTwist, StraightMovesOnAYawedPlateLeaveFrictionAcrossTheMotion) {
  ct::Scenario sc = clean_scenario();
  kSlowMoves.apply(sc);
  const Diagnosed yawed = diagnose_scenario(sc, {}, kPaper);
  std::cout << "YAWED " << yawed.line << "\n";
  EXPECT_EQ(yawed.d.cause, "unexplained") << yawed.line;
  bool across = false;
  for (const auto& f : yawed.d.nominal_residuals.structure)
    across = across || f.text.rfind("fy correlates with vx", 0) == 0 || f.text.rfind("fx correlates with vy", 0) == 0;
  EXPECT_TRUE(across) << yawed.d.nominal_residuals.structure_text();
  sc.plate.yaw_rad = sc.plate.tilt_x_rad = sc.plate.tilt_y_rad = 0.0;
  const Diagnosed level = diagnose_scenario(sc, {}, kPaper);
  std::cout << "LEVEL " << level.line << "\n";
  EXPECT_EQ(level.d.cause, "none") << level.line;
}

// The slow moves' normal twist takes only odd levels of its 2e-5 m/s grid (±1, ±5, ±11, ±15 steps
// on clean_scenario): its quantum was seen as 4e-5 or, on drawn speeds, not at all (2026-12-03), so
// the damping's twist-level errors were held within twice their bound or not at all. A stream that
// takes few, sparse levels (the slow moves' x: 0, ±78, ±184 steps) cannot show its step; what is
// seen must then be a multiple of it, never a wrong grid.
TEST(QuantisedTwist, TheReportedStreamsShowTheirQuantumOrAMultipleOfIt) {
  for (const Motion* m : {&kCircle, &kTwoTone, &kMoves, &kSlowMoves, &kTrapezoidal}) {
    ct::Scenario sc = clean_scenario();
    m->apply(sc);
    const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, {});
    const auto data = make_contact_data(scene, kStickBelow_m_per_s,
                                        to_measurements(ct::simulate(sc), {kFine.position_m, kFine.velocity_m_per_s}));
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(data.position_quantum_m(a), kFine.position_m, 1e-15) << m->name << " position axis " << a;
      const double steps = data.velocity_quantum_m_per_s(a) / kFine.velocity_m_per_s;
      EXPECT_NEAR(steps, std::round(steps), 1e-9) << m->name << " twist axis " << a;
      if (m == &kSlowMoves && a == 2) {
        EXPECT_NEAR(steps, 1.0, 1e-9) << "the slow moves' normal twist";
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Blind draws (issue 32, items 3 and 4). These rules were written and committed before any draw
// below ran; the thresholds (StructureOptions' defaults) were fixed before, on CleanRuns.
//  * Seeds 32,100,000 + 1000 e + i (e the effect, i < 1000 the draw; 32,150,000 + 10,000 e + i for
//    i >= 1000), never used before. Each draw's motion family, its speed, stops, amplitudes and
//    yaw, the effect's magnitudes and the noise come from its seed.
//  * Resolution: fine; the paper's on the circle and two-tone families for odd i / 4 (straight
//    moves at the paper's resolution carry structure of their own: QuantisedTwist).
//  * Clean: the verdict is `none`, no second cause.
//  * Effects outside the library: Stribeck friction (on moves with stops: the feet must slow down
//    for it to show), a drifting offset, a plate's fx -> fy cross-coupling. A draw passes when
//     - the report is not silent: `unexplained`, or a named cause whose residual still shows
//       structure;
//     - the structure named is the effect's kind: a trend for the drift; a correlation with a
//       velocity signal (speed, slip_speed, vx, vy, acceleration) for the friction; a finding on
//       fy for the cross-coupling (in the nominal residual when `unexplained`, else the extended);
//     - no wrong name: for the drift a named cause can only be sensor_bias (a drift's constant
//       part), with the trend left in its residual; for the others a named cause explains less
//       than half of the misfit (held-out gain < 50 %).
//  * Pass rate: at most ceil(10 %) of an effect's draws fail. CI draws 8 per effect (i = 0..7, 1
//    may fail); HIL_UNEXPLAINED_DRAWS=50 is the full draw (5 may fail), docs/diagnosis.md, on
//    i = 100..149: the CI draws were seen during development, those were not (added after the CI
//    draws first ran, before any full draw).

enum class Hidden { none, stribeck, drift, coupling };

struct Drawn {
  ct::Scenario scenario;
  Resolution resolution;
  std::string label;
};

Drawn draw(Hidden h, unsigned i) {
  // i < 1000: 32,100,000 + 1000 e + i. Beyond, that formula would give the next effect's seeds
  // (i = 1000 of one effect is i = 0 of the next), so i >= 1000 draws from its own range.
  const unsigned e = static_cast<unsigned>(h);
  const unsigned seed = i < 1000u ? 32'100'000u + 1000u * e + i : 32'150'000u + 10'000u * e + i;
  Draws r(seed);
  Drawn d{clean_scenario(), kFine, ""};
  ct::Scenario& sc = d.scenario;
  const Motion* families[] = {&kCircle, &kTwoTone, &kMoves, &kSlowMoves};
  const unsigned f = h == Hidden::stribeck ? 2 + i % 2 : i % 4;
  families[f]->apply(sc);
  auto& t = sc.trajectory;
  if (f < 2) {
    t.angular_rate_rad_per_s *= r.uniform(0.7, 1.3);
    if ((i / 4) % 2 == 1) d.resolution = kPaper;
  } else {
    t.angular_rate_rad_per_s = r.uniform(4e-3, 12e-3) / t.radius_m;
    t.dwell_s = r.uniform(0.3, 1.0);
  }
  t.depth_amplitude_m *= r.uniform(0.8, 1.2);
  t.depth_amplitude2_m *= r.uniform(0.5, 1.5);
  t.yaw_amplitude_rad = r.uniform(0.02, 0.04);
  sc.sensor.seed = seed;
  std::ostringstream o;
  o << std::setprecision(3) << "seed " << seed << " " << families[f]->name << " " << d.resolution.name;
  switch (h) {
    case Hidden::none: break;
    case Hidden::stribeck:
      sc.law.mu_rest = sc.law.mu * r.uniform(1.3, 1.7);
      sc.law.stribeck_speed_m_per_s = r.uniform(1.5e-3, 3e-3);
      o << ", mu " << sc.law.mu_rest << " at rest -> " << sc.law.mu << " above " << 1e3 * sc.law.stribeck_speed_m_per_s << " mm/s";
      break;
    case Hidden::drift: {
      const double T = sc.duration_s;
      sc.sensor.drift_per_s << r.sign() * r.uniform(0.5, 1.5) / T, r.sign() * r.uniform(0.5, 1.5) / T, r.sign() * r.uniform(2.0, 6.0) / T,
          0.0, 0.0, 0.0;
      o << ", drift over the run (N) " << T * sc.sensor.drift_per_s.head<3>().transpose();
      break;
    }
    case Hidden::coupling:
      sc.sensor.cross_coupling(1, 0) = r.sign() * r.uniform(0.03, 0.06);
      o << ", fx -> fy " << 100 * sc.sensor.cross_coupling(1, 0) << " %";
      break;
  }
  d.label = o.str();
  return d;
}

/// Why a draw fails its rule (empty: it passes).
std::string judge(Hidden h, const Diagnosis& d) {
  if (h == Hidden::none) {
    if (d.cause != "none") return "cause " + d.cause + " on a clean run: " + d.nominal_residuals.structure_text();
    return "";
  }
  const bool unexplained = d.cause == "unexplained";
  const ResidualAnalysis& res = unexplained ? d.nominal_residuals : d.extended_residuals;
  if (!unexplained && !d.extended_residuals.structured()) return "silent: " + d.cause + " named and its residual called unstructured";
  bool kind = false;
  for (const auto& f : res.structure) {
    if (h == Hidden::drift) kind = kind || f.kind == "trend";
    if (h == Hidden::stribeck)
      for (const char* sig : {"speed", "slip_speed", "vx", "vy", "acceleration"})
        kind = kind || (f.kind == "correlates" && f.text.find(std::string("correlates with ") + sig + " (") != std::string::npos);
    if (h == Hidden::coupling) kind = kind || f.text.rfind("fy ", 0) == 0 || f.text.find("(fy ") != std::string::npos;
  }
  if (!kind) return "the structure named is not the effect's kind: " + res.structure_text();
  if (!unexplained) {
    if (h == Hidden::drift && (d.cause != "sensor_bias" || !d.second_cause.empty()))
      return "a drift named " + d.cause + (d.second_cause.empty() ? "" : " + " + d.second_cause);
    if (h != Hidden::drift && d.gain_percent >= 50.0)
      return "named " + d.cause + " with a held-out gain of " + std::to_string(d.gain_percent) + " %";
  }
  return "";
}

class BlindDraws : public ::testing::TestWithParam<Hidden> {};

// Known failures: none. Stribeck friction first passed 1 of 8 CI draws (2026-11-28): on moves with
// stops the feet slide fast along the sides (μ, in fx and fy) and slowly at the stops, where the
// yaw twists them (μ_rest, in mz), and sensor_gain's gains stood in for the friction's speed
// dependence (gain_fx = gain_fy = -21 ... -40 %, held-out gain 65-80 %). A plate's calibration
// tolerance fixed it, then not, as the folds split between optima along the friction components'
// common gain (i = 1150..1199: 39 of 50). Since 31722a4 that common gain is μ's (sensor_gain has a
// reference in each group of the plate's components): i = 1200..1249, 50 of 50 (docs/diagnosis.md,
// "The plate's two groups of components").
std::string known_failure(Hidden h) {
  (void)h;
  return "";
}

TEST_P(BlindDraws, MeetTheirRule) {
  const Hidden h = GetParam();
  if (const auto k = known_failure(h); !k.empty() && !std::getenv("HIL_RUN_KNOWN_FAILURES"))
    GTEST_SKIP() << "known failure: " << k << " (HIL_RUN_KNOWN_FAILURES=1 runs it)";
  const unsigned n = std::getenv("HIL_UNEXPLAINED_DRAWS") ? static_cast<unsigned>(std::stoul(std::getenv("HIL_UNEXPLAINED_DRAWS"))) : 8u;
  const unsigned allowed = (n + 9) / 10;  // ceil(10 %)
  // HIL_UNEXPLAINED_FIRST: where a full draw starts (100 for the first; later ones never reuse an i).
  const unsigned first = std::getenv("HIL_UNEXPLAINED_FIRST")   ? static_cast<unsigned>(std::stoul(std::getenv("HIL_UNEXPLAINED_FIRST")))
                         : std::getenv("HIL_UNEXPLAINED_DRAWS") ? 100u
                                                                : 0u;
  unsigned failed = 0;
  for (unsigned i = first; i < first + n; ++i) {
    const Drawn x = draw(h, i);
    const Diagnosed run = diagnose_scenario(x.scenario, {}, x.resolution);
    const std::string why = judge(h, run.d);
    failed += why.empty() ? 0 : 1;
    std::cout << "DRAW " << x.label << ": " << (why.empty() ? "pass" : "FAIL (" + why + ")") << " | " << run.line << "\n";
  }
  std::cout << "SUMMARY " << ::testing::UnitTest::GetInstance()->current_test_info()->name() << ": " << n - failed << " of " << n
            << " pass (at most " << allowed << " may fail)\n";
  EXPECT_LE(failed, allowed);
}

std::string hidden_name(const ::testing::TestParamInfo<Hidden>& i) {
  switch (i.param) {
    case Hidden::none: return "clean";
    case Hidden::stribeck: return "stribeck_friction";
    case Hidden::drift: return "drifting_offset";
    case Hidden::coupling: return "cross_coupling";
  }
  return "?";
}

INSTANTIATE_TEST_SUITE_P(Issue32, BlindDraws, ::testing::Values(Hidden::none, Hidden::stribeck, Hidden::drift, Hidden::coupling),
                         hidden_name);

// A plate whose fx reads 28 % low (a wrong row of its calibration matrix, say) is not a plate the
// lab trusts: sensor_gain would explain the run, but with gains beyond the declared calibration
// tolerance it is not physical, and the run says `unexplained` with the candidate's reason. The
// same run with the tolerance declared wide enough names sensor_gain and reads the gain.
TEST(PlateCalibration, AGainBeyondThePlatesToleranceIsNotNamedButSaysWhy) {
  ct::Scenario sc = clean_scenario();
  kCircle.apply(sc);
  sc.sensor.gain(0) = -0.28;
  sc.sensor.seed = 32'120'001u;
  const Diagnosed strict = diagnose_scenario(sc, {}, kFine);
  std::cout << "STRICT " << strict.line << "\n";
  EXPECT_EQ(strict.d.cause, "unexplained") << strict.line;
  bool said = false;
  for (const auto& c : strict.d.candidates)
    if (c.name == "sensor_gain") said = c.verdict.find("beyond the plate's calibration tolerance") != std::string::npos;
  EXPECT_TRUE(said) << "sensor_gain's verdict does not name the tolerance";

  TripodRigOptions wide;
  wide.plate_gain_tolerance = 0.5;
  const Diagnosed lenient = diagnose_scenario(sc, wide, kFine);
  std::cout << "WIDE " << lenient.line << "\n";
  ASSERT_EQ(lenient.d.cause, "sensor_gain") << lenient.line;
  ASSERT_TRUE(lenient.d.extended.has_value());
  // The gains are relative to a reference component (truth_of): fx's 28 % shows in whichever
  // component is not the reference.
  int checked = 0, large = 0;
  for (const auto& q : lenient.d.extended->full.reported) {
    const auto truth = truth_of(q.name, sc, lenient.d.extended->full, kFine.velocity_m_per_s);
    if (q.name.rfind("gain_", 0) != 0 || !truth) continue;
    ++checked;
    large += std::abs(*truth) > 0.2 ? 1 : 0;
    EXPECT_NEAR(q.value, *truth, 3.0 * q.std) << q.name;
  }
  EXPECT_GE(checked, 3);
  EXPECT_GE(large, 1) << "no gain beyond 20 % reported";
}

// On a level plate the normal force loads fz, mx and my only and the friction fx, fy and mz only
// (at the plate's surface): a common scale of fx, fy and mz is μ's, so sensor_gain has a reference
// in each group (its largest signal) and says which. The friction read 20 % low on every friction
// component is then μ 20 % low, not three gains (docs/diagnosis.md, "The plate's two groups of
// components").
TEST(PlateCalibration, OnALevelPlateTheFrictionsCommonScaleIsMus) {
  for (const Motion* m : {&kCircle, &kMoves}) {
    ct::Scenario sc = clean_scenario();
    m->apply(sc);
    const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, {});
    const auto plain = make_contact_data(scene, kStickBelow_m_per_s,
                                         to_measurements(ct::simulate(sc), {kFine.position_m, kFine.velocity_m_per_s}));
    const ContactFamily family(plain, {"sensor_gain"});
    std::vector<std::string> gains;
    for (const auto& q : family.nonlinear()) gains.push_back(q.name);
    EXPECT_EQ(gains.size(), 4u) << m->name;
    for (const auto& [group, name] : {std::pair{std::vector<std::string>{"gain_fz", "gain_mx", "gain_my"}, "normal"},
                                      std::pair{std::vector<std::string>{"gain_fx", "gain_fy", "gain_mz"}, "friction"}}) {
      int references = 0;
      for (const auto& g : group) references += std::find(gains.begin(), gains.end(), g) == gains.end() ? 1 : 0;
      EXPECT_EQ(references, 1) << m->name << ": the " << name << " group";
    }
    ASSERT_EQ(family.notes().size(), 1u);
    EXPECT_NE(family.notes()[0].find("the largest signals of the normal force's components"), std::string::npos) << family.notes()[0];

    // fx, fy and mz 20 % low: μ reads 20 % low and no friction gain moves (the truth's law is not
    // the candidates', so "20 %" within 2 %, and the gains within 2 % of 0).
    ct::Scenario low = sc;
    low.sensor.gain << -0.2, -0.2, 0.0, 0.0, 0.0, -0.2;
    const auto d1 = make_contact_data(scene, kStickBelow_m_per_s,
                                      to_measurements(ct::simulate(low), {kFine.position_m, kFine.velocity_m_per_s}));
    std::vector<int> every(plain.obs.size());
    std::iota(every.begin(), every.end(), 0);
    const Fit f0 = fit(ContactFamily(plain, {}), plain.obs, every);
    const Fit f1 = fit(ContactFamily(d1, {"sensor_gain"}), d1.obs, every);
    EXPECT_NEAR(value(f1.reported, "mu") / value(f0.reported, "mu"), 0.8, 0.02) << m->name;
    for (const auto& q : f1.reported)
      if (q.name.rfind("gain_", 0) == 0) {
        EXPECT_NEAR(q.value, 0.0, 0.02) << m->name << " " << q.name;
      }
  }
}

// The truth's point feet take their friction at their tips, 3δ/4 below the centroid of the
// interference where the contact model applies it (docs/diagnosis.md, "Model-form intervals"). On a
// plate whose tilting moments have an offset, the run shows it: the form with the friction at the
// tip fits better and gives the values. With the model's own lever the friction's moments were
// misread as offsets (bias_my mean z +0.19, se 0.05, over the family suite's draws i = 900..949).
// Without noise and quantisation, so that only the lever separates the two readings (a wrench
// quantised without noise to dither it errs by a constant share of a step: 2-14e-5 N m in both
// readings' offsets here, the lever's size).
TEST(PlateCalibration, APointFootsFrictionIsTakenAtItsTipWhereTheRunShowsIt) {
  for (const Motion* m : {&kCircle, &kMoves}) {
    ct::Scenario sc = clean_scenario();
    m->apply(sc);
    sc.sensor.noise_std.setZero();
    sc.sensor.resolution.setZero();
    sc.sensor.bias << 0.5, -0.4, 1.0, 0.03, -0.02, 0.01;
    const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, {});
    const auto data = make_contact_data(scene, kStickBelow_m_per_s, to_measurements(ct::simulate(sc)));
    const ContactFamily family(data, {"sensor_bias"});
    const Score s = score(family, data.obs);
    EXPECT_NE(s.model_form_taken.find("against the normal"), std::string::npos) << m->name << ": " << s.model_form_taken;
    std::vector<int> every(data.obs.size());
    std::iota(every.begin(), every.end(), 0);
    const Fit centroid = fit(family, data.obs, every);
    for (const auto& [name, truth] : {std::pair{"bias_mx", 0.03}, std::pair{"bias_my", -0.02}}) {
      const double taken = value(s.full.reported, name) - truth, model = value(centroid.reported, name) - truth;
      // The tip's reading at least five times nearer the truth than the centroid's.
      EXPECT_LT(std::abs(taken), 0.2 * std::abs(model)) << m->name << " " << name << ": " << taken << " against " << model;
    }
  }
}

// The reported ee position is a regressor of the interference: its quantisation error (uniform over
// the step, std step / sqrt 12, uncorrelated with a signal spread over many steps) attenuates K and
// moves the plate's height by about mean δ var(e) / var(δ) (+0.42 std over the family suite's draws
// at 2 um, +390 nm at 8 um on moves; docs/diagnosis.md, "Errors in the variables"). Positions at
// 8 um, the wrench exact (no noise, no quantisation), the rig's declared height 20 um off; one run's
// error also depends on where its motion sits on the grid (± 100-150 nm here), so the phases are
// drawn: the mean depth moved by (j + 1/2)/24 of a step, the centre by another share.
// History: the first version (six phases, "corrected within a third of least squares") had two
// bugs, found by running it: the height's truth taken as 0 (it is minus the declared offset), and
// phases that moved x and y only, not the depth; with both fixed its six draws read least squares
// +114 and +257 nm, corrected -44 and -31 nm, against a se of ~50 nm: a third of +114 was below what
// six draws resolve. The rule below replaced it before these 24 phases (none of them run before):
// the least-squares mean error more than 3 se above 0 (the bias is there), the corrected mean
// within 2.5 se of 0. It passed (two-tone +140 -> -5 nm, moves +253 -> -36 nm). Then the
// correction gained its smoothness check (kErrorsInVariablesMismatch), which refused two-tone
// phase 22 (mismatch 0.30): the test now takes what the diagnosis reports (no correction where
// refused), the same rule, and at least 18 of the 24 phases corrected.
TEST(PlateCalibration, TheReportedPositionsQuantumIsNotReadAsThePlatesHeight) {
  const double step_m = 8e-6;
  const int phases = 24;
  for (const Motion* m : {&kTwoTone, &kMoves}) {
    std::vector<double> lsq, corrected;
    int applied = 0;
    for (int j = 0; j < phases; ++j) {
      ct::Scenario sc = clean_scenario();
      m->apply(sc);
      sc.sensor.noise_std.setZero();
      sc.sensor.resolution.setZero();
      sc.trajectory.depth_m += (j + 0.5) / phases * step_m;
      sc.trajectory.centre_x_m = ((7 * j) % phases + 0.5) / phases * step_m;
      sc.trajectory.centre_y_m = ((11 * j) % phases + 0.5) / phases * step_m;
      TripodRigOptions rig;
      rig.declared_plate_height_m = 2e-5;
      const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, rig);
      const auto data = make_contact_data(scene, kStickBelow_m_per_s, to_measurements(ct::simulate(sc), {step_m, kFine.velocity_m_per_s}));
      ASSERT_NEAR(data.position_quantum_m(2), step_m, 1e-12) << m->name;
      const ContactFamily family(data, {"geometric_offset"});
      std::vector<int> every(data.obs.size());
      std::iota(every.begin(), every.end(), 0);
      const Fit f = fit(family, data.obs, every);
      const ErrorsInVariablesBias eiv = errors_in_variables_bias(family, data.obs, f, every);
      applied += eiv.applied ? 1 : 0;
      const Eigen::VectorXd& bias = eiv.bias;  // 0 where not applied: what the diagnosis reports
      const auto at = std::find(f.phi_names.begin(), f.phi_names.end(), kPlateHeight);
      ASSERT_NE(at, f.phi_names.end()) << m->name;
      const auto i = static_cast<Eigen::Index>(at - f.phi_names.begin());
      // φ is the correction to the declared height: its truth is minus the declared offset.
      lsq.push_back(f.phi(i) + rig.declared_plate_height_m);
      corrected.push_back(lsq.back() - bias(f.theta.size() + i));
    }
    const auto [l, l_se] = hil::test::mean_and_se(lsq);
    const auto [c, c_se] = hil::test::mean_and_se(corrected);
    std::cout << "EIV " << m->name << ": least squares " << 1e9 * l << " nm (se " << 1e9 * l_se << "), corrected " << 1e9 * c << " nm (se "
              << 1e9 * c_se << ")\n";
    EXPECT_GE(applied, phases * 3 / 4) << m->name;
    EXPECT_GT(l, 3 * l_se) << m->name;
    EXPECT_LT(std::abs(c), 2.5 * c_se) << m->name;
  }
}

// ---------------------------------------------------------------------------------------------
// Ambiguity said out loud (issue 32, item 2). Rule committed before its draws ran: contact damping
// (D 2,000-5,000 N s/m, friction on the total normal force) on the two-tone sinusoidal normal
// motion, fine resolution, seeds 32,200,000 + k, k = 0..3, never used before. To first order D δ̇
// is the normal force D/K earlier, which a delay of the wrench also gives. Each draw must name
// contact_damping first, or name the pair (contact_damping, time_offset) as confounded with the
// evidence for each and an experiment that separates them: never a confident delay alone. All four
// must pass.
TEST(Confounded, DampingOnASinusoidalNormalMotionIsNeverAConfidentDelayAlone) {
  for (unsigned k = 0; k < 4; ++k) {
    const unsigned seed = 32'200'000u + k;
    Draws r(seed);
    ct::Scenario sc = clean_scenario();
    kTwoTone.apply(sc);
    sc.law.damping_n_s_per_m = r.uniform(2000.0, 5000.0);
    sc.law.friction_on_total_normal = true;
    sc.sensor.seed = seed;
    const Diagnosed run = diagnose_scenario(sc, {}, kFine);
    const Diagnosis& d = run.d;
    bool said = false;
    std::string pairs;
    for (const auto& c : d.confounded) {
      pairs += c.cause + " ~ " + c.rival + " (" + c.evidence + "; " + c.experiment + ") ";
      said = said || (std::set<std::string>{c.cause, c.rival} == std::set<std::string>{"contact_damping", "time_offset"} &&
                      !c.experiment.empty() && !c.evidence.empty());
    }
    std::cout << "CONFOUNDED seed " << seed << " D " << sc.law.damping_n_s_per_m << ": " << run.line << " | " << pairs << "\n";
    EXPECT_TRUE(d.cause == "contact_damping" || said) << "seed " << seed << ": " << run.line << " | " << pairs;
  }
}

// Delay and damping on piecewise-linear motion with stops (issue 32's "Done when"). Rule committed
// before its draws ran: on the moves families (alternating, speeds 4-12 mm/s, stops 0.3-1 s, from
// the seed), fine resolution, seeds 32,300,000 + 100 e + k, k = 0..3, never used before: an 8 ms
// delay must be named time_offset first, and a 4,000 N s/m damping (friction on the total normal
// force) contact_damping first, in every draw; the named parameter inside ± 1.96 of its std of the
// truth in at least 3 of the 4 draws.
struct OnMoves {
  std::string effect, parameter;
  double truth;
};
void PrintTo(const OnMoves& c, std::ostream* os) { *os << c.effect; }

/// Moves with stops from `r` (moves or slow moves by the parity of i; speed, stops and yaw drawn in
/// this order: the committed draws depend on it).
ct::Scenario drawn_moves(Draws& r, unsigned i, unsigned seed) {
  ct::Scenario sc = clean_scenario();
  (i % 2 ? kSlowMoves : kMoves).apply(sc);
  auto& t = sc.trajectory;
  t.angular_rate_rad_per_s = r.uniform(4e-3, 12e-3) / t.radius_m;
  t.dwell_s = r.uniform(0.3, 1.0);
  t.yaw_amplitude_rad = r.uniform(0.02, 0.04);
  sc.sensor.seed = seed;
  return sc;
}

/// A delay of `value` s, or a damping of `value` N s/m with friction on the total normal force.
void hide(ct::Scenario& sc, const std::string& effect, double value) {
  if (effect == "time_offset") sc.sensor.delay_s = value;
  else {
    sc.law.damping_n_s_per_m = value;
    sc.law.friction_on_total_normal = true;
  }
}

class DelayAndDampingOnMoves : public ::testing::TestWithParam<OnMoves> {};

// History, the delay (first run, 2026-11-29): named in 2 of 4 draws, τ 9.48 ± 0.44 and 9.90 ±
// 0.04 ms for 8, the other two `unexplained`. Causes, measured one change at a time on these draws:
// (1) at each of the ~20 kinks of the in-plane motion the truth's Coulomb friction turns between
// two samples, while the delayed twist was a windowed sinc of the samples: it turned halfway and
// rang into the stops (a stop's zero velocity became a slip); (2) the one-sample spikes this left
// in the nominal model's residual were taken for noise (2.1 % against 0.35 % on clean moves), so a
// delay explained "0.04 noise variances"; (3) the cost then steps as a delayed instant crosses a
// kink, and a fold's LM stayed at its start one sample off, mispredicting a yaw reversal's whole
// moment. Fixed (later the same day): the twist steps where the poses place the step (rate_steps),
// the noise is the least the nominal and the single candidates leave, and time_offset starts
// every quarter sample near zero. Then: named 4 of 4, τ 7.97 ± 0.27, 7.34 ± 0.16, 7.76 ±
// 0.15, 7.86 ± 0.59 ms. Fresh draws: DelayAndDampingOnFreshMoves below.
TEST_P(DelayAndDampingOnMoves, AreNamedWithTheirMagnitude) {
  const OnMoves& c = GetParam();
  int inside = 0;
  for (unsigned k = 0; k < 4; ++k) {
    const unsigned seed = 32'300'000u + (c.effect == "time_offset" ? 0u : 100u) + k;
    Draws r(seed);
    ct::Scenario sc = drawn_moves(r, k, seed);
    hide(sc, c.effect, c.truth);
    const Diagnosed run = diagnose_scenario(sc, {}, kFine);
    std::cout << "MOVES " << c.effect << " seed " << seed << ": " << run.line << "\n";
    EXPECT_EQ(run.d.cause, c.effect) << "seed " << seed << ": " << run.line;
    if (run.d.cause != c.effect || !run.d.extended) continue;
    for (const auto& q : run.d.extended->full.reported)
      if (q.name == c.parameter) inside += std::abs(q.value - c.truth) <= 1.96 * q.std ? 1 : 0;
  }
  EXPECT_GE(inside, 3) << c.parameter << " inside its 95 % interval in " << inside << " of 4 draws";
}

INSTANTIATE_TEST_SUITE_P(Issue32, DelayAndDampingOnMoves,
                         ::testing::Values(OnMoves{"time_offset", "time_offset_s", 0.008},
                                           OnMoves{"contact_damping", "damping_n_s_per_m", 4000.0}),
                         [](const ::testing::TestParamInfo<OnMoves>& i) { return i.param.effect; });

// Fresh draws after the fix above, rules written before their first run (2026-11-29): the delay
// uniform in 5-15 ms, the damping in 2,000-6,000 N s/m (friction on the total normal force), on
// the moves and slow moves families with drawn speeds, stops and yaw, at the fine resolution. Per
// effect, of 8 draws (seeds 32,500,000 + 100 e + i, i = 0..7; HIL_MOVES_DRAWS=50: i = 100..149,
// the full draw in docs/diagnosis.md): the effect named first in at least 7; no second cause in
// at least 7; the truth inside the reported 95 % interval in at least 6 of those named.
// Second full draw (rule added 2026-12-05, before it ran): HIL_MOVES_DRAWS=50 HIL_MOVES_FIRST=200,
// i = 200..249, never drawn before, the same rules, the damping's intervals asserted as the
// delay's. Why: the damping's known failure (below, 2026-11-29) was found stale on the CI draws
// (8 of 8 inside, mean z -0.55, after the damping's clip at lift-off, its twist-level interval and
// its Hunt-Crossley form), and the exemption was removed before this draw.
class DelayAndDampingOnFreshMoves : public ::testing::TestWithParam<OnMoves> {};

TEST_P(DelayAndDampingOnFreshMoves, MeetTheirRule) {
  const OnMoves& c = GetParam();
  const bool full = std::getenv("HIL_MOVES_DRAWS") != nullptr;
  const unsigned count = full ? static_cast<unsigned>(std::stoul(std::getenv("HIL_MOVES_DRAWS"))) : 8u;
  const char* first_env = std::getenv("HIL_MOVES_FIRST");
  const unsigned first = !full ? 0u : first_env ? static_cast<unsigned>(std::stoul(first_env)) : 100u;
  unsigned named = 0, single = 0, inside = 0;
  std::vector<double> z;
  for (unsigned i = first; i < first + count; ++i) {
    const unsigned seed = 32'500'000u + (c.effect == "time_offset" ? 0u : 100u) + i;
    Draws r(seed);
    ct::Scenario sc = drawn_moves(r, i, seed);
    sc.trajectory.depth_amplitude_m *= r.uniform(0.8, 1.2);
    const double truth = c.effect == "time_offset" ? r.uniform(0.005, 0.015) : r.uniform(2000.0, 6000.0);
    hide(sc, c.effect, truth);
    const Diagnosed run = diagnose_scenario(sc, {}, kFine);
    std::cout << "FRESH " << c.effect << " seed " << seed << " truth " << truth << ": " << run.line << "\n";
    if (run.d.cause != c.effect) continue;
    ++named;
    single += run.d.second_cause.empty() ? 1 : 0;
    if (!run.d.extended) continue;
    for (const auto& q : run.d.extended->full.reported)
      if (q.name == c.parameter) {
        inside += std::abs(q.value - truth) <= 1.96 * q.std ? 1 : 0;
        z.push_back((q.value - truth) / q.std);
      }
  }
  double mean_z = 0.0;
  for (const double x : z) mean_z += x / static_cast<double>(z.size());
  std::cout << "FRESH " << c.effect << ": named " << named << ", single " << single << ", inside " << inside << " of " << count
            << ", mean z " << mean_z << "\n";
  const unsigned allowed = full ? count / 8 : 1u;  // 1 of 8; the full draw at the same rate
  EXPECT_GE(named + allowed, count) << c.effect << " named first in " << named << " of " << count;
  EXPECT_GE(single + allowed, count) << "a second cause in " << count - single << " of " << count;
  // Until 2026-12-05 the damping's intervals were a known failure, not asserted (first run,
  // 2026-11-29: D inside in 3 of 8, 2-3.5 % low on the two-tone moves; the full draw 30 of 50).
  // With the clip at lift-off, the twist levels' interval term and the Hunt-Crossley form (all
  // 2026-12-03) the CI draws give 8 of 8 inside (mean z -0.55): asserted since.
  EXPECT_GE(inside + 2 * allowed, named) << c.parameter << " inside its 95 % interval in " << inside << " of " << named;
}

INSTANTIATE_TEST_SUITE_P(Issue32, DelayAndDampingOnFreshMoves,
                         ::testing::Values(OnMoves{"time_offset", "time_offset_s", 0.0},
                                           OnMoves{"contact_damping", "damping_n_s_per_m", 0.0}),
                         [](const ::testing::TestParamInfo<OnMoves>& i) { return i.param.effect; });
}  // namespace
}  // namespace hil::diagnose::test
