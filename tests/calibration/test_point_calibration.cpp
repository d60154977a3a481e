// Point calibration (calibration/src/point_calibration.cpp) on data from an independent generator
// (kdl_point_truth.cpp: Orocos KDL's kinematics and gravity from the UR10's URDF). The rules were
// written before the draws: identifiable parameters within 4 standard deviations of the truth,
// the undetermined combinations named, the noise estimated within a factor 1.4, the named cause
// the hidden effect, no cause on a clean robot.
#include <gtest/gtest.h>

#include <random>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>

#include "kdl_point_truth.hpp"

namespace hc = hil::calibration;

namespace {

const std::string kUr10 = std::string(HIL_SOURCE_DIR) + "/examples/robots/ur10.urdf";

hc::SerialRobot ur10() { return hil::models::to_serial_robot(hil::format::read_urdf_robot(kUr10, "base_link", "wrist_3_link")); }

std::vector<hc::PointObservation> observations(const std::vector<hil::test::PointSample>& s) {
  std::vector<hc::PointObservation> o;
  for (const auto& x : s) {
    hc::PointObservation p;
    p.q = x.q;
    p.station = x.station;
    p.p_station_m = x.p_station_m;
    o.push_back(p);
  }
  return o;
}

hil::test::PointTruth base_truth(std::mt19937& rng, int stations) {
  hil::test::PointTruth t;
  for (int s = 0; s < stations; ++s) t.T_station_base.push_back(hil::test::random_station(rng, 3.0, 3.0));
  t.tool_point_m = Eigen::Vector3d(0.02, -0.01, 0.08);
  t.noise_m = 50e-6;
  return t;
}

bool mentions(const std::vector<hc::Undetermined>& u, const std::string& name) {
  for (const auto& c : u)
    for (const auto& [n, w] : c.terms)
      if (n == name) return true;
  return false;
}

const hc::PointParameter& param(const hc::PointFit& f, const std::string& name) {
  for (const auto& p : f.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

}  // namespace

TEST(PointCalibration, JointOffsetsAreRecoveredAndTheUndeterminedOnesNamed) {
  std::mt19937 rng(4101);
  const hc::SerialRobot robot = ur10();
  auto truth = base_truth(rng, 2);
  truth.joint_offset_rad = Eigen::VectorXd(6);
  for (int j = 0; j < 6; ++j) truth.joint_offset_rad[j] = std::uniform_real_distribution<double>(-3e-3, 3e-3)(rng);
  const auto obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", truth, 60, rng));

  // Before anything is estimated: which offsets the postures cannot tell from the nuisance frames.
  const auto before = hc::identifiability(robot, obs, 2, {hc::PointCandidate::joint_offsets});
  EXPECT_TRUE(mentions(before.undetermined, "offset shoulder_pan_joint"));  // = turning the stations about the base z axis
  EXPECT_TRUE(mentions(before.undetermined, "offset wrist_3_joint"));       // = turning the tool point about the last axis
  EXPECT_EQ(before.rank, before.parameters_total - static_cast<int>(before.undetermined.size()));

  const auto rigid = hc::fit_points(robot, obs, 2, {});
  const auto fit = hc::fit_points(robot, obs, 2, {hc::PointCandidate::joint_offsets});
  EXPECT_GT(rigid.rms_m, 10 * truth.noise_m);
  EXPECT_GT(fit.sigma_m, truth.noise_m / 1.4);
  EXPECT_LT(fit.sigma_m, truth.noise_m * 1.4);
  int checked = 0;
  for (int j = 0; j < 6; ++j) {
    const auto& p = param(fit, "offset " + robot.joints[static_cast<std::size_t>(j)].name);
    if (j == 0 || j == 5) {
      EXPECT_FALSE(p.identifiable) << p.name;
      continue;
    }
    ASSERT_TRUE(p.identifiable) << p.name;
    EXPECT_LT(std::abs(p.value - truth.joint_offset_rad[j]), 4 * p.std) << p.name << " " << p.value << " vs " << truth.joint_offset_rad[j];
    EXPECT_LT(p.std, 2e-4) << p.name;  // determined, not merely consistent
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

TEST(PointCalibration, GravityComplianceIsNamedAndAcleanRobotHasNoCause) {
  std::mt19937 rng(4202);
  const hc::SerialRobot robot = ur10();
  auto truth = base_truth(rng, 2);
  truth.joint_compliance = Eigen::VectorXd::Zero(6);
  truth.joint_compliance[1] = std::uniform_real_distribution<double>(5e-6, 2e-5)(rng);  // shoulder lift, rad/(N·m)
  truth.joint_compliance[2] = std::uniform_real_distribution<double>(5e-6, 2e-5)(rng);  // elbow
  const auto obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", truth, 60, rng));
  const auto cmp = hc::compare_point_candidates(robot, obs, 2, hc::point_candidates());
  ASSERT_GE(cmp.cause, 0) << cmp.verdict;
  EXPECT_EQ(hc::to_string(cmp.rows[static_cast<std::size_t>(cmp.cause)].model), "joint_compliance") << cmp.verdict;
  EXPECT_EQ(cmp.rigid.scheme, "leave one station out");
  // Its parameters: the two compliant joints within 4 σ.
  const auto fit = hc::fit_points(robot, obs, 2, {hc::PointCandidate::joint_compliance});
  for (int j : {1, 2}) {
    const auto& p = param(fit, "compliance " + robot.joints[static_cast<std::size_t>(j)].name);
    ASSERT_TRUE(p.identifiable) << p.name;
    EXPECT_LT(std::abs(p.value - truth.joint_compliance[j]), 4 * p.std) << p.name;
  }

  auto clean = base_truth(rng, 2);
  const auto clean_obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", clean, 60, rng));
  const auto none = hc::compare_point_candidates(robot, clean_obs, 2, hc::point_candidates());
  EXPECT_EQ(none.cause, -1) << none.verdict;
  EXPECT_LT(none.rigid.rms_m, 3 * std::sqrt(3.0) * clean.noise_m);
}

TEST(PointCalibration, OneStationIsCrossValidatedByPostures) {
  std::mt19937 rng(4303);
  const hc::SerialRobot robot = ur10();
  auto truth = base_truth(rng, 1);
  truth.joint_offset_rad = Eigen::VectorXd::Zero(6);
  truth.joint_offset_rad[2] = 4e-3;
  const auto obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", truth, 30, rng));
  const auto h = hc::held_out_error(robot, obs, 1, {hc::PointCandidate::joint_offsets});
  EXPECT_EQ(h.scheme, "leave one posture out");
  EXPECT_EQ(h.error_m.size(), 30);
  const auto r = hc::held_out_error(robot, obs, 1, {}, 5);
  EXPECT_EQ(r.scheme, "5-fold over postures");
  EXPECT_GT(r.rms_m, 3 * h.rms_m);
}

TEST(PointCalibration, TooFewPosturesOrMissingInertialsAreRefusedByName) {
  const hc::SerialRobot robot = ur10();
  std::vector<hc::PointObservation> two(2);
  for (auto& p : two) p.q = Eigen::VectorXd::Zero(6);
  EXPECT_THROW(hc::fit_points(robot, two, 1, {}), std::invalid_argument);
  hc::SerialRobot bare = robot;
  bare.inertials.clear();
  std::vector<hc::PointObservation> four(4);
  for (std::size_t k = 0; k < 4; ++k) {
    four[k].q = Eigen::VectorXd::Constant(6, 0.3 * static_cast<double>(k));
    four[k].p_station_m = Eigen::Vector3d(static_cast<double>(k), static_cast<double>(k * k), 1.0);
  }
  try {
    hc::fit_points(bare, four, 1, {hc::PointCandidate::joint_compliance});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("inertials"), std::string::npos) << e.what();
  }
}
