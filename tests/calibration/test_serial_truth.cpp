// The truth generator of the blind point-calibration tests (serial_truth.cpp) against what it claims:
// KDL's forward kinematics when every effect is off, the cantilever closed forms on a one-link robot
// built here, joint springs at their equilibrium, the two sides of backlash, the base tilting
// towards the overhang, the offsets of flagged postures, the base inclinometer's reading and noise,
// the random stream the blind suite's seeds depend on, and bad input refused by name. The
// expectations are computed here, from KDL and from the equations, not from the generator's own
// intermediate values.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "serial_truth.hpp"

namespace ts = hil::test::serial;
using Vec = Eigen::Vector3d;
using testing::HasSubstr;

namespace {

const std::string kUr10 = std::string(HIL_SOURCE_DIR) + "/examples/robots/ur10.urdf";
const std::string kArm7 = std::string(HIL_SOURCE_DIR) + "/examples/robots/arm7_like.urdf";
constexpr double kG = 9.80665;

KDL::Chain chain_of(const std::string& urdf, const std::string& base, const std::string& tip) {
  KDL::Tree tree;
  if (!kdl_parser::treeFromFile(urdf, tree)) throw std::runtime_error("cannot read " + urdf);
  KDL::Chain chain;
  if (!tree.getChain(base, tip, chain)) throw std::runtime_error("no chain");
  return chain;
}

KDL::JntArray jnt(const Eigen::VectorXd& q) {
  KDL::JntArray a(static_cast<unsigned>(q.size()));
  a.data = q;
  return a;
}

Vec ev(const KDL::Vector& v) { return {v.x(), v.y(), v.z()}; }

// KDL's forward kinematics of a point of the tip frame.
Vec fk(const KDL::Chain& chain, const Eigen::VectorXd& q, const Vec& tool) {
  KDL::ChainFkSolverPos_recursive solver(chain);
  KDL::Frame F;
  solver.JntToCart(jnt(q), F);
  return ev(F * KDL::Vector(tool.x(), tool.y(), tool.z()));
}

// KDL's holding torques (no payload).
Eigen::VectorXd kdl_gravity(const KDL::Chain& chain, const Eigen::VectorXd& q) {
  KDL::ChainDynParam dyn(chain, KDL::Vector(0.0, 0.0, -kG));
  KDL::JntArray G(chain.getNrOfJoints());
  dyn.JntToGravity(jnt(q), G);
  return G.data;
}

// Holding torques from the equations: joint i must cancel the moment about its axis of the weight
// of everything it carries, τ_i = −z_i · Σ (c_j − o_i) × m_j g, payload included.
Eigen::VectorXd hand_gravity(const KDL::Chain& chain, const Eigen::VectorXd& q, double payload_kg, const Vec& payload_com_tip) {
  const unsigned n = chain.getNrOfSegments();
  std::vector<Vec> z, o, c;
  std::vector<int> seg_of_joint;
  std::vector<double> m;
  KDL::Frame F = KDL::Frame::Identity();
  unsigned j = 0;
  for (unsigned i = 0; i < n; ++i) {
    const KDL::Segment& s = chain.getSegment(i);
    const bool moves = s.getJoint().getType() != KDL::Joint::Fixed;
    if (moves) {
      z.push_back(ev(F.M * s.getJoint().JointAxis()));
      o.push_back(ev(F * s.getJoint().JointOrigin()));
      seg_of_joint.push_back(static_cast<int>(i));
    }
    F = F * s.pose(moves ? q[j++] : 0.0);
    m.push_back(s.getInertia().getMass());
    c.push_back(ev(F * s.getInertia().getCOG()));
  }
  m.push_back(payload_kg);
  c.push_back(ev(F * KDL::Vector(payload_com_tip.x(), payload_com_tip.y(), payload_com_tip.z())));
  const Vec g(0.0, 0.0, -kG);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(z.size()));
  for (std::size_t i = 0; i < z.size(); ++i) {
    Vec M = Vec::Zero();
    for (std::size_t k = static_cast<std::size_t>(seg_of_joint[i]); k < c.size(); ++k) M += (c[k] - o[i]).cross(m[k] * g);
    tau[static_cast<Eigen::Index>(i)] = -z[i].dot(M);
  }
  return tau;
}

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double a : v) x[i++] = a;
  return x;
}

Eigen::VectorXd unit(int n, int i) { return Eigen::VectorXd::Unit(n, i); }

ts::Truth ur10_truth() {
  ts::Truth t;
  t.urdf = kUr10;
  t.base = "base_link";
  t.tip = "wrist_3_link";
  t.T_station_base = {Eigen::Isometry3d::Identity()};
  t.tool_point_m = Vec(0.03, -0.02, 0.12);
  return t;
}

// A horizontal-ish UR10 posture reaching along +x (q = 0 stretches the arm along +x).
Eigen::VectorXd ur10_reach() { return vec({0.0, -0.2, 0.3, -1.0, 1.2, 0.5}); }

