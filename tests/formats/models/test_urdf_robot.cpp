// URDF robots (formats/format/src/urdf.cpp): the KR-270-like robot as a DH table and as a URDF gives
// the same poses, Jacobians and deflections; the chain hil builds from a URDF agrees with Orocos
// KDL's own solvers (an independent implementation) on the real UR10 description; bad URDFs and
// rig sections fail by name.
#include <gtest/gtest.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <random>

#include <hil/calibration/gravity.hpp>
#include <hil/calibration/vjm.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/error/error.hpp>
#include <hil/format/calibration_run.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>
#include <hil/models/stiffness_model.hpp>

namespace hc = hil::calibration;
namespace hf = hil::format;

namespace {

const std::string kExamples = std::string(HIL_SOURCE_DIR) + "/examples/stiffness/";
const std::string kUr10 = std::string(HIL_SHARED_DIR) + "/data/ur10-calibration/ur10.urdf";
const std::string kPalletizer = std::string(HIL_SOURCE_DIR) + "/examples/robots/palletizer_mimic.urdf";

/// The real UR10 description lives in ../shared beside the clone, not in the repository.
#define SKIP_WITHOUT_UR10()                                \
  if (!std::filesystem::exists(kUr10))                     \
  GTEST_SKIP() << kUr10 << " is absent (../shared/data); " \
               << "the real UR10's description is not in the repository"

Eigen::VectorXd random_q(const hc::SerialRobot& r, std::mt19937& rng) {
  Eigen::VectorXd q(r.dof());
  for (int i = 0; i < r.dof(); ++i) {
    const auto& j = r.joints[static_cast<std::size_t>(i)];
    q[i] = std::uniform_real_distribution<double>(std::max(j.lower, -3.2), std::min(j.upper, 3.2))(rng);
  }
  return q;
}

/// A physically valid compliance set: SPD link springs, positive joint springs, random magnitudes.
hc::ComplianceSet random_compliance(const hc::VjmModel& m, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  hc::ComplianceSet k = m.zero_compliance();
  for (std::size_t s = 0; s < m.springs().size(); ++s) {
    if (m.springs()[s].dim == 1) {
      k[s](0, 0) = 1e-7 * (1.0 + std::abs(g(rng)));
    } else {
      Eigen::MatrixXd A(6, 6);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) A(r, c) = g(rng);
      k[s] = 1e-8 * (A * A.transpose() + Eigen::MatrixXd::Identity(6, 6));
    }
  }
  return k;
}

/// The FormatError `f` throws, as text; "(no error)" when it throws none.
std::string message(const std::function<void()>& f) {
  try {
    f();
  } catch (const hil::error::FormatError& e) {
    return std::string(e.what());
  }
  return std::string("(no error)");
}

}  // namespace

