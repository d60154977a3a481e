// The serial-robot blind suite (issue 28 item 5; rules in docs/calibration.md, "The blind suite",
// written before its first run). The truth (serial_truth.cpp) shares nothing with the candidates:
// KDL's chain and gravity from the URDF file, the effects from the equations, in forms that differ
// from the candidates' where the physics does (springs at equilibrium, backlash with hysteresis,
// links as beams, a base on springs). Each case draws its magnitudes, station frames, tool point,
// postures and noise from seeds never used in development and passes when at least kMinRight of
// its kDraws draws are right. Every draw's verdict is printed: the record in the docs comes from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <iostream>
#include <random>
#include <set>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>

#include "blind_ur10.hpp"
#include "serial_truth.hpp"

namespace hc = hil::calibration;
namespace ts = hil::test::serial;

namespace {

using namespace hil::test::blind;
// UR10 joints in chain order.
constexpr int kShoulderLift = 1, kElbow = 2, kWrist1 = 3;

using Effect = std::function<void(ts::Truth&, std::mt19937&)>;

struct Draw {
  ts::Truth truth;
  std::vector<hc::PointObservation> obs;
};

/// Draw `i` of case `c`: seed 28,000,000 + 1,000 c + i.
Draw draw(int c, int i, const Effect& effect) {
  std::mt19937 rng(28'000'000u + 1'000u * static_cast<unsigned>(c) + static_cast<unsigned>(i));
  Draw d;
  d.truth = ur10_truth(rng);
  if (effect) effect(d.truth, rng);
  const auto postures = ts::draw_postures(kPostures, kRange, rng);
  for (const auto& s : ts::generate(d.truth, postures, rng)) {
    hc::PointObservation o;
    o.q = s.q;
    o.station = s.station;
    o.p_station_m = s.p_station_m;
    o.sigma_m = kNoise_m;
    d.obs.push_back(o);
  }
  return d;
}

// The effects, with the magnitudes of the rules.
void offsets(ts::Truth& t, std::mt19937& rng) {
  t.joint_offset_rad = Eigen::VectorXd(6);
  for (int j = 0; j < 6; ++j) t.joint_offset_rad[j] = signed_uniform(rng, 0.5e-3, 2e-3);
}
void springs(ts::Truth& t, std::mt19937& rng) {
  t.joint_stiffness_Nm_per_rad = Eigen::VectorXd::Zero(6);
  for (int j : {kShoulderLift, kElbow}) t.joint_stiffness_Nm_per_rad[j] = 1.0 / uniform(rng, 3e-6, 15e-6);
}
void backlash(ts::Truth& t, std::mt19937& rng) {
  t.backlash_rad = Eigen::VectorXd::Zero(6);
  for (int j : {kShoulderLift, kElbow, kWrist1}) t.backlash_rad[j] = uniform(rng, 0.3e-3, 1e-3);
  t.backlash_friction_Nm = Eigen::VectorXd::Constant(6, 2.0);
}
void beams(ts::Truth& t, std::mt19937& rng) {
  for (const char* link : {"upper_arm_link", "forearm_link"}) t.beams.push_back({link, uniform(rng, 3e4, 1e5), 0.0});
}
void base_springs(ts::Truth& t, std::mt19937& rng) { t.base_stiffness_Nm_per_rad = uniform(rng, 2e5, 6e5); }

std::string named(const hc::PointComparison& c, int row) {
  return row < 0 ? "" : hc::to_string(c.rows[static_cast<std::size_t>(row)].model);
}

/// Runs the case's draws, prints each verdict, and counts the draws `right` accepts.
int run_case(int c, const std::string& name, const Effect& effect,
             const std::function<bool(const hc::PointComparison&, const ts::Truth&)>& right) {
  int ok = 0;
  for (int i = 0; i < kDraws; ++i) {
    const Draw d = draw(c, i, effect);
    const auto cmp = hc::compare_point_candidates(ur10(), d.obs, kStations, hc::point_candidates());
    const bool r = right(cmp, d.truth);
    ok += r ? 1 : 0;
    std::cout << "[blind] " << name << " draw " << i << ": " << (r ? "right" : "WRONG") << " | " << cmp.kind << " | " << cmp.verdict
              << "\n";
  }
  std::cout << "[blind] " << name << ": " << ok << " of " << kDraws << " right (pass: " << kMinRight << ")\n";
  return ok;
}

/// Cases 6 and 7 failed their rule on the suite's first run (2026-11-28) and stay in the suite: they
/// run and print every draw. Their rule, "not claimed", was written for effects outside the
/// library; both effects have since entered it (link_bending, base_compliance) and are tested under
/// their own rules in test_point_blind_library (cases 8 and 13). So a miss is reported as a
/// superseded rule (skipped, with the count and why) instead of failing CI. The rule is not changed.
void expect_or_superseded(int right, const std::string& why) {
  if (right >= kMinRight) return;
  GTEST_SKIP() << "rule superseded (docs/calibration.md, the blind suite's first and fourth series): " << right << " of " << kDraws
               << " right under the rule written when the effect was outside the library, " << kMinRight << " required. " << why;
}

bool not_claimed(const hc::PointComparison& c) { return c.kind == "unexplained" || (c.kind == "cause" && !c.noise.after_within); }

}  // namespace

TEST(PointBlind, CleanRobotIsNone) {
  EXPECT_GE(run_case(1, "clean", nullptr, [](const auto& c, const auto&) { return c.kind == "none"; }), kMinRight);
}

TEST(PointBlind, JointOffsetsAreNamedAlone) {
  EXPECT_GE(run_case(2, "offsets", offsets,
                     [](const auto& c, const auto&) {
                       return named(c, c.cause) == "joint_offsets" && c.second_cause < 0 && c.noise.after_within;
                     }),
            kMinRight);
}

TEST(PointBlind, JointSpringsAreNamedAlone) {
  EXPECT_GE(run_case(3, "springs", springs,
                     [](const auto& c, const auto&) {
                       return named(c, c.cause) == "joint_compliance" && c.second_cause < 0 && c.noise.after_within;
                     }),
            kMinRight);
}

TEST(PointBlind, BacklashIsNamedFirst) {
  EXPECT_GE(run_case(4, "backlash", backlash, [](const auto& c, const auto&) { return named(c, c.cause) == "backlash"; }), kMinRight);
}

TEST(PointBlind, OffsetsAndSpringsAreBothNamed) {
  EXPECT_GE(run_case(
                5, "offsets+springs",
                [](ts::Truth& t, std::mt19937& rng) {
                  offsets(t, rng);
                  springs(t, rng);
                },
                [](const auto& c, const auto&) {
                  if (c.cause < 0 || c.second_cause < 0) return false;
                  const auto& m = c.rows[static_cast<std::size_t>(c.second_cause)].model;
                  return std::set<hc::PointCandidate>(m.begin(), m.end()) ==
                         std::set<hc::PointCandidate>{hc::PointCandidate::joint_offsets, hc::PointCandidate::joint_compliance};
                }),
            kMinRight);
}

TEST(PointBlind, BendingLinksAreNotClaimed) {
  expect_or_superseded(run_case(6, "beams (outside the library)", beams, [](const auto& c, const auto&) { return not_claimed(c); }),
                       "At these magnitudes a link bending under gravity is a joint compliance within the noise (the end rotation "
                       "follows the gravity torque; the translation it adds is below 50 um): joint_compliance is named and leaves "
                       "the noise. Since then link_bending is in the library, which names the beams (case 8 of the second series, "
                       "test_point_blind_library); this case's rule, written when they were outside it, can no longer hold.");
}

TEST(PointBlind, ABaseOnSpringsIsNotClaimed) {
  expect_or_superseded(run_case(7, "base springs (outside the library)", base_springs,
                                [](const auto& c, const auto&) { return not_claimed(c); }),
                       "A base tilting by 0.2-1 mrad under the arm's moment was, before base_compliance, explained within the "
                       "noise by joint compliance (mostly the shoulder lift's) with the geometric set as second cause. Since then "
                       "measured_tilt (case 9) and base_compliance (case 13, test_point_blind_library) are in the library, and "
                       "base_compliance names these draws; this case's rule, written when the effect was outside it, can no longer "
                       "hold.");
}

namespace {

struct Coverage {
  int intervals = 0, above = 0, below = 0;
  double width_sum = 0.0;
  void add(double value, double std, double truth) {
    ++intervals;
    width_sum += 2 * 1.96 * std;
    if (truth > value + 1.96 * std) ++above;
    if (truth < value - 1.96 * std) ++below;
  }
  double rate() const { return intervals ? 1.0 - static_cast<double>(above + below) / intervals : 0.0; }
};

/// The 95 % intervals of `model` fitted to every posture of case c's draws; `truth_of` gives a
/// parameter's truth (NaN: not counted).
Coverage coverage(int c, const Effect& effect, const hc::PointModel& model,
                  const std::function<double(const std::string&, const ts::Truth&)>& truth_of, const std::string& name) {
  Coverage cov;
  for (int i = 0; i < kDraws; ++i) {
    const Draw d = draw(c, i, effect);
    const auto fit = hc::fit_points(ur10(), d.obs, kStations, model);
    for (const auto& p : fit.parameters) {
      const double t = truth_of(p.name, d.truth);
      if (std::isnan(t) || !p.identifiable) continue;
      cov.add(p.value, p.std, t);
    }
  }
  std::cout << "[blind] coverage " << name << ": " << cov.intervals << " intervals, " << cov.rate() * 100 << " % cover, " << cov.above
            << " missed above, " << cov.below << " below, mean width " << (cov.intervals ? cov.width_sum / cov.intervals : 0.0) << "\n";
  return cov;
}

void expect_coverage(const Coverage& cov) {
  ASSERT_GT(cov.intervals, 0);
  EXPECT_GE(cov.rate(), 0.85);
  EXPECT_LE(cov.above, cov.intervals / 10);
  EXPECT_LE(cov.below, cov.intervals / 10);
}

double joint_truth(const std::string& name, const std::string& prefix, const Eigen::VectorXd& values, bool inverse) {
  for (std::size_t j = 0; j < ur10().joints.size(); ++j) {
    if (name != prefix + ur10().joints[j].name || values.size() == 0) continue;
    const double v = values[static_cast<Eigen::Index>(j)];
    if (inverse) return v > 0 ? 1.0 / v : std::nan("");
    return v;
  }
  return std::nan("");
}

}  // namespace

TEST(PointBlind, OffsetIntervalsCoverTheTruth) {
  expect_coverage(coverage(
      2, offsets, {hc::PointCandidate::joint_offsets},
      [](const std::string& n, const ts::Truth& t) { return joint_truth(n, "offset ", t.joint_offset_rad, false); }, "offsets"));
}

TEST(PointBlind, ComplianceIntervalsCoverTheTruth) {
  expect_coverage(coverage(
      3, springs, {hc::PointCandidate::joint_compliance},
      [](const std::string& n, const ts::Truth& t) { return joint_truth(n, "compliance ", t.joint_stiffness_Nm_per_rad, true); },
      "compliance (1/k)"));
}

TEST(PointBlind, BacklashIntervalsAreReported) {
  // Reported, not gated: the truth's hysteresis is a form the candidate does not have.
  const auto cov = coverage(
      4, backlash, {hc::PointCandidate::backlash},
      [](const std::string& n, const ts::Truth& t) {
        const double v = joint_truth(n, "backlash ", t.backlash_rad, false);
        return v > 0 ? v : std::nan("");
      },
      "backlash (reported)");
  EXPECT_GT(cov.intervals, 0);
}