// A URDF written to a temporary file for the duration of a test (unique per test and process:
// ctest may run the tests of this binary in parallel).
struct TempUrdf {
  std::filesystem::path path;
  explicit TempUrdf(const std::string& xml) {
    path = std::filesystem::temp_directory_path() /
           ("serial_truth_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()) + ".urdf");
    std::ofstream(path) << xml;
  }
  ~TempUrdf() { std::filesystem::remove(path); }
  TempUrdf(const TempUrdf&) = delete;
  TempUrdf& operator=(const TempUrdf&) = delete;
};

// One revolute joint about z, 0.5 m above the base, carrying a horizontal 1 m link along its x of
// mass `m`, a fixed tip at its end; optionally a second revolute joint about z at the end of the
// first link with a 0.5 m link of mass `m2` (centre of mass at its middle) and the tip at its end.
std::string beam_urdf(double m, double m2 = -1.0) {
  const auto inertial = [](double mass, double x) {
    return "<inertial><mass value=\"" + std::to_string(mass) + "\"/><origin xyz=\"" + std::to_string(x) +
           " 0 0\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial>";
  };
  std::string x = R"(<?xml version="1.0"?>
<robot name="beam">
  <link name="world"/>
  <joint name="j1" type="revolute">
    <parent link="world"/><child link="arm"/><origin xyz="0 0 0.5" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.2" upper="3.2" effort="100" velocity="1"/>
  </joint>
  <link name="arm">)" +
                  inertial(m, 0.5) + "</link>\n";
  if (m2 < 0.0) {
    x += R"(  <joint name="tip_joint" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="1 0 0" rpy="0 0 0"/></joint>)";
  } else {
    x += R"(  <joint name="j2" type="revolute">
    <parent link="arm"/><child link="arm2"/><origin xyz="1 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.2" upper="3.2" effort="100" velocity="1"/>
  </joint>
  <link name="arm2">)" +
         inertial(m2, 0.25) +
         R"(</link>
  <joint name="tip_joint" type="fixed"><parent link="arm2"/><child link="tip"/><origin xyz="0.5 0 0" rpy="0 0 0"/></joint>)";
  }
  return x + "\n  <link name=\"tip\"/>\n</robot>\n";
}

ts::Truth beam_truth(const std::string& urdf, double EI, double GJ = 0.0) {
  ts::Truth t;
  t.urdf = urdf;
  t.base = "world";
  t.tip = "tip";
  t.beams = {{"arm", EI, GJ}};
  t.T_station_base = {Eigen::Isometry3d::Identity()};
  return t;
}

// Where a point of the tip frame goes when the beam's end D moves by δ and turns by θ (rotation
// vector) and carries the rest rigidly.
Vec carried(const Vec& D, const Vec& delta, const Vec& theta, const Vec& nominal) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(theta.norm(), theta.normalized()).toRotationMatrix();
  return D + delta + R * (nominal - D);
}

Vec one(const ts::Truth& t, const Eigen::VectorXd& q) {
  std::mt19937 rng(1);
  return ts::generate(t, {q}, rng).at(0).p_base_m;
}

}  // namespace