TEST(UrdfRobot, Kr270UrdfAndDhGiveTheSamePosesJacobiansAndDeflections) {
  const hc::SerialRobot dh = hil::models::load_robot(kExamples + "kr270_like.yaml");
  const hc::SerialRobot urdf = hil::models::load_robot(kExamples + "kr270_like_urdf.yaml");
  ASSERT_EQ(urdf.convention, hc::DhConvention::urdf);
  ASSERT_EQ(urdf.dof(), dh.dof());
  for (int i = 0; i < dh.dof(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    EXPECT_EQ(urdf.joints[ui].name, dh.joints[ui].name);
    EXPECT_DOUBLE_EQ(urdf.joints[ui].lower, dh.joints[ui].lower);
    EXPECT_DOUBLE_EQ(urdf.joints[ui].upper, dh.joints[ui].upper);
  }
  const hc::VjmModel mdh(dh), murdf(urdf);
  ASSERT_EQ(murdf.springs().size(), mdh.springs().size());
  std::mt19937 rng(20261127);
  const hc::ComplianceSet k = random_compliance(mdh, rng);
  double worst_pose = 0, worst_jac = 0, worst_defl = 0, scale_defl = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = random_q(dh, rng);
    const Eigen::Isometry3d Ta = hc::tool_pose(dh, q), Tb = hc::tool_pose(urdf, q);
    worst_pose = std::max(worst_pose, (Ta.matrix() - Tb.matrix()).cwiseAbs().maxCoeff());
    worst_jac = std::max(worst_jac, (hc::tool_jacobian(dh, q) - hc::tool_jacobian(urdf, q)).cwiseAbs().maxCoeff());
    hil::Vector6d w;
    for (int c = 0; c < 6; ++c) w[c] = std::normal_distribution<double>(0.0, c < 3 ? 1000.0 : 300.0)(rng);
    const hil::Vector6d da = mdh.deflection(k, q, w), db = murdf.deflection(k, q, w);
    worst_defl = std::max(worst_defl, (da - db).cwiseAbs().maxCoeff());
    scale_defl = std::max(scale_defl, da.cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_pose, 1e-12);
  EXPECT_LT(worst_jac, 1e-12);
  ASSERT_GT(scale_defl, 1e-6);  // deflections of a size that could disagree
  EXPECT_LT(worst_defl, 1e-12 * (1.0 + scale_defl));
  // The spring frames are geometric (joint origins and axes), so both forms place them alike.
  for (std::size_t s = 0; s < mdh.springs().size(); ++s) {
    const Eigen::VectorXd q = random_q(dh, rng);
    const Eigen::Isometry3d Sa = mdh.spring_pose(static_cast<int>(s), hc::forward(dh, q));
    const Eigen::Isometry3d Sb = murdf.spring_pose(static_cast<int>(s), hc::forward(urdf, q));
    EXPECT_LT((Sa.matrix() - Sb.matrix()).cwiseAbs().maxCoeff(), 1e-12) << mdh.springs()[s].name;
  }
}

TEST(UrdfRobot, ChainAgreesWithKdlSolversOnTheRealUr10) {
  SKIP_WITHOUT_UR10();
  const hf::RobotSpec spec = hf::read_urdf_robot(kUr10, "base_link", "tool0");
  ASSERT_EQ(spec.joints.size(), 6u);
  EXPECT_EQ(spec.joints[0].name, "shoulder_pan_joint");
  EXPECT_EQ(spec.joints[5].name, "wrist_3_joint");
  ASSERT_EQ(spec.body_links.size(), 7u);
  EXPECT_EQ(spec.body_links.back(), "wrist_3_link");  // tool0 is fixed: folded into the tool frame
  ASSERT_EQ(spec.inertials.size(), 7u);
  EXPECT_DOUBLE_EQ(spec.inertials[2].mass_kg, 12.93);                     // upper_arm_link
  EXPECT_NEAR(spec.inertials[2].com_m.z(), 0.306, 1e-12);                 // its centre of mass, in its frame
  EXPECT_NEAR(spec.inertials[2].inertia_kgm2(2, 2), 0.036365625, 1e-12);  // about the centre of mass
  const hc::SerialRobot robot = hil::models::to_serial_robot(spec);

  // KDL's own chain and solvers, built here from the file without hil's reader.
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromFile(kUr10, tree));
  KDL::Chain chain;
  ASSERT_TRUE(tree.getChain("base_link", "tool0", chain));
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  std::mt19937 rng(7131);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::VectorXd q = random_q(robot, rng);
    KDL::JntArray qk(6);
    for (int i = 0; i < 6; ++i) qk(static_cast<unsigned>(i)) = q[i];
    KDL::Frame F;
    ASSERT_GE(fk.JntToCart(qk, F), 0);
    const Eigen::Isometry3d T = hc::tool_pose(robot, q);
    for (unsigned r = 0; r < 3; ++r) {
      EXPECT_NEAR(T.translation()[r], F.p(r), 1e-12);
      for (unsigned c = 0; c < 3; ++c) EXPECT_NEAR(T.linear()(r, c), F.M(r, c), 1e-12);
    }
    KDL::Jacobian Jk(6);
    ASSERT_GE(jac.JntToJac(qk, Jk), 0);
    const Eigen::MatrixXd J = hc::tool_jacobian(robot, q);
    EXPECT_LT((J - Jk.data).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(UrdfRobot, GravityTorquesAgreeWithKdlOnTheRealUr10) {
  SKIP_WITHOUT_UR10();
  const hc::SerialRobot robot = hil::models::to_serial_robot(hf::read_urdf_robot(kUr10, "base_link", "tool0"));
  EXPECT_NEAR(hc::moving_mass_kg(robot), 7.778 + 12.93 + 3.87 + 1.96 + 1.96 + 0.202, 1e-12);
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromFile(kUr10, tree));
  KDL::Chain chain;
  ASSERT_TRUE(tree.getChain("base_link", "tool0", chain));
  KDL::ChainDynParam dyn(chain, KDL::Vector(0.0, 0.0, -9.80665));
  std::mt19937 rng(99);
  double worst = 0, largest = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::VectorXd q = random_q(robot, rng);
    KDL::JntArray qk(6), G(6);
    for (int i = 0; i < 6; ++i) qk(static_cast<unsigned>(i)) = q[i];
    ASSERT_GE(dyn.JntToGravity(qk, G), 0);
    const Eigen::VectorXd g = hc::gravity_torques(robot, hc::forward(robot, q));
    worst = std::max(worst, (g - G.data).cwiseAbs().maxCoeff());
    largest = std::max(largest, G.data.cwiseAbs().maxCoeff());
  }
  EXPECT_GT(largest, 50.0);  // the shoulder holds the arm: torques that could disagree
  EXPECT_LT(worst, 1e-9 * largest);
  // A payload: its weight at the tool point, as a heavier last body would be.
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
  const auto poses = hc::forward(robot, q);
  hc::SerialRobot heavier = robot;
  auto& last = heavier.inertials.back();
  const Eigen::Vector3d com_tool_in_body = (poses.T_world_body.back().inverse() * poses.T_world_ee) * Eigen::Vector3d(0.0, 0.0, 0.05);
  last.com_m = (last.mass_kg * last.com_m + 5.0 * com_tool_in_body) / (last.mass_kg + 5.0);
  last.mass_kg += 5.0;
  EXPECT_LT((hc::gravity_torques(robot, poses, hc::kGravityWorld, 5.0, Eigen::Vector3d(0.0, 0.0, 0.05)) -
             hc::gravity_torques(heavier, poses))
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  EXPECT_THROW(hc::gravity_torques(hil::models::load_robot(kExamples + "kr270_like.yaml"), poses), std::invalid_argument);
}

TEST(UrdfRobot, PrismaticJointsMoveAlongTheirAxis) {
  const std::string xml = R"(<robot name="column">
    <link name="floor"/><link name="carriage"/><link name="arm"/>
    <joint name="lift" type="prismatic"><parent link="floor"/><child link="carriage"/>
      <origin xyz="0.1 0 0.5" rpy="0 0 0.3"/><axis xyz="0 0.6 0.8"/><limit lower="0" upper="1.2" effort="1" velocity="1"/></joint>
    <joint name="swing" type="continuous"><parent link="carriage"/><child link="arm"/>
      <origin xyz="0.2 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  </robot>)";
  const hc::SerialRobot r = hil::models::to_serial_robot(hf::parse_urdf_robot(xml, "column.urdf", "floor", "arm"));
  ASSERT_EQ(r.dof(), 2);
  EXPECT_EQ(r.joints[0].kind, hc::JointKind::prismatic);
  EXPECT_DOUBLE_EQ(r.joints[0].upper, 1.2);
  EXPECT_DOUBLE_EQ(r.joints[1].lower, -3.141592653589793);  // continuous: one turn either way
  Eigen::Vector2d q0(0.0, 0.0), q1(0.5, 0.0);
  const Eigen::Vector3d moved = hc::tool_pose(r, q1).translation() - hc::tool_pose(r, q0).translation();
  const Eigen::Vector3d axis_world = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0, 0.6, 0.8);
  EXPECT_LT((moved - 0.5 * axis_world).norm(), 1e-12);
  const Eigen::MatrixXd J = hc::tool_jacobian(r, q1);
  EXPECT_LT((J.col(0).head<3>() - axis_world).norm(), 1e-12);
  EXPECT_LT(J.col(0).tail<3>().norm(), 1e-15);
}

