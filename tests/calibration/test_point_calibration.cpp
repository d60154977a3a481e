// Point calibration (calibration/src/point_calibration.cpp) on data from an independent generator
// (kdl_point_truth.cpp: Orocos KDL's kinematics and gravity from the UR10's URDF). The rules were
// written before the draws: identifiable parameters within 4 standard deviations of the truth,
// the undetermined combinations named, the noise estimated within a factor 1.4, the named cause
// the hidden effect, no cause on a clean robot.
#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <set>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>

#include "kdl_point_truth.hpp"
#include "serial_truth.hpp"

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

/// `n` UR10 postures from `stations` stations with one joint's offset hidden.
std::vector<hc::PointObservation> one_offset_run(std::mt19937& rng, int stations, int joint, double offset_rad, int n) {
  auto truth = base_truth(rng, stations);
  truth.joint_offset_rad = Eigen::VectorXd::Zero(6);
  truth.joint_offset_rad[joint] = offset_rad;
  return observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", truth, n, rng));
}

const hc::PointParameter& param(const hc::PointFit& f, const std::string& name) {
  for (const auto& p : f.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

namespace ts = hil::test::serial;
const std::vector<std::pair<double, double>> kUr10Range = {{-3.0, 3.0}, {-2.6, -0.5}, {-2.5, 2.5}, {-3.0, 3.0}, {-3.0, 3.0}, {-3.0, 3.0}};

/// The serial truth's UR10 with `stations` random stations and a fixed tool point, no effect yet.
ts::Truth serial_ur10(std::mt19937& rng, int stations) {
  ts::Truth t;
  t.urdf = kUr10;
  t.base = "base_link";
  t.tip = "wrist_3_link";
  for (int s = 0; s < stations; ++s) t.T_station_base.push_back(ts::random_station(rng, 3.0, 3.0));
  t.tool_point_m = Eigen::Vector3d(0.03, -0.02, 0.12);
  return t;
}

/// `n` postures of the truth, drawn in kUr10Range, as observations (points only).
std::vector<hc::PointObservation> serial_run(const ts::Truth& t, int n, std::mt19937& rng) {
  std::vector<hc::PointObservation> run;
  for (const auto& s : ts::generate(t, ts::draw_postures(n, kUr10Range, rng), rng)) {
    hc::PointObservation o;
    o.q = s.q;
    o.station = s.station;
    o.p_station_m = s.p_station_m;
    run.push_back(o);
  }
  return run;
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
  const auto obs = one_offset_run(rng, 1, 2, 4e-3, 30);
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

namespace {

/// A random point in a model's parameter space, every block moved by a realistic-to-large amount
/// (rotations up to 0.1 rad so that the rotation Jacobians' Jr(ω) matters).
Eigen::VectorXd random_dx(std::mt19937& rng, int stations, int dof, const hc::PointModel& model) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v;
  for (int s = 0; s < stations; ++s)
    for (int a = 0; a < 6; ++a) v.push_back((a < 3 ? 0.1 : 0.2) * u(rng));
  for (int a = 0; a < 3; ++a) v.push_back(0.05 * u(rng));
  for (const auto c : model) {
    for (int i = 0; i < dof; ++i) {
      if (c == hc::PointCandidate::geometric)
        for (int a = 0; a < 6; ++a) v.push_back((a < 3 ? 0.05 : 0.1) * u(rng));
      else v.push_back((c == hc::PointCandidate::joint_compliance ? 2e-5 : 0.05) * u(rng));
    }
  }
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

/// Largest column error of the closed-form Jacobian relative to the column's size (columns below
/// 1e-3 of the largest, such as a wrist's compliance under almost no torque, relative to that
/// floor: there the differences' rounding is all that differs).
double worst_column_error(const std::pair<Eigen::MatrixXd, Eigen::MatrixXd>& J) {
  const double floor = 1e-3 * J.second.colwise().norm().maxCoeff();
  double worst = 0.0;
  for (Eigen::Index j = 0; j < J.first.cols(); ++j)
    worst = std::max(worst, (J.first.col(j) - J.second.col(j)).norm() / std::max(floor, J.second.col(j).norm()));
  return worst;
}

std::vector<hc::PointObservation> random_postures(std::mt19937& rng, int dof, int n, int stations) {
  std::vector<hc::PointObservation> obs(static_cast<std::size_t>(n));
  std::uniform_real_distribution<double> q(-2.5, 2.5), p(-1.0, 1.0);
  for (int k = 0; k < n; ++k) {
    auto& o = obs[static_cast<std::size_t>(k)];
    o.q.resize(dof);
    for (int j = 0; j < dof; ++j) o.q[j] = q(rng);
    o.station = k % stations;
    o.p_station_m = Eigen::Vector3d(p(rng), p(rng), p(rng));
  }
  return obs;
}

}  // namespace

// The closed-form Jacobian (the one every fit uses) against central differences of the residual,
// away from the start, for URDF, standard-DH and modified-DH robots and a prismatic joint.
TEST(PointCalibration, ClosedFormJacobianEqualsCentralDifferences) {
  std::mt19937 rng(4404);
  struct Case {
    std::string what;
    hc::SerialRobot robot;
    std::vector<hc::PointModel> models;
  };
  std::vector<Case> cases;
  const hc::PointModel all = {hc::PointCandidate::joint_offsets, hc::PointCandidate::joint_compliance, hc::PointCandidate::backlash,
                              hc::PointCandidate::geometric};
  cases.push_back({"UR10 (URDF)",
                   ur10(),
                   {{},
                    {hc::PointCandidate::joint_offsets},
                    {hc::PointCandidate::joint_compliance},
                    {hc::PointCandidate::backlash},
                    {hc::PointCandidate::geometric},
                    all}});
  const hc::PointModel kinematic = {hc::PointCandidate::joint_offsets, hc::PointCandidate::geometric};
  cases.push_back({"KR-270-like (standard DH)", hc::kr270_like(), {{hc::PointCandidate::geometric}, kinematic}});
  hc::SerialRobot modified = hc::kr270_like();
  modified.convention = hc::DhConvention::modified;
  modified.T_flange_ee.translation() = Eigen::Vector3d(0.01, 0.02, 0.15);
  cases.push_back({"KR-270-like read as modified DH", modified, {kinematic}});
  hc::SerialRobot prismatic = hc::kr270_like();
  prismatic.joints[2].kind = hc::JointKind::prismatic;
  cases.push_back({"a prismatic third joint", prismatic, {kinematic}});
  for (const auto& c : cases) {
    const int stations = 2;
    const auto obs = random_postures(rng, c.robot.dof(), 12, stations);
    for (const auto& m : c.models) {
      const auto J = hc::detail::point_jacobians(c.robot, obs, stations, m, random_dx(rng, stations, c.robot.dof(), m));
      ASSERT_EQ(J.first.rows(), J.second.rows());
      ASSERT_EQ(J.first.cols(), J.second.cols());
      EXPECT_LT(worst_column_error(J), 1e-6) << c.what << ", model " << hc::to_string(m);
    }
  }
}

// The folds and candidate models run on several threads; the outcome must be the serial one,
// bit for bit, and the closed-form fits must land where the central-difference fits do.
TEST(PointCalibration, ThreadsAndJacobianChoiceDoNotChangeTheResult) {
  std::mt19937 rng(4505);
  const hc::SerialRobot robot = ur10();
  const auto obs = one_offset_run(rng, 3, 1, 2e-3, 36);
  hc::PointFitOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = hc::compare_point_candidates(robot, obs, 3, hc::point_candidates(), 0, one);
  const auto b = hc::compare_point_candidates(robot, obs, 3, hc::point_candidates(), 0, two);
  EXPECT_EQ(a.verdict, b.verdict);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(a.rows[i].held_out.error_m, b.rows[i].held_out.error_m) << hc::to_string(a.rows[i].model);
    EXPECT_EQ(a.rows[i].rank, b.rows[i].rank);
  }
  EXPECT_EQ(hc::to_string(a.rows[static_cast<std::size_t>(a.cause)].model), "joint_offsets") << a.verdict;

  hc::PointFitOptions fd;
  fd.analytic_jacobian = false;
  const hc::PointModel m = {hc::PointCandidate::joint_offsets};
  const auto closed = hc::fit_points(robot, obs, 3, m);
  const auto differences = hc::fit_points(robot, obs, 3, m, fd);
  EXPECT_NEAR(closed.rms_m, differences.rms_m, 1e-9);
  EXPECT_EQ(closed.rank, differences.rank);
  for (std::size_t j = 0; j < closed.parameters.size(); ++j) {
    const auto& p = closed.parameters[j];
    const auto& q = differences.parameters[j];
    EXPECT_NEAR(p.value, q.value, 1e-7 + 1e-4 * std::abs(q.value)) << p.name;
    if (p.identifiable) {
      EXPECT_NEAR(p.std, q.std, 1e-4 * q.std) << p.name;
    }
  }
}

// Hidden joint offsets and joint compliance: the geometric set explains the offsets as well as the
// offsets do (a rotation of each frame about its joint's axis), with five more parameters per joint.
// The smaller candidate it contains is named, and the geometric set's claim is stated and refused.
TEST(PointCalibration, NestedCandidatesGiveWayToTheSmallerOne) {
  std::mt19937 rng(4606);
  const hc::SerialRobot robot = ur10();
  auto truth = base_truth(rng, 3);
  truth.joint_offset_rad = Eigen::VectorXd(6);
  truth.joint_compliance = Eigen::VectorXd::Zero(6);
  for (int j = 0; j < 6; ++j) truth.joint_offset_rad[j] = std::uniform_real_distribution<double>(-3e-3, 3e-3)(rng);
  for (int j : {1, 2}) truth.joint_compliance[j] = std::uniform_real_distribution<double>(5e-6, 2e-5)(rng);
  const auto obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", truth, 90, rng));
  const auto cmp = hc::compare_point_candidates(robot, obs, 3, hc::point_candidates());
  ASSERT_GE(cmp.cause, 0) << cmp.verdict;
  EXPECT_EQ(hc::to_string(cmp.rows[static_cast<std::size_t>(cmp.cause)].model), "joint_offsets") << cmp.verdict;
  ASSERT_GE(cmp.second_cause, 0) << cmp.verdict;
  EXPECT_EQ(hc::to_string(cmp.rows[static_cast<std::size_t>(cmp.second_cause)].model), "joint_offsets+joint_compliance") << cmp.verdict;
  EXPECT_NE(cmp.reduced.find("not geometric"), std::string::npos) << cmp.reduced;
  // No pair of nested candidates is tried as a cause and its second.
  for (const auto& r : cmp.rows) EXPECT_NE(hc::to_string(r.model), "joint_offsets+geometric");
  EXPECT_TRUE(hc::contains(hc::PointCandidate::geometric, hc::PointCandidate::joint_offsets));
  EXPECT_FALSE(hc::contains(hc::PointCandidate::joint_offsets, hc::PointCandidate::geometric));
}

// With the measurement noise stated, `none` is a finding (the rigid model is within it) and a
// residual above it with no candidate passing is `unexplained`, not `none`.
TEST(PointCalibration, StatedNoiseTellsNoneFromUnexplained) {
  std::mt19937 rng(4707);
  const hc::SerialRobot robot = ur10();
  const auto clean = base_truth(rng, 2);
  auto obs = observations(hil::test::generate_points(kUr10, "base_link", "wrist_3_link", clean, 60, rng));
  const auto unstated = hc::compare_point_candidates(robot, obs, 2, hc::point_candidates());
  EXPECT_FALSE(unstated.noise.stated);
  EXPECT_EQ(unstated.kind, "none");
  EXPECT_NE(unstated.verdict.find("no measurement noise stated"), std::string::npos) << unstated.verdict;

  for (auto& o : obs) o.sigma_m = clean.noise_m;
  const auto within = hc::compare_point_candidates(robot, obs, 2, hc::point_candidates());
  ASSERT_TRUE(within.noise.stated);
  EXPECT_TRUE(within.noise.within) << within.verdict;
  EXPECT_EQ(within.kind, "none");
  EXPECT_EQ(within.cause, -1);
  EXPECT_EQ(within.noise.dof, 3 * 60 - 15);  // two stations' frames (6 each) and the tool point (3)
  EXPECT_NEAR(within.noise.rms_over_sigma, 1.0, 0.25);

  for (auto& o : obs) o.sigma_m = clean.noise_m / 5;  // a device believed five times better than it is
  const auto above = hc::compare_point_candidates(robot, obs, 2, hc::point_candidates());
  EXPECT_FALSE(above.noise.within);
  EXPECT_EQ(above.kind, "unexplained") << above.verdict;
  EXPECT_NE(above.verdict.find("times the stated noise"), std::string::npos) << above.verdict;

  auto moved = one_offset_run(rng, 2, 2, 1e-3, 60);
  for (auto& o : moved) o.sigma_m = clean.noise_m;
  const auto named = hc::compare_point_candidates(robot, moved, 2, hc::point_candidates());
  EXPECT_FALSE(named.noise.within);
  EXPECT_EQ(named.kind, "cause") << named.verdict;
  // The named offsets explain the run down to the noise...
  EXPECT_TRUE(named.noise.after_within) << named.verdict;
  EXPECT_NEAR(named.noise.after_rms_over_sigma, 1.0, 0.25);
  // ...and stated five times too small, what was named no longer does: said, not hidden.
  for (auto& o : moved) o.sigma_m = clean.noise_m / 5;
  const auto short_of = hc::compare_point_candidates(robot, moved, 2, hc::point_candidates());
  EXPECT_EQ(short_of.kind, "cause");
  EXPECT_FALSE(short_of.noise.after_within);
  EXPECT_NE(short_of.verdict.find("something else remains"), std::string::npos) << short_of.verdict;
}

namespace {
/// A random step away from the start per parameter, by its unit: what a calibration's parameters
/// are worth, larger (5 cm, 0.05 rad; 2e-5 for compliances and 1/EI).
Eigen::VectorXd step_by_unit(const hc::SerialRobot& robot, const std::vector<hc::PointObservation>& obs, int stations,
                             const hc::PointModel& m, const hc::PointFitOptions& opt, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto params = hc::identifiability(robot, obs, stations, m, opt).parameters;
  Eigen::VectorXd dx(static_cast<Eigen::Index>(params.size()));
  for (std::size_t j = 0; j < params.size(); ++j)
    dx[static_cast<Eigen::Index>(j)] = (params[j].unit == "rad" || params[j].unit == "m" ? 0.05 : 2e-5) * u(rng);
  return dx;
}
}  // namespace

// The closed form also for the candidates that read flags and tilts and for the links' bending,
// alone and with every other candidate, away from the start (bending turns of a few mrad, so the
// turns' own rotation Jacobians and their carrying of the rest are both exercised).
TEST(PointCalibration, ClosedFormJacobianOfFlagsTiltsAndBending) {
  std::mt19937 rng(4407);
  const hc::SerialRobot robot = ur10();
  const int stations = 2;
  auto obs = random_postures(rng, robot.dof(), 14, stations);
  hc::PointFitOptions opt;
  opt.flag_names = {"elbow_flipped", "wrist_flipped"};
  opt.tilts = {{0, 0, "tilt_base_link_rx"}, {0, 1, "tilt_base_link_ry"}, {2, 0, "tilt_forearm_link_rx"}};
  std::uniform_real_distribution<double> tilt(-2e-3, 2e-3);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    obs[k].flags = {k % 2 == 0, k % 3 == 0};
    obs[k].tilts_rad = {tilt(rng), tilt(rng), tilt(rng)};
  }
  const std::vector<hc::PointModel> models = {
      {hc::PointCandidate::flag_offsets},
      {hc::PointCandidate::link_bending},
      {hc::PointCandidate::measured_tilt},
      {hc::PointCandidate::geometric, hc::PointCandidate::link_bending, hc::PointCandidate::measured_tilt},
      {hc::PointCandidate::joint_offsets, hc::PointCandidate::joint_compliance, hc::PointCandidate::backlash, hc::PointCandidate::geometric,
       hc::PointCandidate::flag_offsets, hc::PointCandidate::link_bending, hc::PointCandidate::measured_tilt}};
  for (const auto& m : models) {
    const auto J = hc::detail::point_jacobians(robot, obs, stations, m, step_by_unit(robot, obs, stations, m, opt, rng), opt);
    ASSERT_EQ(J.first.cols(), J.second.cols());
    EXPECT_LT(worst_column_error(J), 1e-6) << "model " << hc::to_string(m);
  }
  // The UR10's three links spanning 0.2 m or more bend (shoulder, upper arm, forearm), and each
  // turn moves the point.
  const auto params = hc::identifiability(robot, obs, stations, {hc::PointCandidate::link_bending}, opt).parameters;
  ASSERT_EQ(params.size(), 6u * stations + 3 + 3);
  EXPECT_EQ(params.back().name, "bending forearm_link");
  EXPECT_EQ(params.back().unit, "1/(N·m²)");
  const auto J = hc::detail::point_jacobians(robot, obs, stations, {hc::PointCandidate::link_bending},
                                             Eigen::VectorXd::Zero(static_cast<Eigen::Index>(params.size())), opt);
  EXPECT_GT(J.first.rightCols(3).colwise().norm().minCoeff(), 0.0);
}

// A telescopic column: its span runs from the prismatic joint's fixed origin to the next joint,
// so its bending grows with the extension. With an arm of weight m g at r beyond the column's top
// and the point at R, the point moves per unit 1/EI by L · m g r · sqrt(R² + L²/4) (a cantilever
// under an end moment M turns by L·M and deflects by L²M/2: a turn L·M about the span's mid-point;
// the weights along the vertical column do not bend it): the ratio between two extensions follows.
TEST(PointCalibration, ATelescopicColumnBendsMoreWhenExtended) {
  hc::SerialRobot robot;
  robot.convention = hc::DhConvention::urdf;
  hc::DhRow column;
  column.name = "column_joint";
  column.kind = hc::JointKind::prismatic;
  column.T_parent_joint.translation() = Eigen::Vector3d(0, 0, 0.3);
  column.lower = 0.0;
  column.upper = 0.5;
  hc::DhRow pan;
  pan.name = "pan_joint";
  pan.T_parent_joint.translation() = Eigen::Vector3d(0, 0, 0.5);
  robot.joints = {column, pan};
  const double m_kg = 10.0, r_m = 0.4, R_m = 1.0;
  robot.inertials = {{20.0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()},
                     {5.0, Eigen::Vector3d(0, 0, 0.25), Eigen::Matrix3d::Identity()},
                     {m_kg, Eigen::Vector3d(r_m, 0, 0), Eigen::Matrix3d::Identity()}};
  std::vector<hc::PointObservation> obs(4);
  const double ext[4][2] = {{0.0, 0.0}, {0.4, 0.0}, {0.0, 1.5}, {0.4, 1.5}};
  for (int k = 0; k < 4; ++k) {
    obs[static_cast<std::size_t>(k)].q = Eigen::Vector2d(ext[k][0], ext[k][1]);
    obs[static_cast<std::size_t>(k)].p_station_m = hc::tool_pose(robot, obs[static_cast<std::size_t>(k)].q) * Eigen::Vector3d(R_m, 0, 0);
  }
  hc::PointFitOptions opt;
  opt.tool_point_start_ee_m = Eigen::Vector3d(R_m, 0, 0);
  const auto params = hc::identifiability(robot, obs, 1, {hc::PointCandidate::link_bending}, opt).parameters;
  ASSERT_EQ(params.back().name, "bending body 1");  // only the column spans 0.2 m or more
  const auto J = hc::detail::point_jacobians(robot, obs, 1, {hc::PointCandidate::link_bending},
                                             Eigen::VectorXd::Zero(static_cast<Eigen::Index>(params.size())), opt);
  const Eigen::Index col = J.first.cols() - 1;
  const double retracted = J.first.block<3, 1>(0, col).norm(), extended = J.first.block<3, 1>(3, col).norm();
  const auto expected = [&](double L) { return L * m_kg * 9.80665 * r_m * std::sqrt(R_m * R_m + L * L / 4); };
  EXPECT_NEAR(extended / retracted, expected(0.9) / expected(0.5), 1e-9);
  EXPECT_GT(extended / retracted, 1.8);
  EXPECT_LT((J.first - J.second).norm(), 1e-6 * J.first.norm());
}

// With orientations fitted: the closed form of the rotation rows (the joints' axes, the frame
// errors' and the bending turns' rotations, the station's and the measured frame's), postures with
// and without an orientation mixed, against central differences.
TEST(PointCalibration, ClosedFormJacobianWithOrientations) {
  std::mt19937 rng(4408);
  const hc::SerialRobot robot = ur10();
  const int stations = 2;
  auto obs = random_postures(rng, robot.dof(), 15, stations);
  hc::PointFitOptions opt;
  opt.fit_orientation = true;
  opt.flag_names = {"elbow_flipped"};
  opt.tilts = {{0, 0, "tilt_base_link_rx"}, {1, 1, "tilt_shoulder_link_ry"}};
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    obs[k].flags = {k % 2 == 1};
    obs[k].tilts_rad = {2e-3 * u(rng), 2e-3 * u(rng)};
    if (k % 4 != 3) obs[k].r_station_rad = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1.5;
    if (k % 5 == 0) obs[k].sigma_m = 1e-4, obs[k].sigma_rad = 2e-4;  // a weight other than the default
  }
  const std::vector<hc::PointModel> models = {{},
                                              {hc::PointCandidate::joint_offsets, hc::PointCandidate::joint_compliance,
                                               hc::PointCandidate::backlash},
                                              {hc::PointCandidate::geometric, hc::PointCandidate::link_bending,
                                               hc::PointCandidate::measured_tilt, hc::PointCandidate::flag_offsets}};
  for (const auto& m : models) {
    const auto J = hc::detail::point_jacobians(robot, obs, stations, m, step_by_unit(robot, obs, stations, m, opt, rng), opt);
    ASSERT_EQ(J.first.rows(), 3 * 15 + 3 * 12);
    EXPECT_LT(worst_column_error(J), 1e-6) << "model " << hc::to_string(m);
  }
  // A prismatic joint turns nothing.
  hc::SerialRobot prismatic = hc::kr270_like();
  prismatic.joints[2].kind = hc::JointKind::prismatic;
  auto pobs = random_postures(rng, prismatic.dof(), 12, 2);
  for (auto& o : pobs) o.r_station_rad = Eigen::Vector3d(u(rng), u(rng), u(rng));
  hc::PointFitOptions popt;
  popt.fit_orientation = true;
  const hc::PointModel kinematic = {hc::PointCandidate::joint_offsets, hc::PointCandidate::geometric};
  const auto params = hc::identifiability(prismatic, pobs, 2, kinematic, popt).parameters;
  const auto J = hc::detail::point_jacobians(prismatic, pobs, 2, kinematic,
                                             Eigen::VectorXd::Constant(static_cast<Eigen::Index>(params.size()), 1e-3), popt);
  EXPECT_LT(worst_column_error(J), 1e-6);
  // Orientations asked for, none given: refused by name.
  popt.fit_orientation = true;
  for (auto& o : pobs) o.r_station_rad.reset();
  EXPECT_THROW(
      {
        try {
          hc::fit_points(prismatic, pobs, 2, {}, popt);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("no posture has one"), std::string::npos) << e.what();
          throw;
        }
      },
      std::invalid_argument);
}

