// Contact model, regressor and identification: oracle tests, noise-free recovery, bad input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <hil/contact_id/online.hpp>
#include "scenes.hpp"

namespace hil::contact_id::test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(Model, PlateWrenchMatchesHandComputation) {
  // Cube pressed d into the block, sliding along +x faster than v_t,m: the plate feels the normal
  // force K d downwards and the friction μ K d along +x (dragged by the cube).
  auto s = cube_on_block();
  s.T_world_fp.translation() = Vec3(0.0, 0.0, -0.05);  // plate under the block
  ContactModel m{1.8e5, 0.3, 1e-3};
  Kinematics k;
  const double d = 2e-4;
  k.T_world_ee.translation() = Vec3(0.01, 0.02, -d);
  k.v_world_ee = Vec3(0.01, 0.0, 0.0);
  MindistWorkspace ws;
  std::vector<ContactPoint> c;
  const Vector6d w = plate_wrench(s, m, s.design(), k, ws, c);
  ASSERT_EQ(c.size(), 1u);
  const Vec3 F(m.mu * m.K * d, 0.0, -m.K * d);
  const Vec3 p = Vec3(0.01, 0.02, -d / 2) - s.T_world_fp.translation();  // point in plate frame
  const Vec3 M = p.cross(F);
  EXPECT_LT((w.head<3>() - F).norm(), 1e-9);
  EXPECT_LT((w.tail<3>() - M).norm(), 1e-9);
}

TEST(Model, WrenchTransformsAreInverse) {
  Eigen::Isometry3d Tfp = Eigen::Isometry3d::Identity(), To1 = Eigen::Isometry3d::Identity();
  Tfp.linear() = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  Tfp.translation() = Vec3(0.1, -0.2, 0.3);
  To1.linear() = Eigen::AngleAxisd(-0.7, Vec3(3, 1, 2).normalized()).toRotationMatrix();
  To1.translation() = Vec3(-0.4, 0.5, 0.6);
  Vector6d w;
  w << 1, 2, 3, 4, 5, 6;
  EXPECT_LT((object1_to_plate(plate_to_object1(w, Tfp, To1), Tfp, To1) - w).norm(), 1e-12);
}

TEST(Model, RejectsNonPhysicalParameters) {
  EXPECT_THAT(([] {
                ContactModel{0.0, 0.2, 1e-3}.check();
              }),
              ThrowsMessage<std::invalid_argument>(HasSubstr("contact stiffness K must be > 0, got 0")));
  EXPECT_THAT(([] {
                ContactModel{1e5, -0.1, 1e-3}.check();
              }),
              ThrowsMessage<std::invalid_argument>(HasSubstr("friction coefficient mu must be >= 0, got -0.1")));
  EXPECT_NO_THROW((ContactModel{1e5, 0.0, 1e-3}.check()));
}

TEST(Identification, RegressorTimesThetaEqualsSimulation) {
  auto s = cube_on_block();
  ContactModel m{2.1e5, 0.25, 1e-3};
  const auto sim = simulate(s, m, s.design(), press_slide(), {});
  ContactProblem p(s, measure(sim), {});
  Eigen::MatrixX2d A;
  p.regressor(s.design(), A);
  const Eigen::VectorXd pred = A * m.theta();
  EXPECT_LT((pred - p.y()).norm(), 1e-9 * p.y().norm());
  EXPECT_LT(p.used().size(), sim.size());  // the approach samples have no contact
}

TEST(Identification, NoiseFreeRecoveryOfKAndMu) {
  auto s = cube_on_block();
  ContactModel m{1.8e5, 0.2, 1e-3};
  const auto sim = simulate(s, m, s.design(), press_slide(), {});
  ContactProblem p(s, measure(sim), {});
  const auto e = global_estimate(p, s.design());
  EXPECT_EQ(e.rank, 2);
  EXPECT_TRUE(e.mu_identifiable);
  EXPECT_NEAR(e.K / m.K, 1.0, 1e-6);
  EXPECT_NEAR(e.mu / m.mu, 1.0, 1e-6);
  EXPECT_LT(e.relative_force_error, 1e-8);
  EXPECT_GT(e.condition, 1.0);
}

