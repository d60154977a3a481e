// Forward kinematics and Jacobians of the DH robot model, checked against finite differences and
// hand-computed poses, for both DH conventions and prismatic joints.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include <hil/test/eigen.hpp>
#include <hil/calibration/robot.hpp>

namespace hc = hil::calibration;

namespace {

hc::SerialRobot mixed_robot(hc::DhConvention convention) {
  hc::SerialRobot r;
  r.convention = convention;
  r.joints = {{"j1", hc::JointKind::revolute, 0.1, 1.2, 0.3, 0.2},
              {"j2", hc::JointKind::prismatic, 0.2, -0.7, 0.15, 0.4},
              {"j3", hc::JointKind::revolute, 0.5, 0.3, -0.1, -0.5},
              {"j4", hc::JointKind::revolute, 0.0, 1.5707963267948966, 0.4, 0.0}};
  r.T_world_base = Eigen::Translation3d(0.3, -0.2, 0.1) * Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized());
  r.T_flange_ee = Eigen::Translation3d(0.01, 0.02, 0.15) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitY());
  return r;
}

Eigen::MatrixXd numeric_jacobian(const hc::SerialRobot& r, const Eigen::VectorXd& q) {
  const double h = 1e-6;
  Eigen::MatrixXd J(6, q.size());
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    Eigen::VectorXd qp = q, qm = q;
    qp[i] += h;
    qm[i] -= h;
    J.col(i) = (hc::pose_difference(hc::tool_pose(r, qm), hc::tool_pose(r, qp))) / (2 * h);
  }
  return J;
}

}  // namespace

TEST(Kinematics, JacobianMatchesFiniteDifferencesBothConventions) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (auto conv : {hc::DhConvention::standard, hc::DhConvention::modified}) {
    const auto r = mixed_robot(conv);
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd q(4);
      for (int i = 0; i < 4; ++i) q[i] = u(rng);
      EXPECT_TRUE(hil::test::near(hc::tool_jacobian(r, q), numeric_jacobian(r, q), 1e-7));
    }
  }
}

TEST(Kinematics, Kr270AtZeroHasTheHandComputedToolPosition) {
  const auto r = hc::kr270_like();
  const Eigen::Isometry3d T = hc::tool_pose(r, Eigen::VectorXd::Zero(6));
  // Standard DH at q = 0, by hand: z1 = z2 = +y0, the upper arm (a2) and the elbow offset (a3) lie
  // along +x at the shoulder height d1, z3 = -z0 so the forearm (d4), flange (d6) and tool point down.
  EXPECT_TRUE(hil::test::near(T.translation(), Eigen::Vector3d(0.35 + 1.15 + 0.041, 0.0, 0.675 - 1.2 - 0.215 - 0.2), 1e-12))
      << T.translation().transpose();
  // Joint 2 moves the tool in the vertical x-z plane, joint 1 about the vertical axis.
  const Eigen::MatrixXd J = hc::tool_jacobian(r, Eigen::VectorXd::Zero(6));
  EXPECT_NEAR(J(1, 1), 0.0, 1e-12);
  EXPECT_TRUE(hil::test::near(J.col(0).tail<3>(), Eigen::Vector3d::UnitZ(), 1e-12));
}

TEST(Kinematics, ConventionsAgreeOnAnEquivalentPlanarArm) {
  // A planar 2R arm with link lengths 0.5 and 0.3, written in both conventions.
  hc::SerialRobot s, m;
  s.convention = hc::DhConvention::standard;
  s.joints = {{"j1", hc::JointKind::revolute, 0.5, 0.0, 0.0, 0.0}, {"j2", hc::JointKind::revolute, 0.3, 0.0, 0.0, 0.0}};
  m.convention = hc::DhConvention::modified;
  m.joints = {{"j1", hc::JointKind::revolute, 0.0, 0.0, 0.0, 0.0}, {"j2", hc::JointKind::revolute, 0.5, 0.0, 0.0, 0.0}};
  m.T_flange_ee = Eigen::Isometry3d(Eigen::Translation3d(0.3, 0.0, 0.0));
  const Eigen::Vector2d q(0.4, -1.1);
  const Eigen::Vector3d expect(0.5 * std::cos(0.4) + 0.3 * std::cos(0.4 - 1.1), 0.5 * std::sin(0.4) + 0.3 * std::sin(0.4 - 1.1), 0.0);
  EXPECT_TRUE(hil::test::near(hc::tool_pose(s, q).translation(), expect, 1e-12));
  EXPECT_TRUE(hil::test::near(hc::tool_pose(m, q).translation(), expect, 1e-12));
  EXPECT_TRUE(hil::test::near(hc::tool_jacobian(s, q), hc::tool_jacobian(m, q), 1e-12));
}

TEST(Kinematics, ToolInBaseIsTheToolPoseWithoutTheBase) {
  // The allocation-free form the Modbus driver calls per poll (through hil::rig_service), for both
  // conventions and a prismatic joint: T_world_base^-1 T_world_ee.
  for (const auto convention : {hc::DhConvention::standard, hc::DhConvention::modified}) {
    const hc::SerialRobot r = mixed_robot(convention);
    const Eigen::Vector4d q(0.3, 0.05, -1.2, 2.0);
    const Eigen::Isometry3d expect = r.T_world_base.inverse() * hc::tool_pose(r, q);
    EXPECT_TRUE(hil::test::near(hc::tool_in_base(r, q.data()).matrix(), expect.matrix(), 1e-12));
  }
  // Craig's convention with a prismatic last joint, by hand: joint 1 turns 90° about z, link 1 m,
  // the slider adds 0.25 m to d = 0.5 m along z, the tool 0.1 m further along z.
  hc::SerialRobot craig;
  craig.convention = hc::DhConvention::modified;
  craig.joints = {{"j1", hc::JointKind::revolute, 0.0, 0.0, 0.0, 0.0},
                  {"j2", hc::JointKind::revolute, 1.0, 0.0, 0.0, 0.0},
                  {"j3", hc::JointKind::prismatic, 0.0, 0.0, 0.5, 0.0}};
  craig.T_flange_ee = Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, 0.1));
  const double q[3] = {1.5707963267948966, 0.0, 0.25};
  EXPECT_TRUE(hil::test::near(hc::tool_in_base(craig, q).translation(), Eigen::Vector3d(0, 1, 0.85), 1e-12));
}

TEST(Kinematics, WrongJointCountIsRefused) {
  EXPECT_THAT([] { hc::forward(hc::kr270_like(), Eigen::VectorXd::Zero(5)); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("forward: expected 6 joint values")));
}
