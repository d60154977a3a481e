#include <gtest/gtest.h>

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
