// Geometry and mindist on analytic cases with known answers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "scenes.hpp"

namespace hil::contact_id::test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

::testing::AssertionResult near_vec(const Vec3& a, const Vec3& b, double tol) {
  if ((a - b).norm() <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "[" << a.transpose() << "] vs [" << b.transpose() << "], |diff| = " << (a - b).norm() << " > "
                                       << tol;
}

TEST(Polyhedron, CubeTopology) {
  const auto p = Polyhedron::from_vertices(box({0, 0, 0}, {1, 2, 3}));
  EXPECT_EQ(p.vertices().size(), 8u);
  EXPECT_EQ(p.faces().size(), 6u);
  EXPECT_EQ(p.edges().size(), 12u);
  EXPECT_EQ(p.edge_directions().size(), 3u);
  EXPECT_NEAR(p.volume(), 6.0, 1e-12);
  for (const auto& f : p.faces()) {
    EXPECT_EQ(f.loop.size(), 4u);
    for (const auto& v : p.vertices()) EXPECT_LE(f.normal.dot(v), f.offset + 1e-12);
  }
}

TEST(Polyhedron, DropsInteriorPointsAndRejectsFlat) {
  auto v = box({0, 0, 0}, {1, 1, 1});
  v.emplace_back(0.5, 0.5, 0.5);
  EXPECT_EQ(Polyhedron::from_vertices(v).vertices().size(), 8u);
  EXPECT_THAT(
      [] {
        Polyhedron::from_vertices({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});
      },
      ThrowsMessage<std::invalid_argument>(HasSubstr("coplanar (no volume)")));
  EXPECT_THAT(
      [] {
        Polyhedron::from_vertices({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
      },
      ThrowsMessage<std::invalid_argument>(HasSubstr("at least 4 vertices")));
}

TEST(Mindist, FaceFace) {
  const auto cube = Polyhedron::from_vertices(box({-0.015, -0.015, 0.0}, {0.015, 0.015, 0.03}));
  const auto block = Polyhedron::from_vertices(box({-0.1, -0.1, -0.05}, {0.1, 0.1, 0.0}));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double d = 3e-4;
  T.translation() = Vec3(0.02, -0.01, -d);
  ClipWorkspace ws;
  PairContact c;
  ASSERT_TRUE(penetration(posed(cube, T), posed(block), c, ws));
  EXPECT_NEAR(c.delta, d, 1e-15);
  EXPECT_TRUE(near_vec(c.normal, Vec3::UnitZ(), 1e-15));
  EXPECT_TRUE(near_vec(c.point, Vec3(0.02, -0.01, -d / 2), 1e-12));
  // Separated and exactly touching: no contact.
  T.translation().z() = 1e-6;
  EXPECT_FALSE(penetration(posed(cube, T), posed(block), c, ws));
  T.translation().z() = 0.0;
  EXPECT_FALSE(penetration(posed(cube, T), posed(block), c, ws));
}

TEST(Mindist, VertexFace) {
  // A square pyramid, apex down at the origin of its frame.
  const auto pyr =
      Polyhedron::from_vertices({{0, 0, 0}, {-0.02, -0.02, 0.02}, {0.02, -0.02, 0.02}, {0.02, 0.02, 0.02}, {-0.02, 0.02, 0.02}});
  EXPECT_EQ(pyr.faces().size(), 5u);
  const auto block = Polyhedron::from_vertices(box({-0.1, -0.1, -0.05}, {0.1, 0.1, 0.0}));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double d = 4e-4;
  T.translation() = Vec3(0.01, 0.03, -d);
  ClipWorkspace ws;
  PairContact c;
  ASSERT_TRUE(penetration(posed(pyr, T), posed(block), c, ws));
  EXPECT_NEAR(c.delta, d, 1e-15);
  EXPECT_TRUE(near_vec(c.normal, Vec3::UnitZ(), 1e-15));
  // Centroid of the immersed pyramid: 3/4 of its height above the apex.
  EXPECT_TRUE(near_vec(c.point, Vec3(0.01, 0.03, -d + 0.75 * d), 1e-12));
}

TEST(Mindist, EdgeEdge) {
  // Two square bars crossed at right angles, each turned 45° about its axis: edge on edge.
  const double a = 0.01;
  const auto barx = Polyhedron::from_vertices(box({-0.1, -a, -a}, {0.1, a, a}));
  const auto bary = Polyhedron::from_vertices(box({-a, -0.1, -a}, {a, 0.1, a}));
  const double h = a * std::sqrt(2.0);  // centre to edge
  const double d = 2e-4;
  Eigen::Isometry3d TA = Eigen::Isometry3d::Identity(), TB = Eigen::Isometry3d::Identity();
  TA.linear() = Eigen::AngleAxisd(M_PI / 4, Vec3::UnitX()).toRotationMatrix();
  TA.translation() = Vec3(0.0, 0.0, h - d);  // lower edge at z = -d
  TB.linear() = Eigen::AngleAxisd(M_PI / 4, Vec3::UnitY()).toRotationMatrix();
  TB.translation() = Vec3(0.0, 0.0, -h);  // upper edge at z = 0
  ClipWorkspace ws;
  PairContact c;
  ASSERT_TRUE(penetration(posed(barx, TA), posed(bary, TB), c, ws));
  EXPECT_NEAR(c.delta, d, 1e-14);
  EXPECT_TRUE(near_vec(c.normal, Vec3::UnitZ(), 1e-12));
  EXPECT_TRUE(near_vec(c.point, Vec3(0.0, 0.0, -d / 2), 1e-12));
}

TEST(Mindist, TiltedFaceIsContinuousInPose) {
  const auto cube = Polyhedron::from_vertices(box({-0.015, -0.015, 0.0}, {0.015, 0.015, 0.03}));
  const auto block = Polyhedron::from_vertices(box({-0.1, -0.1, -0.05}, {0.1, 0.1, 0.0}));
  ClipWorkspace ws;
  PairContact prev;
  bool first = true;
  for (int i = -50; i <= 50; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    const double ang = 1e-4 * i;  // through the flat configuration
    T.linear() = Eigen::AngleAxisd(ang, Vec3::UnitX()).toRotationMatrix();
    T.translation() = Vec3(0, 0, -3e-4);
    PairContact c;
    ASSERT_TRUE(penetration(posed(cube, T), posed(block), c, ws));
    // Deepest corner: 3e-4 + 0.015 |sin ang| (to first order).
    EXPECT_NEAR(c.delta, 3e-4 + 0.015 * std::abs(std::sin(ang)), 1e-9);
    if (!first) {
      EXPECT_LT(std::abs(c.delta - prev.delta), 2e-6);
      EXPECT_LT((c.point - prev.point).norm(), 2e-4);
    }
    prev = c;
    first = false;
  }
}

// A solver's finite differences replay a recorded separating-axis pass after a small motion: the
// result must be the full pass's, bit for bit, for translations and turns, in contact or apart.
TEST(Mindist, ReplayAfterSmallMotionEqualsTheFullPass) {
  // A chamfered guide (many faces, nearly parallel edges after a turn) against a V-groove wall.
  std::vector<Vec3> guide = {{-0.01, -0.005, 0},       {0.01, -0.005, 0},       {0.01, 0.005, 0},       {-0.01, 0.005, 0},
                             {-0.008, -0.003, -0.004}, {0.008, -0.003, -0.004}, {0.008, 0.003, -0.004}, {-0.008, 0.003, -0.004}};
  const auto a = Polyhedron::from_vertices(guide);
  const auto b = Polyhedron::from_vertices(box({-0.05, -0.05, -0.02}, {0.05, 0.05, -0.003}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ClipWorkspace ws;
  int replayed = 0, apart = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = (Eigen::AngleAxisd(0.05 * u(rng), Vec3::UnitX()) * Eigen::AngleAxisd(0.05 * u(rng), Vec3::UnitY()) *
                  Eigen::AngleAxisd(0.3 * u(rng), Vec3::UnitZ()))
                     .toRotationMatrix();
    T.translation() = Vec3(0.01 * u(rng), 0.01 * u(rng), 0.001 + 0.003 * u(rng));
    const double max_turn = 1e-5;
    SatRecord rec;
    PairContact base;
    const auto A = posed(a, T), B = posed(b);
    penetration_recorded(A, B, max_turn, base, rec, ws);
    // A motion about a point off the guide, within the recorded turn.
    const bool turn = trial % 2 == 1;
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    if (turn) {
      const Vec3 pivot(0.1 * u(rng), 0.1 * u(rng), 0.0);
      M = Eigen::Translation3d(pivot) * Eigen::AngleAxisd(max_turn * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()) *
          Eigen::Translation3d(-pivot);
    } else {
      M.translation() = 1e-7 * Vec3(u(rng), u(rng), u(rng));
    }
    const auto A2 = posed(a, M * T);
    double moved = 0.0;
    for (std::size_t i = 0; i < A.vertices.size(); ++i) moved = std::max(moved, (A2.vertices[i] - A.vertices[i]).norm());
    const double turned = Eigen::AngleAxisd(M.linear()).angle();
    PairContact full, fast;
    const bool in_full = near(A2, B) && penetration(A2, B, full, ws);
    const bool in_fast = penetration_after_motion(A2, B, rec, moved * (1 + 1e-9) + 1e-15, turned * (1 + 1e-9), fast, ws);
    ASSERT_EQ(in_full, in_fast) << "trial " << trial;
    if (in_full) {
      EXPECT_EQ(full.delta, fast.delta) << "trial " << trial;
      EXPECT_EQ(full.normal, fast.normal) << "trial " << trial;
      EXPECT_EQ(full.point, fast.point) << "trial " << trial;
      // (the record allows the replay: the other candidates are far above the best)
      replayed += rec.gap < 0.0 && std::min(rec.second_still, rec.second_turning) > rec.best + 1e-5;
    } else {
      apart += rec.gap >= 0.0;
    }
  }
  // Both branches were exercised.
  EXPECT_GT(replayed, 40);
  EXPECT_GT(apart, 40);
  std::printf("replayable %d, apart %d of 400\n", replayed, apart);
}

TEST(Mindist, SceneBroadPhaseAndTangent) {
  auto s = cube_on_block();
  Kinematics k;
  k.T_world_ee.translation() = Vec3(0, 0, -2e-4);
  k.v_world_ee = Vec3(0.01, 0, 0);
  MindistWorkspace ws;
  std::vector<ContactPoint> c;
  mindist(s, k, s.design(), 1e-3, c, ws);
  ASSERT_EQ(c.size(), 1u);  // the far block is culled by the broad phase
  EXPECT_EQ(c[0].poly2, 0);
  EXPECT_TRUE(near_vec(c[0].tangent, -Vec3::UnitX(), 1e-15));
  k.v_world_ee = Vec3(5e-4, 0, 0);  // below the sticking threshold
  mindist(s, k, s.design(), 1e-3, c, ws);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(near_vec(c[0].tangent, Vec3::Zero(), 0.0));
  k.T_world_ee.translation().z() = 1e-3;
  mindist(s, k, s.design(), 1e-3, c, ws);
  EXPECT_TRUE(c.empty());
}

TEST(Uncertainty, TransformsComposeInListOrder) {
  std::vector<Uncertainty> us(2);
  us[0].kind = Uncertainty::Kind::translation;
  us[0].axis = Vec3::UnitX();
  us[1].kind = Uncertainty::Kind::rotation;
  us[1].axis = Vec3::UnitZ();
  us[1].point = Vec3(1, 0, 0);
  Eigen::VectorXd x(2);
  x << 0.5, M_PI / 2;
  const auto T = feature_transform(us, x, 0, 0);
  // (0,0,0) -> translate -> (0.5,0,0) -> rotate 90° about z through (1,0,0) -> (1,-0.5,0)
  EXPECT_TRUE(near_vec(T * Vec3::Zero(), Vec3(1, -0.5, 0), 1e-15));
  EXPECT_TRUE(near_vec(feature_transform(us, x, 0, 1) * Vec3(1, 2, 3), Vec3(1, 2, 3), 0.0));
}

}  // namespace
}  // namespace hil::contact_id::test
