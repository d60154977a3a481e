// Hidden-effect tests (issue 6): an effect (or two) with a seeded random magnitude is injected into a
// simulated run of the re-created ACU experiment or of the press bench; the diagnosis runs blind;
// the test knows the truth and checks the named cause, its magnitude against the reported interval
// and a positive held-out gain. On clean data the answer must be `none`.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include "scenes.hpp"

namespace hil::diagnose {
namespace {

struct Case {
  std::string scene;
  std::vector<std::string> effects;
  unsigned seed;
};

std::string label(const Case& c) {
  std::string n = c.scene;
  for (const auto& e : c.effects) n += "_" + e;
  if (c.effects.empty()) n += "_clean";
  return n + "_" + std::to_string(c.seed);
}
std::string case_name(const ::testing::TestParamInfo<Case>& i) { return label(i.param); }
// Readable test names in ctest (instead of the parameter's bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << label(c); }

class HiddenEffect : public ::testing::TestWithParam<Case> {};

TEST_P(HiddenEffect, IsNamedWithItsMagnitudeAndAGain) {
  const auto& c = GetParam();
  const auto r = test::scene_run(c.scene);
  Effects e;
  for (const auto& name : c.effects) draw_effect(name, c.seed, r.scene, e);
  const auto data = make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, c.seed), r.force_scale_n, r.moment_scale_nm);
  const ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(data, x); };
  const Diagnosis d = diagnose(make, contact_extensions(), data.obs, {});
  std::string table;
  for (const auto& k : d.candidates)
    table += "  " + k.name + ": " + std::to_string(100 * k.score.cv_error) + " % (" + std::to_string(k.noise_fraction) + ") " + k.verdict +
             "\n";
  for (const auto& k : d.second_step) table += "  + " + k.name + ": " + k.verdict + "\n";
  SCOPED_TRACE("nominal " + std::to_string(100 * d.nominal.cv_error) + " %, noise " + std::to_string(100 * d.noise_relative) +
               " %, excess " + std::to_string(d.nominal_residuals.excess_variance) +
               ", structure: " + d.nominal_residuals.structure_text() + ", candidates:\n" + table);

  if (c.effects.empty()) {
    EXPECT_EQ(d.cause, "none");
    EXPECT_EQ(d.second_cause, "");
    EXPECT_EQ(d.gain_percent, 0.0);
    return;
  }
  if (c.effects.size() == 2) {
    const std::set<std::string> named{d.cause, d.second_cause};
    EXPECT_EQ(named, std::set<std::string>(c.effects.begin(), c.effects.end()));
  } else {
    EXPECT_EQ(d.cause, c.effects.front());
    EXPECT_EQ(d.second_cause, "") << "a second cause on a run with one hidden effect";
  }
  EXPECT_GT(d.gain_percent, 0.0);
  ASSERT_TRUE(d.extended.has_value());
  // The cause's parameters: the truth inside the reported interval (3 std: 99.7 %) wherever the
  // diagnosis calls them practically identifiable; at least one must be. On the ACU scene the
  // paper's undithered 2 µm / 1.5 N quantisation biases some estimates by up to ~12 %, more than
  // their statistical interval (docs/diagnosis.md): there the test allows 15 % of the value.
  const double rel = c.scene.rfind("acu_", 0) == 0 ? 0.15 : 0.0;
  int checked = 0;
  for (const auto& q : d.extended->full.reported) {
    const auto t = e.truth_of(q.name, r.scene);
    if (!t || !(q.extension || q.name.rfind("C_", 0) == 0) || q.pnr() < 5.0) continue;
    if (std::find(c.effects.begin(), c.effects.end(), d.cause) == c.effects.end()) continue;
    ++checked;
    EXPECT_LE(std::abs(q.value - *t), std::max(3.0 * q.std, rel * std::abs(*t - q.nominal)))
        << q.name << " = " << q.value << " ± " << q.std << ", truth " << *t;
  }
  EXPECT_GE(checked, 1);
}

INSTANTIATE_TEST_SUITE_P(Acu, HiddenEffect,
                         ::testing::Values(Case{"acu_2a", {}, 11}, Case{"acu_2a", {"sensor_bias"}, 12}, Case{"acu_2a", {"sensor_gain"}, 13},
                                           Case{"acu_2a", {"time_offset"}, 14}, Case{"acu_2a", {"viscous_friction"}, 15},
                                           Case{"acu_2a", {"contact_damping"}, 16}, Case{"acu_2a", {"nonlinear_stiffness"}, 17},
                                           // robot_compliance: see RobotComplianceOnAcu2a below
                                           Case{"acu_2a", {"geometric_offset"}, 19}, Case{"acu_1a", {}, 21},
                                           Case{"acu_1a", {"viscous_friction"}, 22},
                                           Case{"acu_2a", {"sensor_bias", "viscous_friction"}, 23}),
                         case_name);

INSTANTIATE_TEST_SUITE_P(Press, HiddenEffect,
                         ::testing::Values(Case{"press_slide", {}, 31}, Case{"press_slide", {"sensor_bias"}, 32},
                                           Case{"press_slide", {"sensor_gain"}, 33}, Case{"press_slide", {"time_offset"}, 34},
                                           Case{"press_slide", {"viscous_friction"}, 35}, Case{"press_slide", {"nonlinear_stiffness"}, 36},
                                           Case{"press_slide", {"geometric_offset"}, 37}),
                         case_name);

// A lateral wrist compliance on ACU 2a: in series with the V-guides' contact stiffness it softens
// the contact under load, which a Hertz-like exponent also describes. Scored leak-free (each fold
// fitted without its held-out block), nonlinear_stiffness predicts held-out data better on this
// trajectory (54.9 % against 50.4 % gain) and the compliance adds nothing consistent on top of it
// (docs/diagnosis.md, Known limits). What the test holds the diagnosis to: the compliance is
// supported on its own, physical (a positive semi-definite compliance with its identifiable
// coordinates exists), within a tenth of the cause's gain, and the cause is one of the two
// descriptions of the softening (nothing else).
TEST(HiddenEffectPair, RobotComplianceOnAcu2aIsSupportedBesideTheStiffeningItResembles) {
  const auto data = test::hidden_contact_data(test::scene_run("acu_2a"), "robot_compliance", 18);
  const Diagnosis d = diagnose(test::contact_factory(data), contact_extensions(), data.obs, {});
  std::string table;
  for (const auto& k : d.candidates) table += "  " + k.name + ": " + k.verdict + "\n";
  for (const auto& k : d.second_step) table += "  + " + k.name + ": " + k.verdict + "\n";
  SCOPED_TRACE("cause " + d.cause + ", second " + d.second_cause + ":\n" + table);
  EXPECT_TRUE(d.cause == "robot_compliance" || d.cause == "nonlinear_stiffness");
  EXPECT_GT(d.gain_percent, 0.0);
  bool seen = false;
  for (const auto& k : d.candidates)
    if (k.name == "robot_compliance") {
      seen = true;
      EXPECT_EQ(k.score.full.invalid, "");
      EXPECT_TRUE(k.supported);
      EXPECT_GT(k.gain_percent, d.candidates.front().gain_percent - 10.0);
    }
  EXPECT_TRUE(seen);
}

}  // namespace
}  // namespace hil::diagnose