TEST(UrdfRobot, BadDescriptionsFailByName) {
  EXPECT_NE(message([] { hf::parse_urdf_robot("<robot name='x'><link", "broken.urdf", "a", "b"); }).find("broken.urdf"), std::string::npos);
  const std::string two = "<robot name='two'><link name='a'/><link name='b'/>"
                          "<joint name='j' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
                          "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>";
  const auto no_link = message([&] { hf::parse_urdf_robot(two, "two.urdf", "a", "hand"); });
  EXPECT_NE(no_link.find("no link 'hand'"), std::string::npos) << no_link;
  EXPECT_NE(no_link.find("links: a, b"), std::string::npos) << no_link;
  const auto no_limits = message([] {
    hf::parse_urdf_robot("<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
                         "<parent link='a'/><child link='b'/></joint></robot>",
                         "nolimits.urdf", "a", "b");
  });
  EXPECT_NE(no_limits.find("does not specify limits"), std::string::npos) << no_limits;
  const std::string mimic = "<robot name='m'><link name='a'/><link name='b'/><link name='c'/>"
                            "<joint name='j1' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
                            "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
                            "<joint name='j2' type='revolute'><parent link='b'/><child link='c'/><axis xyz='0 0 1'/>"
                            "<limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='j1' multiplier='2'/></joint></robot>";
  // A mimic joint whose master is outside the chain: its value could not be known.
  const auto outside = message([&] { hf::parse_urdf_robot(mimic, "mimic.urdf", "b", "c"); });
  EXPECT_NE(outside.find("joint 'j2' mimics 'j1', which is not a moving joint between 'b' and 'c'"), std::string::npos) << outside;
  // A mimic joint outside the chain (a gripper's finger) is no concern of the arm's.
  EXPECT_EQ(hf::parse_urdf_robot(mimic, "mimic.urdf", "a", "b").joints.size(), 1u);
  // Found by fuzz_urdf (ASan): TinyXML reads past the text on a broken UTF-8 sequence, so one is
  // refused first, by line, column and byte. Valid multi-byte text (a name in German) passes.
  const auto broken = message([] { hf::parse_urdf_robot("<robot name='x'>\n  <link name='ab\xdf\xdf'/></robot>", "utf8.urdf", "a", "b"); });
  EXPECT_NE(broken.find("utf8.urdf:2:17"), std::string::npos) << broken;
  EXPECT_NE(broken.find("not valid UTF-8 at byte 33 (0xDF)"), std::string::npos) << broken;
  const auto truncated = message([] { hf::parse_urdf_robot("<robot name='x\xe2\x82'/>", "cut.urdf", "a", "b"); });
  EXPECT_NE(truncated.find("not valid UTF-8 at byte 14 (0xE2)"), std::string::npos) << truncated;
  const auto valid = message([] {
    hf::parse_urdf_robot("<robot name='Gr\xc3\xbc\xc3\x9f\xe2\x82\xac'><link name='a'/></robot>", "ok.urdf", "a", "b");
  });
  EXPECT_EQ(valid.find("UTF-8"), std::string::npos) << valid;
  // Found by fuzz_urdf: an <axis> without xyz reaches KDL as (0, 0, 0).
  const auto no_axis = message([] {
    hf::parse_urdf_robot("<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='continuous'>"
                         "<parent link='a'/><child link='b'/><axis xty='1'/></joint></robot>",
                         "noaxis.urdf", "a", "b");
  });
  EXPECT_NE(no_axis.find("joint 'j' has no axis direction"), std::string::npos) << no_axis;
  // Found by fuzz_urdf in CI: a joint closing a loop made kdl_parser recurse until the stack ran out.
  const auto loop = message([] {
    hf::parse_urdf_robot("<robot name='c'><link name='r'/><link name='a'/><link name='b'/>"
                         "<joint name='j1' type='fixed'><parent link='r'/><child link='a'/></joint>"
                         "<joint name='j2' type='fixed'><parent link='a'/><child link='b'/></joint>"
                         "<joint name='j3' type='fixed'><parent link='b'/><child link='a'/></joint></robot>",
                         "loop.urdf", "r", "b");
  });
  EXPECT_NE(loop.find("loop.urdf"), std::string::npos) << loop;
  EXPECT_NE(loop.find("link 'a' is the child of both joint 'j1' and joint 'j3'"), std::string::npos) << loop;
  const auto fixed_only = message([&] {
    hf::parse_urdf_robot(
        "<robot name='f'><link name='a'/><link name='b'/><joint name='j' type='fixed'><parent link='a'/><child link='b'/></joint></robot>",
        "fixed.urdf", "a", "b");
  });
  EXPECT_NE(fixed_only.find("no moving joint"), std::string::npos) << fixed_only;
  // kdl_parser makes a floating joint fixed: hil refuses it by name instead.
  const auto floating = message([&] {
    hf::parse_urdf_robot("<robot name='f'><link name='a'/><link name='b'/><link name='c'/>"
                         "<joint name='free' type='floating'><parent link='a'/><child link='b'/></joint>"
                         "<joint name='j' type='continuous'><parent link='b'/><child link='c'/><axis xyz='0 0 1'/></joint></robot>",
                         "floating.urdf", "a", "c");
  });
  EXPECT_NE(floating.find("joint 'free' is floating"), std::string::npos) << floating;
  // In a rig: the rig's line and the URDF's complaint together; a missing file by its path.
  const auto rig = message([] {
    hf::parse_rig("format_version: 1\nname: r\nrobot:\n  urdf: nowhere.urdf\n  base_link: a\n  tip_link: b\n", "/tmp/rigs/r.yaml");
  });
  EXPECT_NE(rig.find("r.yaml:4"), std::string::npos) << rig;
  EXPECT_NE(rig.find("/tmp/rigs/nowhere.urdf"), std::string::npos) << rig;
  const auto mixed = message([] {
    hf::parse_rig("format_version: 1\nname: r\nrobot:\n  urdf: x.urdf\n  base_link: a\n  tip_link: b\n  joints: []\n", "r.yaml");
  });
  EXPECT_NE(mixed.find("joints"), std::string::npos) << mixed;
}