TEST(Identification, NoisyIntervalsCoverTheTruth) {
  auto s = cube_on_block();
  ContactModel m{1.8e5, 0.2, 1e-3};
  SensorModel sensor;
  sensor.force_noise_n = 0.5;
  sensor.moment_noise_nm = 0.005;
  sensor.seed = 11;
  const auto sim = simulate(s, m, s.design(), press_slide(400), sensor);
  ContactProblem p(s, measure(sim), {});
  const auto e = global_estimate(p, s.design());
  EXPECT_GT(e.K_std, 0.0);
  EXPECT_LT(std::abs(e.K - m.K), 4.0 * e.K_std);
  EXPECT_LT(std::abs(e.mu - m.mu), 4.0 * e.mu_std);
  EXPECT_LT(e.K_std, 0.05 * m.K);
}

TEST(Identification, InstantaneousEstimatesAreConstantOnNoiseFreeData) {
  auto s = cube_on_block();
  ContactModel m{1.8e5, 0.2, 1e-3};
  const auto sim = simulate(s, m, s.design(), press_slide(), {});
  ContactProblem p(s, measure(sim), {});
  for (int window : {1, 9}) {
    const auto inst = instantaneous(p, s.design(), window);
    ASSERT_EQ(inst.size(), p.used().size());
    int mu_valid = 0;
    for (const auto& e : inst) {
      ASSERT_TRUE(e.valid);
      EXPECT_NEAR(e.K / m.K, 1.0, 1e-6);
      if (e.mu_valid) {
        ++mu_valid;
        EXPECT_NEAR(e.mu, m.mu, 1e-6);
      }
    }
    EXPECT_GT(mu_valid, 0);
  }
}

TEST(Online, RunningEstimateEqualsTheBatchEstimate) {
  auto s = cube_on_block();
  ContactModel m{1.8e5, 0.2, 1e-3};
  SensorModel sensor;
  sensor.force_noise_n = 0.3;
  sensor.moment_noise_nm = 0.003;
  const auto data = measure(simulate(s, m, s.design(), press_slide(), sensor));
  ProblemOptions po;
  po.force_scale_n = 50.0;
  po.moment_scale_nm = 2.0;
  ContactProblem p(s, data, po);
  const auto batch = global_estimate(p, s.design());
  OnlineEstimator online(s, 1e-3, 50.0, 2.0);
  OnlineEstimate last;
  int first_contact = -1;
  for (std::size_t i = 0; i < data.size(); ++i) {
    last = online.update(data[i]);
    if (last.contacts > 0 && first_contact < 0) first_contact = static_cast<int>(i);
    if (first_contact < 0) {
      EXPECT_FALSE(last.instantaneous_valid);
    }
  }
  EXPECT_EQ(static_cast<std::size_t>(last.global.rows), 6 * p.used().size());
  EXPECT_NEAR(last.global.K / batch.K, 1.0, 1e-10);
  EXPECT_NEAR(last.global.mu / batch.mu, 1.0, 1e-10);
  EXPECT_NEAR(last.global.relative_force_error / batch.relative_force_error, 1.0, 1e-8);
  EXPECT_GT(last.global.K_std, 0.0);
}

TEST(BadInput, NoContactInTheRun) {
  auto s = cube_on_block();
  std::vector<Measurement> d(10);
  for (auto& x : d) x.kin.T_world_ee.translation() = Vec3(0, 0, 0.01);
  try {
    ContactProblem p(s, d, {});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no sample of the run brings the objects into contact"), std::string::npos) << e.what();
  }
}

