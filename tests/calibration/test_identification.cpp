// Weighted least squares: recovery within the reported intervals, covariance that matches the
// scatter of repeated experiments, rank reporting, unit-free weighting.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <hil/test/eigen.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/calibration/reduction.hpp>

namespace hc = hil::calibration;

namespace {

hc::ParameterSet joint_set(const hc::VjmModel& m) {
  hc::ParameterSet set;
  for (int j = 1; j <= m.dof(); ++j) set.push_back({m.joint_spring(j), 0, 0, false, "J" + std::to_string(j) + ".k"});
  return set;
}

/// Robot with rigid links: only the joints are compliant.
hc::ComplianceSet joints_only(const hc::VjmModel& m) {
  hc::ComplianceSet k = hc::example_compliance(m);
  for (int l = 0; l <= m.dof(); ++l) k[static_cast<std::size_t>(m.link_spring(l))].setZero();
  return k;
}

}  // namespace

TEST(Identification, RecoversJointCompliancesWithinTheirIntervals) {
  const hc::VjmModel m(hc::kr270_like());
  const hc::ComplianceSet truth = joints_only(m);
  hc::ExperimentPlan plan;
  plan.configurations = 40;
  plan.moment_nm = 300.0;  // the tool point lies on joint 6's axis: forces alone never twist it
  plan.seed = 21;
  const hc::NoiseModel noise{20e-6, 20e-6};
  const auto data = hc::simulate(m, truth, plan, noise);
  const auto r = hc::identify_fixed_set(m, joint_set(m), data, noise);
  ASSERT_TRUE(r.solution.full_rank);
  EXPECT_EQ(r.solution.rank, 6);
  for (const auto& p : r.kept) {
    const double t = truth[static_cast<std::size_t>(p.parameter.spring)](0, 0);
    EXPECT_LT(std::abs(p.value - t), 4.0 * p.std_dev) << p.parameter.name << " " << p.value << " vs " << t;
    EXPECT_LT(p.std_dev, 0.05 * t) << p.parameter.name;  // precise enough to mean something
    EXPECT_EQ(p.cls, hc::PnrClass::g1_plus);
  }
  // The chi-square check: with the right noise model the variance factor is about 1.
  EXPECT_NEAR(r.solution.sigma0_sq, 1.0, 0.2);
  for (int a = 0; a < 6; ++a) EXPECT_NEAR(r.residual_rms[static_cast<std::size_t>(a)], 20e-6, 5e-6);
}

TEST(Identification, CovarianceMatchesTheScatterOfRepeatedExperiments) {
  const hc::VjmModel m(hc::kr270_like());
  const hc::ComplianceSet truth = joints_only(m);
  hc::ExperimentPlan plan;
  plan.configurations = 12;
  // Markers off the tool axis: the tool point alone never sees joint 6 (its axis passes through it).
  plan.kind = hc::MeasurementKind::markers;
  plan.p_ee_marker_m = {Eigen::Vector3d(0.15, 0.0, 0.0), Eigen::Vector3d(0.0, 0.15, 0.0)};
  plan.moment_nm = 300.0;
  plan.seed = 5;
  const hc::NoiseModel noise{50e-6, 0.0};
  const auto clean = hc::simulate(m, truth, plan, {});
  const auto set = joint_set(m);
  const auto reference = hc::identify_fixed_set(m, set, clean, noise);
  const int runs = 300;
  Eigen::MatrixXd est(runs, 6);
  int covered = 0;
  std::mt19937_64 rng(99);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < runs; ++i) {
    auto data = clean;  // same configurations and loads, fresh noise
    for (auto& d : data)
      for (auto& v : d.displacement) v += noise.position_m * g(rng);
    const auto r = hc::identify_fixed_set(m, set, data, noise);
    for (int j = 0; j < 6; ++j) {
      est(i, j) = r.kept[static_cast<std::size_t>(j)].value;
      const double t = truth[static_cast<std::size_t>(m.joint_spring(j + 1))](0, 0);
      covered += (r.kept[static_cast<std::size_t>(j)].ci95_low <= t && t <= r.kept[static_cast<std::size_t>(j)].ci95_high) ? 1 : 0;
    }
  }
  for (int j = 0; j < 6; ++j) {
    const Eigen::VectorXd c = est.col(j).array() - est.col(j).mean();
    const double empirical = std::sqrt(c.squaredNorm() / (runs - 1));
    EXPECT_NEAR(empirical / reference.kept[static_cast<std::size_t>(j)].std_dev, 1.0, 0.15) << "J" << j + 1;
  }
  const double coverage = static_cast<double>(covered) / (6.0 * runs);
  EXPECT_GT(coverage, 0.92);
  EXPECT_LT(coverage, 0.98);
}