// Mimic joints (the palletizer's wrist pitch follows its elbow with multiplier −1). The check is
// against KDL's chain from the file, which knows nothing of mimics: the test itself sets the
// passive joint from the coupling the URDF states, so hil's reading of <mimic> is what is tested.
TEST(UrdfRobot, MimicJointsFollowTheirMasterAsTheUrdfStates) {
  const hf::RobotSpec spec = hf::read_urdf_robot(kPalletizer, "base_link", "tool0");
  ASSERT_EQ(spec.joints.size(), 5u);
  EXPECT_EQ(spec.joints[3].name, "wrist_pitch");
  EXPECT_EQ(spec.joints[3].mimic_of, "elbow");
  EXPECT_EQ(spec.joints[3].mimic_multiplier, -1.0);
  EXPECT_EQ(spec.joints[3].mimic_offset, 0.0);
  for (std::size_t i : {0u, 1u, 2u, 4u}) EXPECT_TRUE(spec.joints[i].mimic_of.empty()) << spec.joints[i].name;
  ASSERT_EQ(spec.body_links.size(), 6u);
  EXPECT_EQ(spec.body_links[4], "wrist");  // the passive joint keeps its own body
  EXPECT_DOUBLE_EQ(spec.inertials[4].mass_kg, 25.0);

  const hc::SerialRobot robot = hil::models::to_serial_robot(spec);
  ASSERT_EQ(robot.joints[3].mimic_master, 2);
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromFile(kPalletizer, tree));
  KDL::Chain chain;
  ASSERT_TRUE(tree.getChain("base_link", "tool0", chain));
  ASSERT_EQ(chain.getNrOfJoints(), 5u);
  KDL::ChainFkSolverPos_recursive fk(chain);
  auto kdl_tool = [&](const Eigen::VectorXd& q_independent) {
    KDL::JntArray qk(5);
    for (unsigned i = 0; i < 5; ++i) qk(i) = q_independent[i];
    qk(3) = -1.0 * q_independent[2];  // <mimic joint="elbow" multiplier="-1" offset="0"/>
    KDL::Frame F;
    EXPECT_GE(fk.JntToCart(qk, F), 0);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (unsigned r = 0; r < 3; ++r) {
      T.translation()[r] = F.p(r);
      for (unsigned c = 0; c < 3; ++c) T.linear()(r, c) = F.M(r, c);
    }
    return T;
  };
  std::mt19937 rng(52817);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::VectorXd q = random_q(robot, rng);
    q[3] = 99.0;  // whatever was there: the master decides
    hc::fill_mimic_joints(robot, q);
    EXPECT_DOUBLE_EQ(q[3], -q[2]);
    const Eigen::Isometry3d T = hc::tool_pose(robot, q);
    const Eigen::Isometry3d Tk = kdl_tool(q);
    EXPECT_LT((T.matrix() - Tk.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    // The parallelogram keeps the wrist at the upper arm's pitch: the flange's axis leans from the
    // vertical by the shoulder's angle, whatever the elbow does.
    EXPECT_NEAR(std::abs(T.linear()(2, 2)), std::cos(q[1]), 1e-12);
    // Moving the elbow moves the passive joint too: the tool's rate per elbow radian is the elbow's
    // column plus multiplier × the passive joint's, as KDL's finite differences say.
    const Eigen::MatrixXd J = hc::tool_jacobian(robot, q);
    const Eigen::Matrix<double, 6, 1> d_elbow = J.col(2) - J.col(3);
    constexpr double h = 1e-6;
    Eigen::VectorXd qp = q, qm = q;
    qp[2] += h, qm[2] -= h;
    const Eigen::Isometry3d Tp = kdl_tool(qp), Tm = kdl_tool(qm);
    const Eigen::Vector3d v = (Tp.translation() - Tm.translation()) / (2 * h);
    const Eigen::AngleAxisd w(Tp.linear() * Tm.linear().transpose());
    EXPECT_LT((d_elbow.head<3>() - v).norm(), 1e-7);
    EXPECT_LT((d_elbow.tail<3>() - w.angle() * w.axis() / (2 * h)).norm(), 1e-7);
  }

  // The postures hil plans for a stiffness experiment obey the coupling.
  const hc::VjmModel model(robot);
  hc::ExperimentPlan plan;
  plan.configurations = 20;
  plan.seed = 3;
  for (const auto& m : hc::simulate(model, model.zero_compliance(), plan, hc::NoiseModel{})) EXPECT_DOUBLE_EQ(m.q_rad[3], -m.q_rad[2]);

  // Model files keep the coupling.
  const hc::SerialRobot back = hil::models::robot_from_json(hil::models::robot_to_json(robot), "model.json");
  EXPECT_EQ(back.joints[3].mimic_master, 2);
  EXPECT_EQ(back.joints[3].mimic_multiplier, -1.0);
  EXPECT_EQ(back.joints[1].mimic_master, -1);
  // A hand-edited model whose mimic follows another mimic, or a joint it does not have, is refused.
  for (const std::string master : {"wrist_pitch", "gripper"}) {
    auto bad = hil::models::robot_to_json(robot);
    bad["joints"][1]["mimic"] = {{"joint", master}, {"multiplier", 1.0}, {"offset", 0.0}};
    EXPECT_NE(message([&] { hil::models::robot_from_json(bad, "model.json"); }).find("'" + master + "' is not an independent joint"),
              std::string::npos)
        << master;
  }
}