TEST(BadInput, AllContactsStickingOnlyKIdentifiable) {
  auto s = cube_on_block();
  auto traj = press_slide();
  for (auto& k : traj) {
    k.v_world_ee.setZero();
    k.w_world_ee.setZero();
  }
  ContactModel m{1.8e5, 0.2, 1e-3};
  const auto sim = simulate(s, m, s.design(), traj, {});
  ContactProblem p(s, measure(sim), {});
  const auto e = global_estimate(p, s.design());
  EXPECT_EQ(e.rank, 1);
  EXPECT_FALSE(e.mu_identifiable);
  EXPECT_NEAR(e.K / m.K, 1.0, 1e-6);
  EXPECT_NE(e.note.find("only K is identifiable"), std::string::npos) << e.note;
}

TEST(BadInput, NonFiniteValues) {
  auto s = cube_on_block();
  std::vector<Measurement> d(3);
  d[1].w_fp[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    ContactProblem p(s, d, {});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
  }
}

Scene cube_on_block_with_uncertainties() {
  auto s = cube_on_block();
  Uncertainty tz;
  tz.name = "top_z";
  tz.body = 1;
  tz.feature = 0;
  tz.kind = Uncertainty::Kind::translation;
  tz.axis = Vec3::UnitZ();
  tz.prior_std = 1e-4;
  Uncertainty rx;
  rx.name = "top_tilt_x";
  rx.body = 1;
  rx.feature = 0;
  rx.kind = Uncertainty::Kind::rotation;
  rx.axis = Vec3::UnitX();
  rx.prior_std = 1e-3;
  Uncertainty far;
  far.name = "far_z";
  far.body = 1;
  far.feature = 1;
  far.axis = Vec3::UnitZ();
  far.prior_std = 1e-4;
  s.uncertainties = {tz, rx, far};
  return s;
}

TEST(BadInput, NeverTouchedFeatureIsUnobservableAndNotFitted) {
  auto s = cube_on_block_with_uncertainties();
  const auto sim = simulate(s, ContactModel{}, s.design(), press_slide(), {});
  ContactProblem p(s, measure(sim), {});
  EXPECT_TRUE(p.touches(0));
  EXPECT_FALSE(p.touches(2));
  const auto o = analyse_observability(p, s.design());
  ASSERT_EQ(o.unobservable.size(), 1u);
  EXPECT_NE(o.unobservable[0].find("far_z"), std::string::npos);
  EXPECT_NE(o.unobservable[0].find("never in contact"), std::string::npos);
  GeometricOptions g;
  g.fit = {false, false, true};  // only the untouched one requested
  try {
    identify_geometry(p, g);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("unobservable"), std::string::npos) << e.what();
  }
  g.fit.clear();
  const auto est = identify_geometry(p, g);
  EXPECT_FALSE(est.fitted[2]);
  EXPECT_EQ(est.x[2], 0.0);
}

/// The cube pressed and slid on the block with two uncertainties; `x` is set off their design.
ContactProblem pressed_cube_problem(Eigen::VectorXd& x) {
  auto s = cube_on_block_with_uncertainties();
  const auto sim = simulate(s, ContactModel{}, s.design(), press_slide(), {});
  x = s.design();
  x[0] = 3e-5;
  x[1] = 2e-4;
  return ContactProblem(s, measure(sim), {});
}

TEST(Geometric, SensitivityMatchesFiniteDifferenceOfTheRegressor) {
  Eigen::VectorXd x;
  const ContactProblem p = pressed_cube_problem(x);
  for (int j = 0; j < 2; ++j) {
    Eigen::MatrixX2d dA, Ap, Am;
    const double h = p.fd_step(j) * 10;
    p.sensitivity(x, j, p.fd_step(j), dA);
    Eigen::VectorXd xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    p.regressor(xp, Ap);
    p.regressor(xm, Am);
    const Eigen::MatrixX2d ref = (Ap - Am) / (2 * h);
    EXPECT_LT((dA - ref).norm(), 1e-2 * ref.norm()) << "x_" << j;  // kinks where the deepest vertex switches
    EXPECT_GT(ref.norm(), 0.0);
  }
}