TEST(SerialTruth, AllEffectsOffIsKdlForwardKinematicsSeenFromEachStation) {
  std::mt19937 rng(7);
  ts::Truth t = ur10_truth();
  t.T_station_base = {ts::random_station(rng, 3.0, 2.0), ts::random_station(rng, 3.0, 2.0), ts::random_station(rng, 3.0, 2.0)};
  const auto postures = ts::draw_postures(40, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  const auto samples = ts::generate(t, postures, rng);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  ASSERT_EQ(samples.size(), postures.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto& s = samples[k];
    EXPECT_EQ(s.station, static_cast<int>(k % 3));
    EXPECT_EQ(s.q, postures[k]);
    EXPECT_EQ(s.q_link, postures[k]);
    EXPECT_LT((s.p_base_m - fk(chain, s.q, t.tool_point_m)).norm(), 1e-12) << k;
    EXPECT_LT((s.p_station_m - t.T_station_base[static_cast<std::size_t>(s.station)] * s.p_base_m).norm(), 1e-12) << k;
  }
}

TEST(SerialTruth, DrawnPosturesStayInTheirRanges) {
  std::mt19937 rng(3);
  const std::vector<std::pair<double, double>> r = {{-1.0, -0.5}, {0.0, 0.0}, {2.0, 3.0}};
  const auto q = ts::draw_postures(200, r, rng);
  ASSERT_EQ(q.size(), 200u);
  double lo0 = 0.0, hi0 = -2.0;
  for (const auto& x : q) {
    ASSERT_EQ(x.size(), 3);
    for (int j = 0; j < 3; ++j) {
      EXPECT_GE(x[j], r[static_cast<std::size_t>(j)].first);
      EXPECT_LE(x[j], r[static_cast<std::size_t>(j)].second);
    }
    lo0 = std::min(lo0, x[0]);
    hi0 = std::max(hi0, x[0]);
  }
  EXPECT_LT(lo0, -0.95);  // spread over the range, not stuck at a point
  EXPECT_GT(hi0, -0.55);
}

TEST(SerialTruth, JointOffsetsShiftTheLinkSide) {
  ts::Truth t = ur10_truth();
  t.joint_offset_rad = vec({0.01, -0.02, 0.003, 0.0, 0.05, -0.01});
  const Eigen::VectorXd q = ur10_reach();
  std::mt19937 rng(1);
  const auto s = ts::generate(t, {q}, rng).at(0);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  EXPECT_LT((s.p_base_m - fk(chain, q + t.joint_offset_rad, t.tool_point_m)).norm(), 1e-12);
  EXPECT_GT((s.p_base_m - fk(chain, q, t.tool_point_m)).norm(), 1e-3);
}

TEST(SerialTruth, AnEncoderErrorTurnsWithTheJoint) {
  ts::Truth t = ur10_truth();
  t.joint_offset_rad = vec({0.0, 0.001, 0.0, 0.0, 0.0, 0.0});
  t.encoder_error_rad = vec({0.0, 0.002, 0.004, 0.0, 0.0, 0.0});
  t.encoder_phase_rad = vec({0.0, 0.3, -1.0, 0.0, 0.0, 0.0});
  std::mt19937 rng(1);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  for (double elbow : {-2.0, 0.0, 1.5}) {
    Eigen::VectorXd q = ur10_reach();
    q[2] = elbow;
    const auto s = ts::generate(t, {q}, rng).at(0);
    Eigen::VectorXd expect = q + t.joint_offset_rad;
    expect[1] += 0.002 * std::sin(q[1] + 0.3);
    expect[2] += 0.004 * std::sin(elbow - 1.0);
    EXPECT_LT((s.q_link - expect).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((s.p_base_m - fk(chain, expect, t.tool_point_m)).norm(), 1e-12);
  }
}

TEST(SerialTruth, NoiseHasTheGivenSpreadPerCoordinate) {
  std::mt19937 rng(11);
  ts::Truth t = ur10_truth();
  t.T_station_base = {ts::random_station(rng, 1.0, 1.0), ts::random_station(rng, 1.0, 1.0)};
  t.noise_m = 1e-3;
  const auto postures = ts::draw_postures(2000, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  const auto samples = ts::generate(t, postures, rng);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  for (const auto& s : samples) {
    const Vec r = s.p_station_m - t.T_station_base[static_cast<std::size_t>(s.station)] * s.p_base_m;
    sum += r;
    sq += r.cwiseProduct(r);
  }
  const double n = static_cast<double>(samples.size());
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(sum[a] / n, 0.0, 1e-4);                    // 4.5 standard errors
    EXPECT_NEAR(std::sqrt(sq[a] / n), 1e-3, 0.07 * 1e-3);  // standard error of σ: 1.6 %
  }
}

TEST(SerialTruth, BeamSagsUnderItsOwnWeightByTheClosedForms) {
  const double m = 10.0, L = 1.0, EI = 2e4, d = 0.2;
  const TempUrdf urdf(beam_urdf(m));
  ts::Truth t = beam_truth(urdf.path.string(), EI);
  const double w = m * kG / L, sag = w * std::pow(L, 4) / (8 * EI), turn = w * std::pow(L, 3) / (6 * EI);
  for (double q1 : {0.0, 0.7, -2.0}) {
    const Vec e(std::cos(q1), std::sin(q1), 0.0), D = Vec(0, 0, 0.5) + L * e;
    t.tool_point_m = Vec::Zero();
    const Vec end = one(t, vec({q1}));
    EXPECT_LT((end - (D - sag * Vec::UnitZ())).norm(), 1e-12) << q1;
    EXPECT_LT(end.z(), D.z());  // down, the way the weight pushes
    // A point ahead of the end on the beam's axis drops further by d·sin θ: the end tangent turned.
    t.tool_point_m = Vec(d, 0, 0);
    const Vec ahead = one(t, vec({q1}));
    EXPECT_NEAR(ahead.z(), 0.5 - sag - d * std::sin(turn), 1e-12) << q1;
    EXPECT_LT((ahead.head<2>() - (D + d * std::cos(turn) * e).head<2>()).norm(), 1e-12) << q1;
  }
  // Twice as stiff, half the sag: the deflection is not a constant.
  t.tool_point_m = Vec::Zero();
  t.beams[0].EI_Nm2 = 2 * EI;
  EXPECT_NEAR(one(t, vec({0.0})).z(), 0.5 - sag / 2, 1e-12);
}

TEST(SerialTruth, PayloadAtTheEndAddsTheEndForceTerms) {
  const double m = 10.0, L = 1.0, EI = 2e4, P_kg = 5.0, d = 0.2;
  const TempUrdf urdf(beam_urdf(m));
  ts::Truth t = beam_truth(urdf.path.string(), EI);
  t.payload_kg = P_kg;
  const double w = m * kG / L, P = P_kg * kG;
  const double sag = w * std::pow(L, 4) / (8 * EI) + P * std::pow(L, 3) / (3 * EI);
  const double turn = w * std::pow(L, 3) / (6 * EI) + P * L * L / (2 * EI);
  EXPECT_NEAR(one(t, vec({0.0})).z(), 0.5 - sag, 1e-12);
  t.tool_point_m = Vec(d, 0, 0);
  const Vec ahead = one(t, vec({0.0}));
  EXPECT_NEAR(ahead.z(), 0.5 - sag - d * std::sin(turn), 1e-12);
  EXPECT_NEAR(ahead.x(), L + d * std::cos(turn), 1e-12);
}

TEST(SerialTruth, PayloadBesideTheEndBendsAndTwistsTheBeam) {
  // Payload ahead of the end by a and beside it by c: the end moment aP bends, −cP twists.
  const double m = 4.0, L = 1.0, EI = 3e4, GJ = 1e4, P_kg = 6.0, a = 0.1, c = 0.15;
  const TempUrdf urdf(beam_urdf(m));
  ts::Truth t = beam_truth(urdf.path.string(), EI, GJ);
  t.payload_kg = P_kg;
  t.payload_com_tip_m = Vec(a, c, 0.0);
  const double w = m * kG / L, P = P_kg * kG, M = a * P, T = -c * P;
  const double sag = w * std::pow(L, 4) / (8 * EI) + P * std::pow(L, 3) / (3 * EI) + M * L * L / (2 * EI);
  const double bend = w * std::pow(L, 3) / (6 * EI) + P * L * L / (2 * EI) + M * L / EI;
  const double twist = T * L / GJ;
  for (double q1 : {0.0, 1.1}) {
    const Vec e(std::cos(q1), std::sin(q1), 0.0), side(-std::sin(q1), std::cos(q1), 0.0), D = Vec(0, 0, 0.5) + L * e;
    const Vec theta = bend * side + twist * e;  // bending about e × (−z) = side
    for (const Vec& tool : {Vec(0, 0, 0), Vec(0.2, 0, 0), Vec(0, 0.2, 0), Vec(0.05, -0.1, 0.3)}) {
      t.tool_point_m = tool;
      const Vec nominal = D + tool.x() * e + tool.y() * side + tool.z() * Vec::UnitZ();
      EXPECT_LT((one(t, vec({q1})) - carried(D, -sag * Vec::UnitZ(), theta, nominal)).norm(), 1e-12) << q1 << " " << tool.transpose();
    }
    // The side of the end that carries the payload drops: the beam twists the way the load pushes.
    t.tool_point_m = Vec(0, 0.2, 0);
    const double z_side = one(t, vec({q1})).z();
    t.tool_point_m = Vec(0, -0.2, 0);
    EXPECT_LT(z_side, one(t, vec({q1})).z());
  }
  // GJ = 0: rigid in torsion, the two sides drop alike.
  t.beams[0].GJ_Nm2 = 0.0;
  t.tool_point_m = Vec(0, 0.2, 0);
  const double z_side = one(t, vec({0.0})).z();
  t.tool_point_m = Vec(0, -0.2, 0);
  EXPECT_NEAR(z_side, one(t, vec({0.0})).z(), 1e-15);
}

TEST(SerialTruth, BeamEndsAtTheNextJointAndCarriesTheRestRigidly) {
  // Two links: the beam is the first (1 m, to the second joint); the second link's weight at its
  // centre of mass loads the end with a force and a moment that twists when the link turns aside.
  const double m = 3.0, m2 = 2.0, L = 1.0, EI = 5e3, GJ = 2e3;
  const TempUrdf urdf(beam_urdf(m, m2));
  ts::Truth t = beam_truth(urdf.path.string(), EI, GJ);
  const KDL::Chain chain = chain_of(urdf.path.string(), "world", "tip");
  for (double q2 : {0.0, 0.9, -2.5}) {
    const Eigen::VectorXd q = vec({0.0, q2});
    const Vec D(L, 0, 0.5), u(std::cos(q2), std::sin(q2), 0.0);
    const double w = m * kG / L, P = m2 * kG;
    const Vec M = (0.25 * u).cross(Vec(0, 0, -P));  // about D
    const double T = M.x(), Mb = M.y();             // beam along x: torsion about x, bending about y
    const double sag = w * std::pow(L, 4) / (8 * EI) + P * std::pow(L, 3) / (3 * EI) + Mb * L * L / (2 * EI);
    const Vec theta(T * L / GJ, w * std::pow(L, 3) / (6 * EI) + P * L * L / (2 * EI) + Mb * L / EI, 0.0);
    for (const Vec& tool : {Vec(0, 0, 0), Vec(0.1, 0.2, -0.1)}) {
      t.tool_point_m = tool;
      const Vec expected = carried(D, -sag * Vec::UnitZ(), theta, fk(chain, q, tool));
      EXPECT_LT((one(t, q) - expected).norm(), 1e-12) << q2 << " " << tool.transpose();
    }
  }
}

TEST(SerialTruth, TwoBeamsCompose) {
  // The second link, a beam from its joint to the tip, bends under its own weight; the first
  // carries it, bent as well: the tip point goes through the second motion, then the first.
  const double m = 3.0, m2 = 2.0, EI = 5e3, GJ = 2e3, EI2 = 1e3;
  const TempUrdf urdf(beam_urdf(m, m2));
  ts::Truth t = beam_truth(urdf.path.string(), EI, GJ);
  t.beams.push_back({"arm2", EI2, 0.0});
  t.tool_point_m = Vec(0.05, 0.1, 0.02);
  const KDL::Chain chain = chain_of(urdf.path.string(), "world", "tip");
  const double q2 = 0.9, L = 1.0, L2 = 0.5;
  const Vec D(L, 0, 0.5), u(std::cos(q2), std::sin(q2), 0.0), E = D + L2 * u;
  const double w = m * kG / L, w2 = m2 * kG / L2, P = m2 * kG;
  const Vec M = (0.25 * u).cross(Vec(0, 0, -P));
  const Vec theta1(M.x() * L / GJ, w * std::pow(L, 3) / (6 * EI) + P * L * L / (2 * EI) + M.y() * L / EI, 0.0);
  const double sag1 = w * std::pow(L, 4) / (8 * EI) + P * std::pow(L, 3) / (3 * EI) + M.y() * L * L / (2 * EI);
  const Vec theta2 = u.cross(-Vec::UnitZ()) * (w2 * std::pow(L2, 3) / (6 * EI2));
  const double sag2 = w2 * std::pow(L2, 4) / (8 * EI2);
  const Eigen::VectorXd q = vec({0.0, q2});
  const Vec expected = carried(D, -sag1 * Vec::UnitZ(), theta1, carried(E, -sag2 * Vec::UnitZ(), theta2, fk(chain, q, t.tool_point_m)));
  EXPECT_LT((one(t, q) - expected).norm(), 1e-12);
}

TEST(SerialTruth, BeamOnTheUr10ForearmLowersTheTool) {
  ts::Truth t = ur10_truth();
  const Vec rigid = one(t, ur10_reach());
  t.beams = {{"forearm_link", 2e5, 1e5}};
  const Vec bent = one(t, ur10_reach());
  EXPECT_LT(bent.z(), rigid.z() - 1e-5);
  EXPECT_LT((bent - rigid).norm(), 5e-3);
}

TEST(SerialTruth, JointSpringSagsTheArmByTauOverK) {
  ts::Truth t = ur10_truth();
  const double k = 2e5;
  t.joint_stiffness_Nm_per_rad = k * unit(6, 1);  // only the shoulder lift yields
  const Eigen::VectorXd q = ur10_reach();
  std::mt19937 rng(1);
  const auto s = ts::generate(t, {q}, rng).at(0);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  const Eigen::VectorXd dq = s.q_link - q;
  for (int j = 0; j < 6; ++j)
    if (j != 1) {
      EXPECT_EQ(dq[j], 0.0) << j;
    }
  // The equilibrium itself (torque at the deflected arm), and τ/k to first order.
  const double tau_link = kdl_gravity(chain, s.q_link)[1], tau_cmd = kdl_gravity(chain, q)[1];
  ASSERT_GT(std::abs(tau_cmd), 50.0);  // the posture does load the joint
  EXPECT_NEAR(dq[1], -tau_link / k, 1e-12);
  EXPECT_NEAR(dq[1], -tau_cmd / k, 1e-3 * std::abs(tau_cmd / k));
  EXPECT_NE(dq[1], -tau_cmd / k);  // solved at the deflected arm, not linearised
  EXPECT_LT((s.p_base_m - fk(chain, s.q_link, t.tool_point_m)).norm(), 1e-12);
  // The tool goes down, by the joint's Jacobian column times Δq.
  const Vec rigid = fk(chain, q, t.tool_point_m);
  EXPECT_LT(s.p_base_m.z(), rigid.z() - 1e-4);
  const double h = 1e-6;
  const Vec column = (fk(chain, q + h * unit(6, 1), t.tool_point_m) - fk(chain, q - h * unit(6, 1), t.tool_point_m)) / (2 * h);
  EXPECT_LT((s.p_base_m - rigid - column * dq[1]).norm(), 1e-3 * (s.p_base_m - rigid).norm());
}

TEST(SerialTruth, PayloadLoadsEveryJointAsTheEquationsSay) {
  ts::Truth t = ur10_truth();
  t.joint_stiffness_Nm_per_rad = vec({1e5, 5e4, 4e4, 1e4, 1e4, 5e3});
  t.payload_kg = 8.0;
  t.payload_com_tip_m = Vec(0.05, 0.02, 0.1);
  std::mt19937 rng(5);
  const auto postures = ts::draw_postures(10, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  const auto samples = ts::generate(t, postures, rng);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  for (const auto& s : samples) {
    const Eigen::VectorXd tau = hand_gravity(chain, s.q_link, t.payload_kg, t.payload_com_tip_m);
    const Eigen::VectorXd expected = s.q - tau.cwiseQuotient(t.joint_stiffness_Nm_per_rad);
    EXPECT_LT((s.q_link - expected).cwiseAbs().maxCoeff(), 1e-11);
    // Without the payload's torque the equilibrium would be elsewhere.
    const Eigen::VectorXd bare = s.q - hand_gravity(chain, s.q_link, 0.0, Vec::Zero()).cwiseQuotient(t.joint_stiffness_Nm_per_rad);
    EXPECT_GT((s.q_link - bare).cwiseAbs().maxCoeff(), 1e-5);
  }
}

TEST(SerialTruth, BacklashUnderSmallTorqueSitsOnTheSideOfTheApproach) {
  // The shoulder pan turns about the vertical: gravity never loads it, the last move decides.
  ts::Truth t = ur10_truth();
  const double b = 1e-3;
  t.backlash_rad = b * unit(6, 0);
  const Eigen::VectorXd q = ur10_reach(), e0 = unit(6, 0);
  std::mt19937 rng(1);
  const auto s = ts::generate(t, {q, q - 0.2 * e0, q, q + 0.2 * e0, q, q}, rng);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  EXPECT_NEAR(s[0].q_link[0], q[0] + b, 1e-15);  // before any move: +b
  EXPECT_NEAR(s[2].q_link[0], q[0] - b, 1e-15);  // reached from below: the link lags behind the motor
  EXPECT_NEAR(s[4].q_link[0], q[0] + b, 1e-15);  // reached from above
  EXPECT_NEAR(s[5].q_link[0], q[0] + b, 1e-15);  // not moved: stays where it was
  const Vec from_below = fk(chain, q - b * e0, t.tool_point_m), from_above = fk(chain, q + b * e0, t.tool_point_m);
  EXPECT_LT((s[2].p_base_m - from_below).norm(), 1e-12);
  EXPECT_LT((s[4].p_base_m - from_above).norm(), 1e-12);
  EXPECT_GT((s[2].p_base_m - s[4].p_base_m).norm(), 1e-3);  // ≈ 2b times the reach (> 1 m)
  for (int j = 1; j < 6; ++j) EXPECT_EQ(s[4].q_link[j], q[j]);
}

TEST(SerialTruth, BacklashUnderGravitySitsOnTheGravitySideWhateverTheApproach) {
  ts::Truth t = ur10_truth();
  const double b = 1e-3;
  t.backlash_rad = b * unit(6, 1);  // the shoulder lift holds the stretched arm
  const Eigen::VectorXd q = ur10_reach(), e1 = unit(6, 1);
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  const double tau = kdl_gravity(chain, q)[1];
  ASSERT_GT(std::abs(tau), 50.0);
  const std::vector<Eigen::VectorXd> moves = {q - 0.2 * e1, q, q + 0.2 * e1, q};
  std::mt19937 rng(1);
  auto s = ts::generate(t, moves, rng);
  const double gravity_side = q[1] - b * (tau > 0 ? 1.0 : -1.0);
  EXPECT_NEAR(s[1].q_link[1], gravity_side, 1e-15);
  EXPECT_NEAR(s[3].q_link[1], gravity_side, 1e-15);
  EXPECT_EQ(s[1].p_base_m, s[3].p_base_m);
  // The tool hangs lower than at the middle of the play.
  EXPECT_LT(s[1].p_base_m.z(), fk(chain, q, t.tool_point_m).z());
  // With a friction no torque overcomes, the approach decides again.
  t.backlash_friction_Nm = 1e6 * Eigen::VectorXd::Ones(6);
  s = ts::generate(t, moves, rng);
  EXPECT_NEAR(s[1].q_link[1], q[1] - b, 1e-15);  // reached from below: lagging
  EXPECT_NEAR(s[3].q_link[1], q[1] + b, 1e-15);  // reached from above
}

TEST(SerialTruth, BaseSpringsTiltTheArmDownOnTheSideItOverhangs) {
  ts::Truth t = ur10_truth();
  const double k = 1e6;
  const KDL::Chain chain = chain_of(kUr10, "base_link", "wrist_3_link");
  for (double pan : {0.0, std::numbers::pi / 2, std::numbers::pi, -2.2}) {
    Eigen::VectorXd q = ur10_reach();
    q[0] = pan;
    t.base_stiffness_Nm_per_rad = 0.0;
    const Vec rigid = one(t, q);
    t.base_stiffness_Nm_per_rad = k;
    const Vec tilted = one(t, q);
    // The weight's moment about the base origin (the UR10's base link has its mass there).
    KDL::ChainFkSolverPos_recursive solver(chain);
    Vec M = Vec::Zero();
    for (unsigned i = 0; i < chain.getNrOfSegments(); ++i) {
      KDL::Frame F;
      solver.JntToCart(jnt(q), F, static_cast<int>(i + 1));
      const KDL::RigidBodyInertia& I = chain.getSegment(i).getInertia();
      M += ev(F * I.getCOG()).cross(Vec(0, 0, -kG * I.getMass()));
    }
    const Vec tilt = M / k;
    EXPECT_LT((tilted - Eigen::AngleAxisd(tilt.norm(), tilt.normalized()) * rigid).norm(), 1e-12) << pan;
    // Down on the overhang's side: the tilt turns the horizontal reach towards −z.
    EXPECT_LT(tilted.z(), rigid.z() - 1e-5) << pan;
    const Vec reach(rigid.x(), rigid.y(), 0.0);
    EXPECT_GT(tilt.dot(reach.cross(-Vec::UnitZ())), 0.0) << pan;
  }
}

TEST(SerialTruth, TheBaseLinksOwnWeightRestsOnTheBaseSpringsToo) {
  // arm7_like's base link has its centre of mass off the base origin: a tilt even with no arm.
  ts::Truth t;
  t.urdf = kArm7;
  t.base = "base_link";
  t.tip = "flange";
  t.T_station_base = {Eigen::Isometry3d::Identity()};
  t.tool_point_m = Vec(0, 0, 0.1);
  t.payload_kg = 2.0;
  t.payload_com_tip_m = Vec(0.1, 0, 0.05);
  const Eigen::VectorXd q = vec({0.4, 1.0, -0.3, -1.2, 0.2, 0.8, -0.5});
  const Vec rigid = one(t, q);
  t.base_stiffness_Nm_per_rad = 2e5;
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromFile(kArm7, tree));
  const KDL::RigidBodyInertia& Ib = GetTreeElementSegment(tree.getSegment("base_link")->second).getInertia();
  ASSERT_GT(Ib.getMass(), 0.0);
  Vec M = ev(Ib.getCOG()).cross(Vec(0, 0, -kG * Ib.getMass()));
  const KDL::Chain chain = chain_of(kArm7, "base_link", "flange");
  KDL::ChainFkSolverPos_recursive solver(chain);
  KDL::Frame F;
  for (unsigned i = 0; i < chain.getNrOfSegments(); ++i) {
    solver.JntToCart(jnt(q), F, static_cast<int>(i + 1));
    const KDL::RigidBodyInertia& I = chain.getSegment(i).getInertia();
    M += ev(F * I.getCOG()).cross(Vec(0, 0, -kG * I.getMass()));
  }
  M += ev(F * KDL::Vector(0.1, 0, 0.05)).cross(Vec(0, 0, -kG * t.payload_kg));
  const Vec tilt = M / t.base_stiffness_Nm_per_rad;
  EXPECT_LT((one(t, q) - Eigen::AngleAxisd(tilt.norm(), tilt.normalized()) * rigid).norm(), 1e-12);
}

TEST(SerialTruth, EverythingOnAtOnceStaysSmallFiniteAndRepeatable) {
  ts::Truth t;
  t.urdf = kArm7;
  t.base = "base_link";
  t.tip = "flange";
  std::mt19937 rng(21);
  t.T_station_base = {ts::random_station(rng, 2.0, 2.0), ts::random_station(rng, 2.0, 2.0)};
  t.tool_point_m = Vec(0.01, 0.02, 0.15);
  t.joint_offset_rad = 1e-3 * vec({1, -2, 3, -1, 2, -3, 1});
  t.joint_stiffness_Nm_per_rad = vec({2e5, 2e5, 1e5, 1e5, 5e4, 5e4, 2e4});
  t.backlash_rad = 2e-4 * Eigen::VectorXd::Ones(7);
  t.beams = {{"link_2", 4e5, 2e5}, {"link_4", 3e5, 0.0}, {"link_7", 1e5, 1e5}};
  t.base_stiffness_Nm_per_rad = 5e6;
  t.payload_kg = 3.0;
  t.payload_com_tip_m = Vec(0, 0, 0.08);
  t.noise_m = 2e-5;
  const auto postures = ts::draw_postures(50, std::vector<std::pair<double, double>>(7, {-2.0, 2.0}), rng);
  std::mt19937 a(9), b(9);
  const auto s = ts::generate(t, postures, a), again = ts::generate(t, postures, b);
  ts::Truth rigid = t;
  rigid.joint_offset_rad = {};
  rigid.joint_stiffness_Nm_per_rad = {};
  rigid.backlash_rad = {};
  rigid.beams.clear();
  rigid.base_stiffness_Nm_per_rad = 0.0;
  const auto r = ts::generate(rigid, postures, a);
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_TRUE(s[k].p_station_m.allFinite());
    EXPECT_EQ(s[k].p_station_m, again[k].p_station_m);
    const double moved = (s[k].p_base_m - r[k].p_base_m).norm();
    EXPECT_GT(moved, 1e-4) << k;
    EXPECT_LT(moved, 2e-2) << k;
  }
}

TEST(SerialTruth, BadInputIsRefusedByName) {
  std::mt19937 rng(1);
  const Eigen::VectorXd q = ur10_reach();
  const auto refused = [&rng](const ts::Truth& t, const std::vector<Eigen::VectorXd>& postures, const std::string& what) {
    try {
      ts::generate(t, postures, rng);
      ADD_FAILURE() << "accepted; expected a refusal naming " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  ts::Truth t = ur10_truth();
  t.beams = {{"elbow_link", 1e5, 0.0}};
  refused(t, {q}, "elbow_link");
  t.beams = {{"wrist_3_link", 1e5, 0.0}};  // the chain's last link: its end is its origin
  refused(t, {q}, "zero length");
  t.beams = {{"forearm_link", 0.0, 0.0}};
  refused(t, {q}, "EI_Nm2");
  t.beams = {{"forearm_link", 1e5, 0.0}, {"forearm_link", 2e5, 0.0}};
  refused(t, {q}, "twice");
  t = ur10_truth();
  t.joint_offset_rad = Eigen::VectorXd::Zero(5);
  refused(t, {q}, "joint_offset_rad");
  t = ur10_truth();
  t.backlash_friction_Nm = Eigen::VectorXd::Zero(7);
  refused(t, {q}, "backlash_friction_Nm");
  t = ur10_truth();
  t.joint_stiffness_Nm_per_rad = -1.0 * Eigen::VectorXd::Ones(6);
  refused(t, {q}, "joint_stiffness_Nm_per_rad");
  refused(ur10_truth(), {q, Eigen::VectorXd::Zero(7)}, "posture 1");
  t = ur10_truth();
  t.T_station_base.clear();
  refused(t, {q}, "station");
  t = ur10_truth();
  t.tip = "no_such_link";
  refused(t, {q}, "no_such_link");
  t = ur10_truth();
  t.urdf = "/nonexistent/robot.urdf";
  refused(t, {q}, "/nonexistent/robot.urdf");
  const TempUrdf garbage("<robot name=\"broken\"><link name=\"a\"/><joint name=\"j\" type=\"revolute\"></robot>");
  t.urdf = garbage.path.string();
  refused(t, {q}, "KDL cannot read");
  EXPECT_THROW(ts::draw_postures(3, {{1.0, 0.0}}, rng), std::invalid_argument);
}

TEST(SerialTruth, FlagOffsetsMoveExactlyTheFlaggedPostures) {
  // Springs on, so the flag's offset must also reach the equilibrium (the holding torque is taken at
  // the offset link side); joint offsets on, so the flag's must come on top of them.
  ts::Truth t = ur10_truth();
  t.joint_offset_rad = 1e-3 * vec({0.5, -1.0, 0.3, 0.0, 1.0, -0.4});
  t.joint_stiffness_Nm_per_rad = vec({1e5, 5e4, 4e4, 1e4, 1e4, 5e3});
  t.flag_offset_rad = 1e-3 * vec({0.0, 0.0, 1.5, -2.0, 0.8, 0.0});
  std::mt19937 rng(13);
  const auto postures = ts::draw_postures(30, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  std::vector<bool> flags;
  for (std::size_t k = 0; k < postures.size(); ++k) flags.push_back(k % 3 == 0);
  const auto s = ts::generate(t, postures, flags, rng);
  // The expectations: the same robot with the flag's offsets made ordinary joint offsets (flagged
  // postures), or without them (the others).
  ts::Truth flagged = t, plain = t;
  flagged.joint_offset_rad = t.joint_offset_rad + t.flag_offset_rad;
  flagged.flag_offset_rad = {};
  plain.flag_offset_rad = {};
  const auto as_flagged = ts::generate(flagged, postures, rng), as_plain = ts::generate(plain, postures, rng);
  ASSERT_EQ(s.size(), postures.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_EQ(s[k].flag, flags[k]) << k;
    const ts::Sample& expected = flags[k] ? as_flagged[k] : as_plain[k];
    EXPECT_LT((s[k].p_base_m - expected.p_base_m).norm(), 1e-12) << k;
    EXPECT_LT((s[k].q_link - expected.q_link).cwiseAbs().maxCoeff(), 1e-12) << k;
    if (flags[k]) {
      EXPECT_GT((s[k].p_base_m - as_plain[k].p_base_m).norm(), 1e-4) << k;  // the flag does move them
    }
  }
}

TEST(SerialTruth, BaseTiltReadingIsTheTiltThePointsShow) {
  // Everything that deflects the chain on, the base too: the reading must be the rotation that
  // takes the chain on a rigid base to the chain on the springs, about the base origin.
  ts::Truth t = ur10_truth();
  t.joint_offset_rad = 1e-3 * vec({0.5, -1.0, 0.3, 0.0, 1.0, -0.4});
  t.joint_stiffness_Nm_per_rad = vec({1e5, 5e4, 4e4, 1e4, 1e4, 5e3});
  t.beams = {{"upper_arm_link", 5e4, 2e4}, {"forearm_link", 5e4, 0.0}};
  t.payload_kg = 5.0;
  t.payload_com_tip_m = Vec(0.02, -0.03, 0.1);
  t.base_stiffness_Nm_per_rad = 3e5;
  std::mt19937 rng(17);
  const auto postures = ts::draw_postures(30, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  ts::Truth rigid_base = t;
  rigid_base.base_stiffness_Nm_per_rad = 0.0;
  const auto s = ts::generate(t, postures, rng), rigid = ts::generate(rigid_base, postures, rng);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const Vec theta(s[k].base_tilt_rad.x(), s[k].base_tilt_rad.y(), 0.0);
    EXPECT_GT(theta.norm(), 1e-5) << k;  // the arm's weight does tilt the base
    EXPECT_LT(theta.norm(), 1e-2) << k;
    const Vec turned = Eigen::AngleAxisd(theta.norm(), theta.normalized()) * rigid[k].p_base_m;
    EXPECT_LT((turned - s[k].p_base_m).norm(), 1e-9) << k;
    EXPECT_GT((rigid[k].p_base_m - s[k].p_base_m).norm(), 1e-5) << k;
    EXPECT_EQ(rigid[k].base_tilt_rad, Eigen::Vector2d::Zero()) << k;  // a rigid base reads nothing
  }
}

TEST(SerialTruth, BaseTiltReadingsHaveTheGivenNoise) {
  for (double k_base : {0.0, 3e5}) {
    ts::Truth t = ur10_truth();
    t.base_stiffness_Nm_per_rad = k_base;
    t.tilt_noise_rad = 1e-5;
    std::mt19937 rng(19);
    const auto postures = ts::draw_postures(2000, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
    ts::Truth quiet = t;
    quiet.tilt_noise_rad = 0.0;
    const auto s = ts::generate(t, postures, rng), exact = ts::generate(quiet, postures, rng);
    Eigen::Vector2d sum = Eigen::Vector2d::Zero(), sq = Eigen::Vector2d::Zero();
    double cross = 0.0;
    for (std::size_t k = 0; k < s.size(); ++k) {
      const Eigen::Vector2d r = s[k].base_tilt_rad - exact[k].base_tilt_rad;
      sum += r;
      sq += r.cwiseProduct(r);
      cross += r.x() * r.y();
    }
    const double n = static_cast<double>(s.size());
    for (int a = 0; a < 2; ++a) {
      EXPECT_NEAR(sum[a] / n, 0.0, 1e-6) << k_base;                    // 4.5 standard errors
      EXPECT_NEAR(std::sqrt(sq[a] / n), 1e-5, 0.07 * 1e-5) << k_base;  // standard error of σ: 1.6 %
    }
    EXPECT_LT(std::abs(cross / std::sqrt(sq.x() * sq.y())), 0.1) << k_base;  // x and y independent (standard error 0.022)
  }
}

TEST(SerialTruth, NoiseIsDrawnPointFirstThenTiltAndTiltOnlyWhenAsked) {
  // The blind suite's seeds fix its draws: the stream the generator takes from `rng` is three
  // standard normals per posture for the point, then two for the inclinometer only when it has
  // noise, and nothing else.
  ts::Truth t = ur10_truth();
  t.base_stiffness_Nm_per_rad = 0.0;  // the reading is its noise alone
  std::mt19937 pr(23);
  const auto postures = ts::draw_postures(21, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), pr);
  for (const auto& [noise_m, tilt_noise_rad] : {std::pair{1e-3, 0.0}, std::pair{1e-3, 1e-5}, std::pair{0.0, 1e-5}}) {
    t.noise_m = noise_m;
    t.tilt_noise_rad = tilt_noise_rad;
    std::mt19937 a(29), b(29);
    const auto s = ts::generate(t, postures, a);
    std::normal_distribution<double> n(0.0, 1.0);
    for (const auto& smp : s) {
      const Vec r = smp.p_station_m - t.T_station_base[0] * smp.p_base_m;
      for (int ax = 0; ax < 3; ++ax) EXPECT_NEAR(r[ax], noise_m > 0 ? noise_m * n(b) : 0.0, 1e-12) << noise_m << " " << tilt_noise_rad;
      for (int ax = 0; ax < 2; ++ax)
        EXPECT_NEAR(smp.base_tilt_rad[ax], tilt_noise_rad > 0 ? tilt_noise_rad * n(b) : 0.0, 1e-15) << noise_m << " " << tilt_noise_rad;
    }
    const auto next = a();
    EXPECT_EQ(next, b()) << noise_m << " " << tilt_noise_rad;  // the same number of draws taken
    // Flags take nothing from the stream: flagged postures get the same noise.
    std::vector<bool> flags;
    for (std::size_t k = 0; k < postures.size(); ++k) flags.push_back(k % 2 == 1);
    std::mt19937 c(29);
    const auto f = ts::generate(t, postures, flags, c);
    for (std::size_t k = 0; k < s.size(); ++k) {
      EXPECT_EQ(f[k].p_station_m, s[k].p_station_m) << k;
      EXPECT_EQ(f[k].base_tilt_rad, s[k].base_tilt_rad) << k;
    }
    EXPECT_EQ(c(), next) << noise_m << " " << tilt_noise_rad;
  }
}

TEST(SerialTruth, WithoutFlagsBothOverloadsGiveTheSameSamples) {
  ts::Truth t = ur10_truth();
  std::mt19937 rng(37);
  t.T_station_base = {ts::random_station(rng, 2.0, 2.0), ts::random_station(rng, 2.0, 2.0)};
  t.joint_offset_rad = 1e-3 * vec({0.5, -1.0, 0.3, 0.0, 1.0, -0.4});
  t.flag_offset_rad = 1e-3 * vec({0.0, 0.0, 1.5, -2.0, 0.8, 0.0});  // no flagged posture: never applied
  t.backlash_rad = 5e-4 * Eigen::VectorXd::Ones(6);
  t.base_stiffness_Nm_per_rad = 4e5;
  t.noise_m = 5e-5;
  const auto postures = ts::draw_postures(25, std::vector<std::pair<double, double>>(6, {-3.0, 3.0}), rng);
  ts::Truth unflagged = t;
  unflagged.flag_offset_rad = {};
  std::mt19937 a(43), b(43), c(43), d(43);
  const auto old = ts::generate(t, postures, a), none = ts::generate(t, postures, {}, b),
             unset = ts::generate(t, postures, std::vector<bool>(postures.size(), false), c), bare = ts::generate(unflagged, postures, d);
  ASSERT_EQ(old.size(), postures.size());
  for (const auto* other : {&none, &unset, &bare}) {
    ASSERT_EQ(other->size(), old.size());
    for (std::size_t k = 0; k < old.size(); ++k) {
      EXPECT_EQ(old[k].p_station_m, (*other)[k].p_station_m) << k;
      EXPECT_EQ(old[k].p_base_m, (*other)[k].p_base_m) << k;
      EXPECT_EQ(old[k].q_link, (*other)[k].q_link) << k;
      EXPECT_EQ(old[k].base_tilt_rad, (*other)[k].base_tilt_rad) << k;
      EXPECT_FALSE((*other)[k].flag) << k;
    }
  }
  EXPECT_FALSE(old[0].flag);
  const auto next = a();
  EXPECT_EQ(next, b());
  EXPECT_EQ(next, c());
  EXPECT_EQ(next, d());
}

TEST(SerialTruth, BadFlagsAndTiltNoiseAreRefusedByName) {
  std::mt19937 rng(1);
  const Eigen::VectorXd q = ur10_reach();
  const auto refused = [&rng](const ts::Truth& t, const std::vector<bool>& flags, const std::string& what) {
    try {
      ts::generate(t, {ur10_reach(), ur10_reach()}, flags, rng);
      ADD_FAILURE() << "accepted; expected a refusal naming " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  ts::Truth t = ur10_truth();
  refused(t, {true}, "flags");
  refused(t, {true, false, true}, "flags");
  t.flag_offset_rad = Eigen::VectorXd::Zero(7);
  refused(t, {true, false}, "flag_offset_rad");
  t = ur10_truth();
  t.tilt_noise_rad = -1e-6;
  refused(t, {}, "tilt_noise_rad");
  EXPECT_NO_THROW(ts::generate(ur10_truth(), {q, q}, {true, false}, rng));
}