// A 6-D device on the UR10 (the independent serial truth: KDL's chain, the measured frame drawn on
// the tip, 50 µm and 50 µrad of noise stated): fitted with the orientations, the same offsets are
// determined, within 4 σ of the truth and as narrow as from the points (a 1 mrad offset moves the
// point by about 1 mm at this reach, 20 noise σ, but turns the frame by 20 angular σ: the
// orientations add little to the offsets), the measured frame on the tool comes out as drawn and
// the rotation residual is the noise's.
TEST(PointCalibration, OrientationsAreFittedWithTheirFrameOnTheTool) {
  std::mt19937 rng(4409);
  namespace ts = hil::test::serial;
  ts::Truth t;
  t.urdf = std::string(HIL_SOURCE_DIR) + "/examples/robots/ur10.urdf";
  t.base = "base_link";
  t.tip = "wrist_3_link";
  t.T_station_base = {ts::random_station(rng, 3.0, 3.0)};
  t.tool_point_m = Eigen::Vector3d(0.03, -0.02, 0.12);
  const Eigen::Vector3d frame_rad(0.3, -0.2, 0.5);
  t.measured_frame_tip = Eigen::AngleAxisd(frame_rad.norm(), frame_rad.normalized()).toRotationMatrix();
  t.noise_m = 50e-6;
  t.noise_rad = 50e-6;
  t.joint_offset_rad = Eigen::VectorXd(6);
  t.joint_offset_rad << 0.8e-3, -1.2e-3, 1.5e-3, -0.7e-3, 1.1e-3, 0.9e-3;
  const std::vector<std::pair<double, double>> range = {{-3.0, 3.0}, {-2.6, -0.5}, {-2.5, 2.5}, {-3.0, 3.0}, {-3.0, 3.0}, {-3.0, 3.0}};
  std::vector<hc::PointObservation> obs;
  for (const auto& s : ts::generate(t, ts::draw_postures(30, range, rng), rng)) {
    hc::PointObservation o;
    o.q = s.q;
    o.p_station_m = s.p_station_m;
    o.sigma_m = 50e-6;
    o.r_station_rad = s.r_station_rad;
    o.sigma_rad = 50e-6;
    obs.push_back(o);
  }
  hc::PointFitOptions points, poses;
  poses.fit_orientation = true;
  const hc::PointModel m = {hc::PointCandidate::joint_offsets};
  const auto a = hc::fit_points(ur10(), obs, 1, m, points);
  const auto b = hc::fit_points(ur10(), obs, 1, m, poses);
  EXPECT_EQ(a.orientations, 0);
  EXPECT_EQ(b.orientations, 30);
  // The pan's offset turns with the station, the last joint's with the free tool point and frame.
  const hc::SerialRobot robot = ur10();
  std::set<std::string> only_points, with_poses;
  for (const auto& p : a.parameters)
    if (p.part == "joint_offsets" && p.identifiable) only_points.insert(p.name);
  for (std::size_t i = 0; i < robot.joints.size(); ++i) {
    const auto it = std::find_if(b.parameters.begin(), b.parameters.end(),
                                 [&](const auto& p) { return p.name == "offset " + robot.joints[i].name; });
    ASSERT_NE(it, b.parameters.end());
    if (!it->identifiable) continue;
    with_poses.insert(it->name);
    EXPECT_LT(std::abs(it->value - t.joint_offset_rad[static_cast<Eigen::Index>(i)]), 4 * it->std) << it->name;
    const auto pa = std::find_if(a.parameters.begin(), a.parameters.end(), [&](const auto& p) { return p.name == it->name; });
    ASSERT_NE(pa, a.parameters.end());
    EXPECT_LT(it->std, 1.2 * pa->std) << it->name;
  }
  EXPECT_EQ(only_points, with_poses);
  EXPECT_EQ(with_poses,
            (std::set<std::string>{"offset shoulder_lift_joint", "offset elbow_joint", "offset wrist_1_joint", "offset wrist_2_joint"}));
  // The measured frame: its turn about the tool's x and y is determined; about z it goes with the
  // last joint's offset (both turn the frame about the same axis).
  // Along that null direction the frame's rotation vector moves as a whole, so its components are
  // not determined one by one: the fitted frame is compared as a rotation, up to a turn about the
  // last joint's axis (y of wrist_3_link in this URDF).
  int frame_params = 0;
  for (const auto& p : b.parameters) frame_params += p.part == "tool" && p.unit == "rad" ? 1 : 0;
  EXPECT_EQ(frame_params, 3);
  const Eigen::Matrix3d R_fit = Eigen::AngleAxisd(b.tool_rotation_ee_rad.norm(), b.tool_rotation_ee_rad.normalized()).toRotationMatrix();
  const Eigen::Vector3d y_fit = R_fit.transpose().col(1), y_true = t.measured_frame_tip.transpose().col(1);
  EXPECT_LT(std::acos(std::min(1.0, y_fit.dot(y_true))), 1e-3);  // the joint's axis seen from the measured frame
}

