// The VJM model: spring Jacobians against finite rigid displacements, the oracle A(q, w | π) π = t
// for complete, symmetrised and reduced sets and for every measurement kind, joint aggregation.
#include <gtest/gtest.h>

#include <random>

#include <hil/test/eigen.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/calibration/observation.hpp>
#include <hil/calibration/reduction.hpp>

namespace hc = hil::calibration;

namespace {

Eigen::VectorXd random_q(const hc::VjmModel& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  Eigen::VectorXd q(m.dof());
  for (int i = 0; i < m.dof(); ++i) q[i] = u(rng);
  return q;
}

hc::Vector6d random_wrench(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  hc::Vector6d w;
  for (int i = 0; i < 6; ++i) w[i] = (i < 3 ? 800.0 : 150.0) * g(rng);
  return w;
}

/// A random (non-symmetric, not SPD) compliance set: the oracle holds for any matrices.
hc::ComplianceSet random_compliance(const hc::VjmModel& m, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1e-7);
  hc::ComplianceSet k = m.zero_compliance();
  for (auto& ks : k) ks = ks.unaryExpr([&](double) { return g(rng); });
  return k;
}

Eigen::Isometry3d twist_exp(const hc::Vector6d& d) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (d.tail<3>().norm() > 0) T.linear() = Eigen::AngleAxisd(d.tail<3>().norm(), d.tail<3>().normalized()).toRotationMatrix();
  T.translation() = d.head<3>();
  return T;
}

}  // namespace

TEST(Vjm, SixRobotHasThirteenSpringsAnd258Entries) {
  const hc::VjmModel m(hc::kr270_like());
  EXPECT_EQ(m.springs().size(), 13u);
  EXPECT_EQ(hc::complete_parameters(m).size(), 258u);
  EXPECT_EQ(m.springs()[0].name, "L0");
  EXPECT_EQ(m.springs()[1].name, "J1");
  EXPECT_EQ(m.springs()[12].name, "L6");
  // Link 2 runs from the shoulder to the elbow: a2 = 1.15 m along its x axis.
  EXPECT_NEAR(m.springs()[static_cast<std::size_t>(m.link_spring(2))].length_m, 1.15, 1e-12);
}

TEST(Vjm, LinkSpringJacobianMovesTheToolLikeARigidDisplacementAtTheSpring) {
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(11);
  hc::VjmWorkspace ws;
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd q = random_q(m, rng);
    m.jacobians(q, ws);
    for (int link = 0; link <= m.dof(); ++link) {
      const int s = m.link_spring(link);
      const Eigen::Isometry3d T_WS = m.spring_pose(s, ws.poses);
      for (int axis = 0; axis < 6; ++axis) {
        const double h = 1e-7;
        hc::Vector6d d = hc::Vector6d::Zero();
        d[axis] = h;
        // Everything distal to the spring moves by the small displacement d expressed in S.
        const Eigen::Isometry3d T_ee = T_WS * twist_exp(d) * T_WS.inverse() * ws.poses.T_world_ee;
        const hc::Vector6d fd = hc::pose_difference(ws.poses.T_world_ee, T_ee) / h;
        EXPECT_TRUE(hil::test::near(ws.J[static_cast<std::size_t>(s)].col(axis), fd, 1e-6)) << "link " << link << " axis " << axis;
      }
    }
  }
}

TEST(Vjm, JointSpringJacobianIsTheToolJacobianColumn) {
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(5);
  hc::VjmWorkspace ws;
  const Eigen::VectorXd q = random_q(m, rng);
  m.jacobians(q, ws);
  const Eigen::MatrixXd J = hc::tool_jacobian(m.robot(), q);
  for (int j = 1; j <= 6; ++j) EXPECT_TRUE(hil::test::near(ws.J[static_cast<std::size_t>(m.joint_spring(j))].col(0), J.col(j - 1), 1e-12));
}

TEST(Vjm, ObservationTimesParametersEqualsForwardDeflectionForEveryParameterSet) {
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(7);
  const hc::ParameterSet complete = hc::complete_parameters(m);
  const hc::ParameterSet sym = hc::m1_symmetrise(complete);
  const hc::ParameterSet sparse = hc::m2_sparsify(m, sym);
  hc::VjmWorkspace ws;
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::VectorXd q = random_q(m, rng);
    const hc::Vector6d w = random_wrench(rng);
    m.jacobians(q, ws);
    for (const hc::ParameterSet* set : {&complete, &sym, &sparse}) {
      // Values drawn at random; the compliance they describe is assembled independently.
      std::normal_distribution<double> g(0.0, 1e-7);
      Eigen::VectorXd pi(static_cast<Eigen::Index>(set->size()));
      for (auto& v : pi) v = g(rng);
      const hc::ComplianceSet k = hc::assemble(m, *set, pi);
      Eigen::MatrixXd A(6, pi.size());
      hc::tool_observation(m, *set, ws, w, A);
      EXPECT_TRUE(hil::test::near(A * pi, m.deflection(k, q, w), 1e-18, 1e-12)) << "set of " << set->size();
    }
  }
}