TEST(UrdfRobot, MimicsOfMimicsResolveToTheIndependentJoint) {
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child, const std::string& mimic) {
    return "<joint name='" + name + "' type='revolute'><parent link='" + parent + "'/><child link='" + child +
           "'/><origin xyz='0.5 0 0'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='1' velocity='1'/>" + mimic + "</joint>";
  };
  const std::string links = "<link name='a'/><link name='b'/><link name='c'/><link name='d'/>";
  const std::string urdf = "<robot name='m'>" + links + joint("j1", "a", "b", "") +
                           joint("j2", "b", "c", "<mimic joint='j1' multiplier='2' offset='0.1'/>") +
                           joint("j3", "c", "d", "<mimic joint='j2' multiplier='-0.5' offset='0.2'/>") + "</robot>";
  const hf::RobotSpec spec = hf::parse_urdf_robot(urdf, "chain.urdf", "a", "d");
  ASSERT_EQ(spec.joints.size(), 3u);
  EXPECT_EQ(spec.joints[2].mimic_of, "j1");
  EXPECT_DOUBLE_EQ(spec.joints[2].mimic_multiplier, -1.0);          // −0.5 × 2
  EXPECT_DOUBLE_EQ(spec.joints[2].mimic_offset, -0.5 * 0.1 + 0.2);  // −0.5 × 0.1 + 0.2
  const hc::SerialRobot robot = hil::models::to_serial_robot(spec);
  Eigen::VectorXd q(3);
  q << 0.3, 0.0, 0.0;
  hc::fill_mimic_joints(robot, q);
  EXPECT_DOUBLE_EQ(q[1], 2 * 0.3 + 0.1);
  EXPECT_DOUBLE_EQ(q[2], -0.5 * q[1] + 0.2);

  const std::string cycle = "<robot name='m'>" + links + joint("j1", "a", "b", "<mimic joint='j2'/>") +
                            joint("j2", "b", "c", "<mimic joint='j1'/>") + joint("j3", "c", "d", "") + "</robot>";
  const auto cyc = message([&] { hf::parse_urdf_robot(cycle, "cycle.urdf", "a", "d"); });
  EXPECT_NE(cyc.find("cycle"), std::string::npos) << cyc;
  const std::string ghost = "<robot name='m'>" + links + joint("j1", "a", "b", "") + joint("j2", "b", "c", "<mimic joint='jx'/>") +
                            joint("j3", "c", "d", "") + "</robot>";
  const auto gh = message([&] { hf::parse_urdf_robot(ghost, "ghost.urdf", "a", "d"); });
  EXPECT_NE(gh.find("mimics 'jx'"), std::string::npos) << gh;
  // A multiplier that is not a number: refused by urdfdom or by hil, never read as NaN.
  const std::string nan = "<robot name='m'>" + links + joint("j1", "a", "b", "") +
                          joint("j2", "b", "c", "<mimic joint='j1' multiplier='nan'/>") + joint("j3", "c", "d", "") + "</robot>";
  const auto nn = message([&] { hf::parse_urdf_robot(nan, "nan.urdf", "a", "d"); });
  EXPECT_NE(nn.find("nan.urdf"), std::string::npos) << nn;

  // A model file's mimic with a multiplier that is not finite.
  const hc::SerialRobot three = hil::models::to_serial_robot(spec);
  auto bad = hil::models::robot_to_json(three);
  bad["joints"][2]["mimic"]["multiplier"] = std::numeric_limits<double>::infinity();
  const auto inf = message([&] { hil::models::robot_from_json(bad, "model.json"); });
  EXPECT_NE(inf.find("the multiplier and offset must be numbers"), std::string::npos) << inf;

  // Limits the coupling can never satisfy: planning refuses instead of looping or leaving them.
  hc::SerialRobot stuck = three;
  stuck.joints[2].mimic_offset = 10.0;  // j3 = -q1 + 10, its limits [-3, 3]
  hc::ExperimentPlan plan;
  plan.configurations = 1;
  const hc::VjmModel model(stuck);
  try {
    hc::simulate(model, model.zero_compliance(), plan, hc::NoiseModel{});
    ADD_FAILURE() << "a plan outside the mimic joint's limits was made";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no posture within every joint's limits"), std::string::npos) << e.what();
  }
}