// What the new candidates need is checked before anything is fitted, and said by name: a flag
// set on every posture (its offsets would be the joints' own), tilt columns that do not match the
// postures, a tilt of a body the chain does not have, a robot without inertials.
TEST(PointCalibration, CandidatesThatCannotBeFittedSayWhy) {
  std::mt19937 rng(4410);
  const hc::SerialRobot robot = ur10();
  auto obs = random_postures(rng, robot.dof(), 12, 2);
  hc::PointFitOptions opt;
  opt.flag_names = {"elbow_flipped"};
  for (auto& o : obs) o.flags = {true};
  std::string why;
  EXPECT_FALSE(hc::usable(hc::PointCandidate::flag_offsets, robot, obs, opt, &why));
  EXPECT_EQ(why, "flag_offsets: flag elbow_flipped is set on every posture: its offsets are not told from the joints' own");
  EXPECT_THROW(hc::fit_points(robot, obs, 2, {hc::PointCandidate::flag_offsets}, opt), std::invalid_argument);
  obs[3].flags = {false};
  EXPECT_TRUE(hc::usable(hc::PointCandidate::flag_offsets, robot, obs, opt, &why));
  obs[4].flags = {};
  EXPECT_FALSE(hc::usable(hc::PointCandidate::flag_offsets, robot, obs, opt, &why));
  EXPECT_EQ(why, "flag_offsets: posture 5 has 0 flags, the run names 1");

  opt.tilts = {{0, 0, "tilt_base_link_rx"}};
  EXPECT_FALSE(hc::usable(hc::PointCandidate::measured_tilt, robot, obs, opt, &why));
  EXPECT_EQ(why, "measured_tilt: posture 1 has 0 tilts, the run names 1");
  for (auto& o : obs) o.tilts_rad = {1e-4};
  EXPECT_TRUE(hc::usable(hc::PointCandidate::measured_tilt, robot, obs, opt, &why));
  opt.tilts = {{7, 0, "tilt_nowhere_rx"}};
  EXPECT_FALSE(hc::usable(hc::PointCandidate::measured_tilt, robot, obs, opt, &why));
  EXPECT_NE(why.find("tilt column tilt_nowhere_rx: body 7"), std::string::npos) << why;

  const hc::SerialRobot dh = hc::kr270_like();  // a DH table: no inertials
  EXPECT_FALSE(hc::usable(hc::PointCandidate::link_bending, dh, random_postures(rng, dh.dof(), 6, 1), {}, &why));
  EXPECT_NE(why.find("needs the robot's inertials"), std::string::npos) << why;
  // compare_point_candidates leaves out what cannot be fitted rather than failing.
  const auto c = hc::compare_point_candidates(robot, obs, 2, {hc::PointCandidate::joint_offsets, hc::PointCandidate::flag_offsets}, 0,
                                              hc::PointFitOptions{});
  for (const auto& row : c.rows) EXPECT_NE(row.model.front(), hc::PointCandidate::flag_offsets);
}