TEST(Identification, WeightsFollowTheNoiseModel) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 15;
  plan.moment_nm = 200.0;
  const auto data = hc::simulate(m, joints_only(m), plan, {10e-6, 10e-6});
  // Two noise models that differ by a common factor give the same estimate, and standard
  // deviations in proportion.
  const auto a = hc::identify_fixed_set(m, joint_set(m), data, {10e-6, 10e-6});
  const auto b = hc::identify_fixed_set(m, joint_set(m), data, {10e-3, 10e-3});
  for (std::size_t i = 0; i < a.kept.size(); ++i) {
    EXPECT_NEAR(a.kept[i].value, b.kept[i].value, 1e-12 * std::abs(a.kept[i].value));
    EXPECT_NEAR(a.kept[i].std_dev * 1e3, b.kept[i].std_dev, 1e-9 * b.kept[i].std_dev);
  }
  // Heavier weight on rotations moves the estimate when the model cannot fit both exactly.
  const auto c = hc::identify_fixed_set(m, joint_set(m), hc::simulate(m, hc::example_compliance(m), plan, {10e-6, 10e-6}), {10e-6, 1e-9});
  const auto d = hc::identify_fixed_set(m, joint_set(m), hc::simulate(m, hc::example_compliance(m), plan, {10e-6, 10e-6}), {1e-9, 10e-6});
  EXPECT_GT(std::abs(c.kept[3].value - d.kept[3].value), 1e-3 * std::abs(c.kept[3].value));
}

TEST(Identification, ToolRollUnderPureForcesIsNotIdentifiable) {
  // The tool point lies on joint 6's axis, so a force there never loads joint 6: its column is
  // rounding noise and must not count in the rank.
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 20;
  const auto data = hc::simulate(m, joints_only(m), plan, {1e-5, 1e-5});
  const auto r = hc::identify_fixed_set(m, joint_set(m), data, {1e-5, 1e-5});
  EXPECT_EQ(r.solution.rank, 5);
  EXPECT_FALSE(r.solution.full_rank);
  const auto sys = hc::build_system(m, joint_set(m), data, {1e-5, 1e-5});
  const auto part = hc::m4a_partition(hc::compress(sys.A_w, sys.t_w), {0, 1, 2, 3, 4, 5});
  EXPECT_EQ(part.g2, (std::vector<int>{5}));
  EXPECT_EQ(part.g1.size(), 5u);
}

TEST(Identification, RankDeficiencyIsReportedNotHidden) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 10;
  plan.moment_nm = 300.0;
  const auto data = hc::simulate(m, hc::example_compliance(m), plan, {});
  auto set = joint_set(m);
  set.push_back(set[2]);  // the same column twice
  const auto r = hc::identify_fixed_set(m, set, data, {1e-5, 1e-5});
  EXPECT_EQ(r.solution.rank, 6);
  EXPECT_FALSE(r.solution.full_rank);
  EXPECT_TRUE(std::isinf(r.solution.condition));
  EXPECT_TRUE(std::isnan(r.kept[2].std_dev));
}

TEST(Identification, CompressedSolveEqualsADirectQrSolve) {
  // The compressed system answers like the full one: same estimate and residual.
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(40, 5);
  Eigen::VectorXd t(40);
  for (auto& v : A.reshaped()) v = g(rng);
  for (auto& v : t) v = g(rng);
  A.col(3) *= 1e-6;  // very different column scales
  const auto c = hc::compress(A, t);
  const auto s = hc::solve(c);
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(t);
  EXPECT_TRUE(hil::test::near(s.value, x, 0.0, 1e-9));
  EXPECT_NEAR(s.rss, (A * x - t).squaredNorm(), 1e-9 * s.rss);
  EXPECT_EQ(s.dof, 35);
}

TEST(Identification, ParameterToNoiseClasses) {
  const hc::PnrThresholds t;  // 2 and 5
  EXPECT_EQ(hc::classify(7.0, t), hc::PnrClass::g1_plus);
  EXPECT_EQ(hc::classify(5.0, t), hc::PnrClass::g1_plus);
  EXPECT_EQ(hc::classify(3.0, t), hc::PnrClass::g1_tilde);
  EXPECT_EQ(hc::classify(1.9, t), hc::PnrClass::g1_minus);
  EXPECT_EQ(hc::classify(3.0, {1.0, 2.5}), hc::PnrClass::g1_plus);
  EXPECT_STREQ(hc::to_string(hc::PnrClass::g1_tilde), "G1~");
}