TEST(UrdfRobot, CalibrationRunsDeriveAMimicJointTheyDoNotLog) {
  const hf::RobotSpec spec = hf::read_urdf_robot(kPalletizer, "base_link", "tool0");
  const std::string header = "posture,base_yaw,shoulder,elbow,flange_yaw,px,py,pz\n";
  const auto run = hf::parse_calibration_run(header + "p1,0.1,0.2,-0.4,0.5,1,2,3\np2,0.2,0.3,0.6,0.1,1,2,3\n", "run.csv", spec);
  ASSERT_EQ(run.postures.size(), 2u);
  EXPECT_DOUBLE_EQ(run.postures[0].q[3], 0.4);
  EXPECT_DOUBLE_EQ(run.postures[1].q[3], -0.6);
  EXPECT_EQ(run.joint_names[3], "wrist_pitch");
  // Logged anyway (a /joint_states dump has it): the logged value is used as it is.
  const auto logged =
      hf::parse_calibration_run("posture,base_yaw,shoulder,elbow,wrist_pitch,flange_yaw,px,py,pz\np1,0.1,0.2,-0.4,0.41,0.5,1,2,3\n",
                                "logged.csv", spec);
  EXPECT_DOUBLE_EQ(logged.postures[0].q[3], 0.41);
  // The master inside its limits (−1.2 .. 0.9) but the passive joint beyond its own (−0.8 .. 1.3):
  // the error points at the master's cell and says why.
  try {
    hf::parse_calibration_run(header + "p1,0.1,0.2,0.85,0.5,1,2,3\n", "run.csv", spec);
    ADD_FAILURE() << "a derived value outside the passive joint's limits was accepted";
  } catch (const hil::error::FormatError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("run.csv:2"), std::string::npos) << m;
    EXPECT_NE(m.find("elbow"), std::string::npos) << m;
    EXPECT_NE(m.find("joint 'wrist_pitch' mimics 'elbow'"), std::string::npos) << m;
  }
}
