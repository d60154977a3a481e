#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <hil/format/ros_frames.hpp>

using namespace hil::format;

namespace {
// Frames listed child before parent, and a robot with one named and one unnamed joint.
const std::string kRig = R"(format_version: 1
name: t
frames:
  - {name: object2, parent: force_plate, translation_m: [0, 0, 0.05]}
  - {name: force_plate, parent: world, translation_m: [0.1, 0, 0]}
  - {name: object1, parent: ee}
robot:
  name: arm
  base: {translation_m: [-0.45, 0, 0]}
  joints:
    - {a_m: 0, alpha_rad: 0, d_m: 0.1, name: shoulder}
    - {a_m: 0.3, alpha_rad: 0, d_m: 0}
)";
}  // namespace

TEST(RosFrames, ParentsComeBeforeChildrenAndTheRobotBaseIsListed) {
  const auto rig = parse_rig(kRig, "rig.yaml");
  const auto frames = static_frames(rig);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[0].child, "force_plate");
  EXPECT_EQ(frames[0].parent, "world");
  EXPECT_DOUBLE_EQ(frames[0].T_parent_child.translation_m.x(), 0.1);
  EXPECT_EQ(frames[1].child, "object1");
  EXPECT_EQ(frames[1].parent, "ee");
  EXPECT_EQ(frames[2].child, "object2");
  EXPECT_EQ(frames[2].parent, "force_plate");
  EXPECT_EQ(frames[3].child, "robot_base");
  EXPECT_DOUBLE_EQ(frames[3].T_parent_child.translation_m.x(), -0.45);
}

TEST(RosFrames, JointNamesComeFromTheRigElseFromTheColumns) {
  const auto rig = parse_rig(kRig, "rig.yaml");
  EXPECT_EQ(joint_names(rig, 3), (std::vector<std::string>{"shoulder", "j2", "j3"}));
  EXPECT_EQ(joint_names(nullptr, 2), (std::vector<std::string>{"j1", "j2"}));
}

namespace {
// What message parse_rig's FormatError gives for `text`, "" when it parses.
std::string error_of(const std::string& text) {
  try {
    parse_rig(text, "rig.yaml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(RosFrames, TheTfSectionRenamesWorldBaseAndEeOnTheTopicsOnly) {
  auto rig = parse_rig(kRig + "tf: {world: map, base: arm/base_link, ee: tool0}\n", "rig.yaml");
  EXPECT_EQ(rig.tf.world, "map");
  EXPECT_EQ(rig.tf.base, "arm/base_link");
  EXPECT_EQ(rig.tf.ee, "tool0");
  EXPECT_EQ(rig.frames[1].parent, "world") << "the rig file's own names stay";
  const auto frames = static_frames(rig);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[0].parent, "map");
  EXPECT_EQ(frames[1].parent, "tool0") << "a frame on the end effector hangs off ee's tf name";
  EXPECT_EQ(frames[2].parent, "force_plate");
  EXPECT_EQ(frames[3].parent, "map");
  EXPECT_EQ(frames[3].child, "arm/base_link");
}

TEST(RosFrames, TheMovingEdgeIsBaseToEeWithARobotAndWorldToEeWithout) {
  const auto rig = parse_rig(kRig, "rig.yaml");
  const auto m = moving_frame(&rig);
  EXPECT_EQ(m.parent, "robot_base");
  EXPECT_EQ(m.child, "ee");
  // ee at (0.2, 0.1, 0.3) in world, turned 90 degrees about z; the base is at x = -0.45 in world.
  Pose T_world_ee;
  T_world_ee.translation_m = {0.2, 0.1, 0.3};
  T_world_ee.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  const auto e = m.at(T_world_ee);
  EXPECT_EQ(e.parent, "robot_base");
  EXPECT_NEAR((e.T_parent_child.translation_m - Eigen::Vector3d(0.65, 0.1, 0.3)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(e.T_parent_child.rotation.angularDistance(T_world_ee.rotation), 0.0, 1e-15);
  // Composed with the static world -> base it gives the pose back.
  const Eigen::Isometry3d T = static_frames(rig)[3].T_parent_child.isometry() * e.T_parent_child.isometry();
  EXPECT_TRUE(T.isApprox(T_world_ee.isometry(), 1e-15));

  const auto no_robot = parse_rig("format_version: 1\nname: t\ntf: {world: odom}\n", "rig.yaml");
  const auto m2 = moving_frame(&no_robot);
  EXPECT_EQ(m2.parent, "odom");
  EXPECT_EQ(m2.child, "ee");
  EXPECT_TRUE(m2.at(T_world_ee).T_parent_child.isometry().isApprox(T_world_ee.isometry(), 1e-15));
  EXPECT_EQ(moving_frame(nullptr).parent, "world");
}

TEST(RosFrames, AUrdfRobotsBaseIsItsBaseLinkUnlessTheTfSectionSaysOtherwise) {
  const std::string dir = std::string(HIL_SOURCE_DIR) + "/examples/robots/";
  const auto rig = load_rig(dir + "palletizer_mimic.yaml");
  EXPECT_EQ(rig.tf.base, "base_link");
  EXPECT_EQ(moving_frame(&rig).parent, "base_link");
  EXPECT_EQ(static_frames(rig).back().child, "base_link");
  EXPECT_EQ(moving_frame(&rig).child, "ee") << "not the URDF's tip: robot_state_publisher owns that one";

  std::ifstream in(dir + "palletizer_mimic.yaml");
  std::ostringstream text;
  text << in.rdbuf() << "tf: {base: cell_base}\n";
  const auto renamed = parse_rig(text.str(), dir + "palletizer_renamed.yaml");  // the URDF beside it
  EXPECT_EQ(renamed.tf.base, "cell_base");
  EXPECT_EQ(moving_frame(&renamed).parent, "cell_base");
}

TEST(RosFrames, BadTfNamesAreRefusedByKeyAndLine) {
  EXPECT_NE(error_of(kRig + "tf: {world: /map}\n").find("tf.world"), std::string::npos);
  EXPECT_NE(error_of(kRig + "tf: {world: /map}\n").find("do not start with '/'"), std::string::npos);
  EXPECT_NE(error_of(kRig + "tf: {ee: 'tool 0'}\n").find("letters, digits"), std::string::npos);
  EXPECT_NE(error_of(kRig + "tf: {ee: ''}\n").find("must not be empty"), std::string::npos);
  const auto same = error_of(kRig + "tf: {base: map, world: map}\n");
  EXPECT_NE(same.find("already the tf name of"), std::string::npos) << same;
  EXPECT_NE(error_of(kRig + "tf: {frames: x}\n").find("frames"), std::string::npos);
  // A rig frame may not take a name the tree gives world, the base or ee.
  const auto clash = error_of(kRig + "tf: {ee: force_plate}\n");
  EXPECT_NE(clash.find("'force_plate' is the name of ee on /tf"), std::string::npos) << clash;
  EXPECT_NE(clash.find("rig.yaml:"), std::string::npos) << clash;
  const auto base_clash = error_of(kRig + "tf: {base: object1}\n");
  EXPECT_NE(base_clash.find("the robot base"), std::string::npos) << base_clash;
  EXPECT_EQ(error_of("format_version: 1\nname: t\nframes:\n  - {name: robot_base, parent: world}\n"), "")
      << "without a robot there is no base on /tf to clash with";
}