TEST(Vjm, DeflectionEqualsSumOfSpringTermsComputedDirectly) {
  // Independent oracle: t = Σ J_s k_s J_sᵀ w written out with plain matrices.
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(8);
  const hc::ComplianceSet k = random_compliance(m, rng);
  const Eigen::VectorXd q = random_q(m, rng);
  const hc::Vector6d w = random_wrench(rng);
  hc::VjmWorkspace ws;
  m.jacobians(q, ws);
  hc::Vector6d t = hc::Vector6d::Zero();
  for (std::size_t s = 0; s < k.size(); ++s) {
    const Eigen::MatrixXd Js = ws.J[s].leftCols(k[s].rows());
    t += Js * k[s] * Js.transpose() * w;
  }
  EXPECT_TRUE(hil::test::near(m.deflection(k, q, w), t, 1e-18, 1e-12));
}

TEST(Vjm, MeasurementKindsProjectTheToolDisplacement) {
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(9);
  const hc::ComplianceSet k = hc::example_compliance(m);
  hc::Measurement meas;
  meas.q_rad = random_q(m, rng);
  meas.w_world = 1e-3 * random_wrench(rng);  // µm deflections: second-order terms below 1e-12 m
  const hc::Vector6d t = m.deflection(k, meas.q_rad, meas.w_world);
  meas.kind = hc::MeasurementKind::point3;
  EXPECT_TRUE(hil::test::near(hc::predict(m, k, meas), t.head<3>(), 1e-18, 1e-12));
  meas.kind = hc::MeasurementKind::markers;
  meas.p_ee_marker_m = {Eigen::Vector3d(0.1, 0.0, 0.0), Eigen::Vector3d(0.0, -0.2, 0.05)};
  const Eigen::Isometry3d T = hc::tool_pose(m.robot(), meas.q_rad);
  const Eigen::VectorXd got = hc::predict(m, k, meas);
  ASSERT_EQ(got.size(), 6);
  for (int i = 0; i < 2; ++i) {
    // A marker moves with the displaced tool: (exp(t) T) p - T p, to first order.
    const Eigen::Vector3d p = T * meas.p_ee_marker_m[static_cast<std::size_t>(i)];
    const Eigen::Vector3d moved = Eigen::AngleAxisd(t.tail<3>().norm(), t.tail<3>().normalized()) * (p - T.translation()) +
                                  T.translation() + t.head<3>();
    EXPECT_TRUE(hil::test::near(got.segment<3>(3 * i), moved - p, 2e-12)) << "marker " << i;
  }
}

TEST(Vjm, AggregatedJointsGiveTheSameDeflectionsAndFitTheBeamTemplate) {
  const hc::VjmModel m(hc::kr270_like());
  std::mt19937_64 rng(10);
  const hc::ComplianceSet k = hc::example_compliance(m);
  const hc::ComplianceSet agg = hc::aggregate_joints(m, k);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = random_q(m, rng);
    const hc::Vector6d w = random_wrench(rng);
    EXPECT_TRUE(hil::test::near(m.deflection(agg, q, w), m.deflection(k, q, w), 1e-18, 1e-12));
  }
  // Spring frames put each joint axis on a frame axis: the aggregated links still fit eq. 12.
  const hc::Template beam = hc::beam_template();
  for (int link = 0; link <= 6; ++link) {
    const auto& K = agg[static_cast<std::size_t>(m.link_spring(link))];
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) {
        if (!beam(r, c)) {
          EXPECT_LT(std::abs(K(r, c)), 1e-12 * K.cwiseAbs().maxCoeff()) << "L" << link << " (" << r << "," << c << ")";
        }
      }
  }
}

TEST(Vjm, CartesianComplianceIsSpdAndChecksFlagBadMatrices) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ComplianceSet k = hc::example_compliance(m);
  for (const auto& c : hc::check_spd(m, k)) EXPECT_TRUE(c.positive_definite) << c.spring;
  const hc::Matrix6d C = m.cartesian_compliance(k, Eigen::VectorXd::Constant(6, 0.3));
  EXPECT_TRUE(hil::test::near(C, C.transpose(), 1e-20));
  k[2](0, 1) += 1e-6;  // L1 made asymmetric
  k[4](3, 3) = -1e-6;  // L2 made indefinite
  const auto checks = hc::check_spd(m, k);
  EXPECT_FALSE(checks[2].symmetric);
  EXPECT_FALSE(checks[2].positive_definite);
  EXPECT_TRUE(checks[4].symmetric);
  EXPECT_FALSE(checks[4].positive_definite);
  EXPECT_LT(checks[4].min_eigenvalue, 0.0);
}

TEST(Vjm, CompensatedJointsCancelTheDeflection) {
  const hc::VjmModel m(hc::kr270_like());
  const hc::ComplianceSet k = hc::example_compliance(m, 3.0, 3.0);
  const Eigen::VectorXd q = (Eigen::VectorXd(6) << 0.2, -1.1, 0.8, 0.3, 0.7, -0.4).finished();
  hc::Vector6d w;
  w << 300.0, -200.0, -1500.0, 20.0, 0.0, 40.0;
  const hc::Vector6d t = m.deflection(k, q, w);
  ASSERT_GT(t.head<3>().norm(), 1e-3);  // a millimetre-size deflection to cancel
  double residual = 1.0;
  const Eigen::VectorXd qc = m.compensate(k, q, w, 8, &residual);
  EXPECT_LT(residual, 1e-9);
  // Independent check: the commanded pose plus its own deflection lands on the target.
  const hc::Vector6d err = hc::pose_difference(hc::tool_pose(m.robot(), q), hc::tool_pose(m.robot(), qc)) + m.deflection(k, qc, w);
  EXPECT_LT(err.norm(), 1e-9);
  EXPECT_GT((qc - q).norm(), 1e-4);
}
