// hil::models's contact adapters: the truth file and the trajectory reader refuse bad input, naming
// file, line and field.
#include <gtest/gtest.h>

#include <string>

#include <hil/error/error.hpp>
#include <hil/format/rig.hpp>
#include <hil/models/contact.hpp>
#include <hil/test/files.hpp>

namespace hil::test {
namespace {

TEST(RigContact, BadTruthAndTrajectoryFilesAreRefusedWithWhereAndWhat) {
  hil::test::TempDir dir;
  const auto rig = format::load_rig(std::string(HIL_SOURCE_DIR) + "/examples/acu/acu.yaml");
  // Unknown key and unknown uncertainty in a truth file: file, line and field named.
  const auto bad = dir.file("truth.yaml", "stiffness_n_per_m: 1.8e5\nfriction: 0.2\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(bad, rig); }, 2, "friction",
                                    "unknown field; known here: stiffness_n_per_m, friction_coefficient"));
  const auto neg = dir.file("neg.yaml", "stiffness_n_per_m: -1\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(neg, rig); }, 1, "stiffness_n_per_m",
                                    "expected a positive number, found -1"));
  // The sensor's seed and resolutions are checked too, with their line.
  const auto seed = dir.file("seed.yaml", "stiffness_n_per_m: 1.8e5\nsensor:\n  force_noise_n: 0.1\n  seed: -3\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(seed, rig); }, 4, "sensor.seed", "expected a seed from 0 to"));
  const auto res = dir.file("res.yaml", "sensor:\n  force_resolution_n: -0.05\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(res, rig); }, 2, "sensor.force_resolution_n", "expected a number >= 0"));
  const auto syntax = dir.file("syntax.yaml", "stiffness_n_per_m: [1\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(syntax, rig); }, 0, "", "YAML syntax error"));
  // The same reader on text (what the fuzz target drives) names the display name; a missing file is named.
  try {
    (void)hil::models::parse_truth("stiffness_n_per_m: 1.8e5\nfriction: 0.2\n", "inline.yaml", rig);
    ADD_FAILURE() << "no exception";
  } catch (const error::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("inline.yaml"), std::string::npos) << e.what();
  }
  EXPECT_EQ(hil::models::parse_truth("stiffness_n_per_m: 2.5e5\n", "inline.yaml", rig).model.K, 2.5e5);
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_truth(dir.path() + "/absent.yaml", rig); }, 0, "", "cannot open the file"));
  // An uncertainty the rig does not declare: the file and the name.
  try {
    hil::models::uncertainty_vector(hil::models::scene_from_rig(rig), {{"guide9_shift", 1e-4}}, "truth.yaml");
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("truth.yaml: unknown geometric uncertainty 'guide9_shift'"), std::string::npos) << e.what();
  }
  // A trajectory whose time goes backwards.
  const auto tr = dir.file("t.csv", "t,px,py,pz,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n0.1,0,0,0,1,0,0,0\n0.05,0,0,0,1,0,0,0\n");
  EXPECT_TRUE(hil::test::fails_with([&] { hil::models::read_trajectory(tr); }, 4, "t", "increase"));
}

}  // namespace
}  // namespace hil::test