// Right after regressor(x) the sensitivities replay its separating-axis passes: they must equal
// the ones computed from scratch.
TEST(Geometric, SensitivityAfterTheRegressorEqualsTheOneFromScratch) {
  Eigen::VectorXd x;
  const ContactProblem p = pressed_cube_problem(x);
  Eigen::VectorXd other = x;
  other[0] += 1e-5;
  for (int j = 0; j < 2; ++j) {
    Eigen::MatrixX2d A, replayed, scratch;
    p.regressor(x, A);
    p.sensitivity(x, j, p.fd_step(j), replayed);
    p.regressor(other, A);  // the records are now for another x
    p.sensitivity(x, j, p.fd_step(j), scratch);
    EXPECT_GT(scratch.norm(), 0.0);
    EXPECT_EQ((replayed - scratch).cwiseAbs().maxCoeff(), 0.0) << "x_" << j;
  }
}

TEST(Geometric, RecoversHiddenShiftAndBothSolversAgree) {
  auto s = cube_on_block_with_uncertainties();
  ContactModel m{1.8e5, 0.2, 1e-3};
  Eigen::VectorXd truth = s.design();
  truth[0] = 6e-5;  // block top 60 µm higher than designed
  truth[1] = 6e-3;  // and tilted more than the cube ever tilts: the deepest corner never switches
                    // (where it does, the max-depth model has kinks and the linearised intervals
                    // understate the spread, see docs/contact_id.md)
  SensorModel sensor;
  sensor.force_noise_n = 0.05;
  sensor.moment_noise_nm = 5e-4;
  sensor.seed = 3;
  const auto sim = simulate(s, m, truth, press_slide(300), sensor);
  ContactProblem p(s, measure(sim), {});
  const auto nominal = global_estimate(p, s.design());
  GeometricOptions o;
  o.lambda = 1e-8;
  const auto lm = identify_geometry(p, o);
  o.solver = Solver::nelder_mead;
  const auto nm = identify_geometry(p, o);
  for (int j = 0; j < 2; ++j) {
    EXPECT_GT(lm.x_std[j], 0.0);
    EXPECT_LT(std::abs(lm.x[j] - truth[j]), 3.0 * lm.x_std[j] + 1e-9) << "x_" << j << " = " << lm.x[j] << " ± " << lm.x_std[j];
    EXPECT_LT(std::abs(lm.x[j] - nm.x[j]), 0.05 * s.prior_std()[j]) << "LM " << lm.x[j] << " NM " << nm.x[j];
  }
  EXPECT_NEAR(lm.objective, nm.objective, 1e-6 * nm.objective + 1e-14);
  EXPECT_LT(std::abs(lm.theta.K - m.K), 3.0 * lm.theta.K_std + 1.0);
  EXPECT_LT(lm.theta.relative_force_error, 0.5 * nominal.relative_force_error);
  EXPECT_LT(lm.evaluations + lm.jacobian_evaluations, nm.evaluations);
  // Kaufman's simplified Jacobian converges to the same optimum.
  o.solver = Solver::levenberg_marquardt;
  o.jacobian = VpJacobian::kaufman;
  const auto ka = identify_geometry(p, o);
  EXPECT_LT(std::abs(ka.x[0] - lm.x[0]), 0.01 * s.prior_std()[0]);
}

TEST(Geometric, LCurveCornerIsInsideTheRange) {
  auto s = cube_on_block_with_uncertainties();
  Eigen::VectorXd truth = s.design();
  truth[0] = 6e-5;
  SensorModel sensor;
  sensor.force_noise_n = 0.5;
  sensor.seed = 5;
  const auto sim = simulate(s, ContactModel{}, truth, press_slide(150), sensor);
  ContactProblem p(s, measure(sim), {});
  const auto c = l_curve(p, {}, 1e-4, 1e3, 12);
  ASSERT_EQ(c.lambda.size(), 12u);
  EXPECT_GT(c.corner, 0u);
  EXPECT_LT(c.corner, 11u);
  // The force cost grows and the geometric cost shrinks with λ.
  EXPECT_LE(c.force_cost.front(), c.force_cost.back() * (1 + 1e-9));
  EXPECT_GE(c.geometric_cost.front(), c.geometric_cost.back());
}

}  // namespace
}  // namespace hil::contact_id::test