// A robot with a mimic joint (examples/robots/palletizer_mimic.urdf: the wrist pitch follows the
// elbow with multiplier −1). The truth is KDL's chain, which has no mimics: the postures are drawn
// here for the four driven joints and the passive one set from the coupling the URDF states. Hidden
// offsets on every physical joint, the passive one included (its linkage's own zero error).
TEST(PointCalibration, AMimicJointIsCalibratedAsThePhysicalJointItIs) {
  const std::string urdf = std::string(HIL_SOURCE_DIR) + "/examples/robots/palletizer_mimic.urdf";
  const hc::SerialRobot robot = hil::models::to_serial_robot(hil::format::read_urdf_robot(urdf, "base_link", "tool0"));
  ASSERT_EQ(robot.joints[3].mimic_master, 2);
  std::mt19937 rng(66121);
  namespace ts = hil::test::serial;
  ts::Truth t;
  t.urdf = urdf;
  t.base = "base_link";
  t.tip = "tool0";
  for (int s = 0; s < 2; ++s) t.T_station_base.push_back(ts::random_station(rng, 3.0, 3.0));
  t.tool_point_m = Eigen::Vector3d(0.05, -0.03, 0.12);
  t.noise_m = 50e-6;
  t.joint_offset_rad = Eigen::VectorXd(5);
  for (int j = 0; j < 5; ++j) t.joint_offset_rad[j] = (j % 2 ? -1.0 : 1.0) * std::uniform_real_distribution<double>(1e-3, 2e-3)(rng);
  auto postures = ts::draw_postures(60, {{-3.0, 3.0}, {-0.7, 1.1}, {-1.1, 0.7}, {0.0, 0.0}, {-3.0, 3.0}}, rng);
  for (auto& q : postures) q[3] = -1.0 * q[2];  // <mimic joint="elbow" multiplier="-1" offset="0"/>
  std::vector<hc::PointObservation> obs;
  for (const auto& s : ts::generate(t, postures, rng)) {
    hc::PointObservation o;
    o.q = s.q;
    o.station = s.station;
    o.p_station_m = s.p_station_m;
    o.sigma_m = t.noise_m;
    obs.push_back(o);
  }
  const auto cmp = hc::compare_point_candidates(robot, obs, 2, hc::point_candidates());
  std::cout << "[mimic] " << cmp.verdict << "\n";
  ASSERT_GE(cmp.cause, 0) << cmp.verdict;
  EXPECT_EQ(hc::to_string(cmp.rows[static_cast<std::size_t>(cmp.cause)].model), "joint_offsets") << cmp.verdict;
  EXPECT_TRUE(cmp.noise.after_within) << cmp.verdict;
  // The passive joint's offset is a parameter of its own: determined, or named in a combination.
  const auto fit = hc::fit_points(robot, obs, 2, {hc::PointCandidate::joint_offsets});
  bool seen = false;
  for (const auto& p : fit.parameters)
    if (p.name.find("wrist_pitch") != std::string::npos) {
      seen = true;
      std::cout << "[mimic] " << p.name << " " << p.value << " +- " << p.std << " (truth " << t.joint_offset_rad[3] << ")"
                << (p.identifiable ? "" : " not identifiable") << "\n";
      if (p.identifiable) {
        EXPECT_LT(std::abs(p.value - t.joint_offset_rad[3]), 4 * p.std) << p.name;
      }
    }
  EXPECT_TRUE(seen || mentions(fit.undetermined, "offset wrist_pitch"));
}

