// Rigid-body fit (Kabsch/SVD) and twist from filtered differences.
#include <gtest/gtest.h>

#include <random>

#include <hil/import/rigid_fit.hpp>
#include <hil/so3/so3.hpp>

namespace hil::import {
namespace {

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

Eigen::Matrix3Xd markers_body() {
  Eigen::Matrix3Xd b(3, 4);
  b << 0.20, -0.15, 0.05, 0.00,  //
      0.00, 0.10, -0.20, 0.05,   //
      0.00, 0.00, 0.03, 0.12;
  return b;
}

Eigen::Matrix3Xd to_world(const Eigen::Matrix3d& R, const Eigen::Vector3d& p, const Eigen::Matrix3Xd& b) { return (R * b).colwise() + p; }

TEST(RigidFit, ExactOnRotatedTranslatedMarkers) {
  std::mt19937 rng(1);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Eigen::Vector3d p = Eigen::Vector3d::Random();
    const auto fit = fit_rigid_body(markers_body(), to_world(R, p, markers_body()), {true, true, true, true}, 3);
    ASSERT_TRUE(fit);
    EXPECT_LT((fit->R_world_body - R).norm(), 1e-12);
    EXPECT_LT((fit->p_world_body_m - p).norm(), 1e-12);
    EXPECT_LT(fit->residual_rms_m, 1e-12);
    EXPECT_EQ(fit->markers_used, 4u);
  }
}

TEST(RigidFit, ThreePlanarMarkersGiveARotationNotAReflection) {
  std::mt19937 rng(2);
  const Eigen::Matrix3Xd b = markers_body().leftCols(3);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Eigen::Vector3d p(0.7, 0.5, 0.3);
    const auto fit = fit_rigid_body(b, to_world(R, p, b), {true, true, true}, 3);
    ASSERT_TRUE(fit);
    EXPECT_NEAR(fit->R_world_body.determinant(), 1.0, 1e-12);
    EXPECT_LT((fit->R_world_body - R).norm(), 1e-10);
    EXPECT_LT((fit->p_world_body_m - p).norm(), 1e-10);
  }
}

TEST(RigidFit, NoiseGivesSmallPoseErrorAndResidualOfTheNoiseSize) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.2e-3);  // 0.2 mm per coordinate
  double sum_rms2 = 0;
  const int trials = 400;
  for (int k = 0; k < trials; ++k) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Eigen::Vector3d p = Eigen::Vector3d::Random();
    Eigen::Matrix3Xd w = to_world(R, p, markers_body());
    for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] += noise(rng);
    const auto fit = fit_rigid_body(markers_body(), w, {true, true, true, true}, 3);
    ASSERT_TRUE(fit);
    EXPECT_LT((fit->p_world_body_m - p).norm(), 1.5e-3);
    EXPECT_LT(hil::so3::log(R.transpose() * fit->R_world_body).norm(), 10e-3);
    sum_rms2 += fit->residual_rms_m * fit->residual_rms_m;
  }
  // E[rms^2] = sigma^2 (3N - 6) / N for N markers (6 pose parameters absorbed): 0.2 mm * sqrt(6/4).
  EXPECT_NEAR(std::sqrt(sum_rms2 / trials), 0.2e-3 * std::sqrt(6.0 / 4.0), 0.02e-3);
}

TEST(RigidFit, MissingMarkerUsesTheRemainingThree) {
  std::mt19937 rng(4);
  const Eigen::Matrix3d R = random_rotation(rng);
  const Eigen::Vector3d p(1, 2, 3);
  Eigen::Matrix3Xd w = to_world(R, p, markers_body());
  w.col(1).setConstant(std::numeric_limits<double>::quiet_NaN());  // must not be read
  const auto fit = fit_rigid_body(markers_body(), w, {true, false, true, true}, 3);
  ASSERT_TRUE(fit);
  EXPECT_EQ(fit->markers_used, 3u);
  EXPECT_LT((fit->R_world_body - R).norm(), 1e-10);
  EXPECT_LT((fit->p_world_body_m - p).norm(), 1e-10);
}

TEST(RigidFit, TooFewOrCollinearMarkersFailWithAReason) {
  FitFailure why;
  const Eigen::Matrix3Xd b = markers_body();
  EXPECT_FALSE(fit_rigid_body(b, b, {true, false, false, true}, 3, &why));
  EXPECT_EQ(why.reason, "2 of 4 markers seen");
  EXPECT_FALSE(fit_rigid_body(b, b, {true, true, true, false}, 4, &why));
  EXPECT_EQ(why.reason, "3 of 4 markers seen");
  Eigen::Matrix3Xd line(3, 3);
  line << 0, 0.1, 0.2, 0, 0.1, 0.2, 0, 0, 0;
  EXPECT_FALSE(fit_rigid_body(line, line, {true, true, true}, 3, &why));
  EXPECT_EQ(why.reason, "seen markers are (nearly) collinear");
}

TEST(Twist, ExactForConstantVelocitiesWithUnevenStepsAndGaps) {
  const Eigen::Vector3d v(0.01, -0.02, 0.005), w(0.3, -0.1, 0.2), p0(0.5, 0.4, 0.3);
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  PoseTrack tr;
  double t = 0;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> step(0.005, 0.015);
  for (int i = 0; i < 300; ++i) {
    t += (i == 100) ? 0.027 : step(rng);  // one gap
    tr.t_s.push_back(t);
    tr.p_world_body_m.push_back(p0 + v * t);
    tr.q_world_body.push_back(Eigen::Quaterniond(Eigen::AngleAxisd(w.norm() * t, w.normalized())) * q0);
  }
  const auto tw = twist_from_poses(tr, 0.05);
  for (std::size_t i = 0; i < tr.t_s.size(); ++i) {
    EXPECT_LT((tw.v_world_m_per_s[i] - v).norm(), 1e-9) << i;
    EXPECT_LT((tw.w_world_rad_per_s[i] - w).norm(), 1e-9) << i;
  }
}

TEST(Twist, SmoothsNoise) {
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.05e-3);
  PoseTrack tr;
  for (int i = 0; i < 1000; ++i) {
    tr.t_s.push_back(0.01 * i);
    tr.p_world_body_m.push_back(Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    tr.q_world_body.push_back(Eigen::Quaterniond::Identity());
  }
  const auto wide = twist_from_poses(tr, 0.1), narrow = twist_from_poses(tr, 0.02);
  double s_wide = 0, s_narrow = 0;
  for (std::size_t i = 0; i < tr.t_s.size(); ++i)
    s_wide += wide.v_world_m_per_s[i].squaredNorm(), s_narrow += narrow.v_world_m_per_s[i].squaredNorm();
  EXPECT_LT(s_wide, 0.2 * s_narrow);
}

}  // namespace
}  // namespace hil::import