// base_compliance: the closed form of its columns (points and orientations, beside a measured tilt
// of the base about one axis and the other candidates) against central differences; then, on the
// independent truth's base springs without noise, the two compliances are 1/k and the points fit
// to rounding; with both of the base's tilts measured the candidate is not compared, by name.
TEST(PointCalibration, ABaseOnSpringsIsItsComplianceAboutXAndY) {
  std::mt19937 rng(4411);
  const hc::SerialRobot robot = ur10();
  const int stations = 2;
  auto obs = random_postures(rng, robot.dof(), 14, stations);
  hc::PointFitOptions opt;
  opt.fit_orientation = true;
  opt.tilts = {{0, 0, "tilt_base_link_rx"}, {2, 1, "tilt_forearm_link_ry"}};
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    obs[k].tilts_rad = {2e-3 * u(rng), 2e-3 * u(rng)};
    if (k % 3 != 2) obs[k].r_station_rad = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1.5;
    obs[k].payload_kg = k % 2 ? 4.0 : 0.0;
    obs[k].payload_com_ee_m = Eigen::Vector3d(0.02, 0.0, 0.1);
  }
  const std::vector<hc::PointModel> models = {{hc::PointCandidate::base_compliance},
                                              {hc::PointCandidate::joint_compliance, hc::PointCandidate::geometric,
                                               hc::PointCandidate::link_bending, hc::PointCandidate::measured_tilt,
                                               hc::PointCandidate::base_compliance}};
  for (const auto& m : models) {
    const auto J = hc::detail::point_jacobians(robot, obs, stations, m, step_by_unit(robot, obs, stations, m, opt, rng), opt);
    EXPECT_LT(worst_column_error(J), 1e-6) << "model " << hc::to_string(m);
    EXPECT_GT(J.first.rightCols(2).colwise().norm().minCoeff(), 0.0) << "model " << hc::to_string(m);
  }

  ts::Truth t = serial_ur10(rng, stations);
  t.base_stiffness_Nm_per_rad = 3.1e5;
  const auto run = serial_run(t, 40, rng);
  hc::PointFitOptions fit_opt;
  fit_opt.tool_point_start_ee_m = t.tool_point_m;
  const auto rigid = hc::fit_points(robot, run, stations, {}, fit_opt);
  const auto fit = hc::fit_points(robot, run, stations, {hc::PointCandidate::base_compliance}, fit_opt);
  EXPECT_GT(rigid.rms_m, 50e-6);  // the effect is there to find
  EXPECT_LT(fit.rms_m, 1e-8);
  for (const char* name : {"compliance base_link rx", "compliance base_link ry"}) {
    const auto& p = param(fit, name);
    EXPECT_EQ(p.unit, "rad/(N·m)");
    EXPECT_EQ(p.part, "base_compliance");
    EXPECT_NEAR(p.value, 1.0 / t.base_stiffness_Nm_per_rad, 1e-4 / t.base_stiffness_Nm_per_rad) << name;
  }

  std::string why;
  opt.tilts = {{0, 0, "tilt_base_link_rx"}, {0, 1, "tilt_base_link_ry"}};
  EXPECT_FALSE(hc::usable(hc::PointCandidate::base_compliance, robot, obs, opt, &why));
  EXPECT_EQ(why, "base_compliance: the run measures the base's tilt (tilt columns): measured_tilt applies it");
  EXPECT_FALSE(hc::usable(hc::PointCandidate::base_compliance, hc::kr270_like(), random_postures(rng, 6, 6, 1), {}, &why));
  EXPECT_NE(why.find("needs the robot's inertials"), std::string::npos) << why;
}

// link_bending on the independent truth's Euler-Bernoulli beams without noise: the upper arm and
// the forearm carry their own weight spread along them and everything beyond. The candidate is the
// cantilever's end motion (turn and deflection), so 1/EI comes out as the truth's to rounding. Its
// former form, a turn about the mid-point by L·M_mid/EI, gave 14 % high and below zero here
// (docs/calibration.md, the blind suite's fifth series).
TEST(PointCalibration, LinkBendingRecoversTheBeamsStiffnessWithoutNoise) {
  std::mt19937 rng(4412);
  ts::Truth t = serial_ur10(rng, 3);
  t.beams = {{"upper_arm_link", 4e4, 0.0}, {"forearm_link", 7e4, 0.0}};
  const auto run = serial_run(t, 72, rng);
  hc::PointFitOptions opt;
  opt.tool_point_start_ee_m = t.tool_point_m;
  opt.bending_bodies = {2, 3};  // upper arm, forearm
  const auto fit = hc::fit_points(ur10(), run, 3, {hc::PointCandidate::link_bending}, opt);
  const double upper = param(fit, "bending upper_arm_link").value, fore = param(fit, "bending forearm_link").value;
  EXPECT_NEAR(upper * 4e4, 1.0, 1e-6);
  EXPECT_NEAR(fore * 7e4, 1.0, 1e-6);
  EXPECT_LT(fit.rms_m, 1e-9);
}
