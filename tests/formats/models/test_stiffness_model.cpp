// The `hil stiffness` I/O: rig adapter, stiffness-experiment table (strict, with locations),
// model/truth files and the JSON report keys the issue asks for.
#include <gtest/gtest.h>

#include <sstream>

#include <hil/test/files.hpp>
#include <hil/test/eigen.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/format/rig.hpp>
#include <hil/models/stiffness_model.hpp>
#include <hil/models/stiffness.hpp>

namespace hc = hil::calibration;
namespace io = hil::models;
using hil::test::fails_with;

namespace {
const char* kHeader = "config,j1,j2,j3,j4,j5,j6,fx,fy,fz,mx,my,mz";
}

TEST(StiffnessIo, ExampleRigAdaptsToTheReferenceRobot) {
  const auto robot = io::load_robot(std::string(HIL_SOURCE_DIR) + "/examples/stiffness/kr270_like.yaml");
  const auto ref = hc::kr270_like();
  ASSERT_EQ(robot.dof(), 6);
  const Eigen::VectorXd q = (Eigen::VectorXd(6) << 0.1, -1.0, 0.7, 0.3, -0.4, 1.1).finished();
  EXPECT_TRUE(hil::test::near(hc::tool_pose(robot, q).matrix(), hc::tool_pose(ref, q).matrix(), 1e-12));
  EXPECT_DOUBLE_EQ(robot.joints[1].lower, -2.44);
}

TEST(StiffnessIo, RigWithoutRobotIsRefused) {
  hil::test::TempDir dir;
  const auto rig = dir.file("rig.yaml", "format_version: 1\nname: empty\n");
  EXPECT_TRUE(fails_with([&] { io::load_robot(rig); }, 0, "robot", "no robot"));
}

TEST(StiffnessIo, TableKindsAndRoundTrip) {
  const hc::VjmModel m(hc::kr270_like());
  for (auto kind : {hc::MeasurementKind::pose6, hc::MeasurementKind::point3, hc::MeasurementKind::markers}) {
    hc::ExperimentPlan plan;
    plan.configurations = 4;
    plan.loads_per_config = 2;
    plan.kind = kind;
    plan.p_ee_marker_m = {{0.1, 0.0, 0.0}, {0.0, 0.1, 0.05}};
    const auto rows = hc::simulate(m, hc::example_compliance(m), plan, {1e-5, 1e-5});
    std::ostringstream os;
    io::write_stiffness_table(os, rows, 6);
    const auto t = io::parse_stiffness_table(os.str(), "t.csv", 6, true);
    ASSERT_EQ(t.rows.size(), rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(t.rows[i].kind, kind);
      EXPECT_EQ(t.rows[i].config, rows[i].config);
      EXPECT_TRUE(hil::test::near(t.rows[i].displacement, rows[i].displacement, 0.0));
      EXPECT_TRUE(hil::test::near(t.rows[i].q_rad, rows[i].q_rad, 0.0));
      EXPECT_TRUE(hil::test::near(t.rows[i].w_world, rows[i].w_world, 0.0));
    }
  }
}

TEST(StiffnessIo, BadTablesNameLineAndColumn) {
  const std::string h = kHeader;
  EXPECT_TRUE(fails_with(
      [&] {
        io::parse_stiffness_table("config,j1,j2,j3,j4,j5,fx,fy,fz,mx,my,mz,dx,dy,dz\n1,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n", "t.csv", 6, true);
      },
      1, "j6", "missing joint column"));
  EXPECT_TRUE(fails_with([&] { io::parse_stiffness_table(h + ",dx,dy,dz\n1.5,0,0,0,0,0,0,1,2,3,0,0,0,0,0,0\n", "t.csv", 6, true); }, 2,
                         "config", "integer"));
  EXPECT_TRUE(fails_with([&] { io::parse_stiffness_table(h + ",dx,dy,dz,rx\n1,0,0,0,0,0,0,1,2,3,0,0,0,0,0,0,0\n", "t.csv", 6, true); }, 1,
                         "ry", "together"));
  EXPECT_TRUE(fails_with([&] { io::parse_stiffness_table(h + "\n1,0,0,0,0,0,0,1,2,3,0,0,0\n", "t.csv", 6, true); }, 1, "dx",
                         "no measured"));
  EXPECT_TRUE(fails_with([&] { io::parse_stiffness_table(h + ",m1_dx,m1_dy,m1_dz\n1,0,0,0,0,0,0,1,2,3,0,0,0,0,0,0\n", "t.csv", 6, true); },
                         1, "m1_px", "position columns"));
  EXPECT_TRUE(fails_with([&] { io::parse_stiffness_table(h + ",dx,dy,dz\n1,0,0,0,0,0,0,1,2,nan,0,0,0,0,0,0\n", "t.csv", 6, true); }, 2, "",
                         ""));
  // Predict reads the same table without the measured columns.
  EXPECT_EQ(io::parse_stiffness_table(h + "\n1,0,0,0,0,0,0,1,2,3,0,0,0\n", "t.csv", 6, false).rows.size(), 1u);
}

TEST(StiffnessIo, SpringsInEveryFormAndTheirErrors) {
  const hc::VjmModel m(hc::kr270_like());
  const auto j = nlohmann::json::parse(R"({"J2": 3e-7,
      "L2": {"beam": {"length_m": 1.15, "EA_n": 2e9, "EIy_nm2": 1.5e7, "EIz_nm2": 1.2e7, "GJ_nm2": 4e6}},
      "L0": {"diagonal": [1, 2, 3, 4, 5, 6], "k26": 0.5}})");
  const auto k = io::read_springs(j, m, "truth.json");
  EXPECT_DOUBLE_EQ(k[static_cast<std::size_t>(m.joint_spring(2))](0, 0), 3e-7);
  EXPECT_TRUE(hil::test::near(k[static_cast<std::size_t>(m.link_spring(2))], hc::beam_compliance(1.15, 2e9, 1.5e7, 1.2e7, 4e6), 0.0));
  EXPECT_DOUBLE_EQ(k[0](5, 1), 0.5);
  EXPECT_DOUBLE_EQ(k[0](3, 3), 4.0);
  // Round trip through the full-matrix form.
  const auto back = io::read_springs(io::springs_to_json(m, k), m, "model.json");
  for (std::size_t s = 0; s < k.size(); ++s) EXPECT_TRUE(hil::test::near(back[s], k[s], 0.0));
  EXPECT_TRUE(fails_with([&] { io::read_springs(nlohmann::json::parse(R"({"L9": 1})"), m, "t.json"); }, 0, "springs.L9", "unknown spring"));
  EXPECT_TRUE(fails_with([&] { io::read_springs(nlohmann::json::parse(R"({"L1": {"k77": 1}})"), m, "t.json"); }, 0, "springs.L1.k77",
                         "unknown key"));
  EXPECT_TRUE(fails_with([&] { io::read_springs(nlohmann::json::parse(R"({"L1": {"beam": {"length_m": 1}}})"), m, "t.json"); }, 0,
                         "springs.L1.beam.EA_n", "missing"));
}

TEST(StiffnessIo, JsonReportHasTheIssueKeysAndIsAModel) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 30;
  plan.moment_nm = 200.0;
  const auto data = hc::simulate(m, hc::example_compliance(m), plan, {1e-5, 1e-5});
  const auto r = hc::calibrate(m, data, {1e-5, 1e-5});
  const auto j = io::result_to_json(m, r);
  ASSERT_TRUE(j.at("parameters").is_array());
  EXPECT_EQ(j.at("parameters").size(), r.kept.size());
  for (const char* key : {"name", "value", "std", "pnr", "class"}) EXPECT_TRUE(j.at("parameters")[0].contains(key)) << key;
  ASSERT_TRUE(j.at("reduction").is_array());
  EXPECT_EQ(j.at("reduction")[0].at("step"), "complete");
  EXPECT_EQ(j.at("reduction")[0].at("count"), 258);
  EXPECT_EQ(j.at("rank").get<int>(), r.rank_final);
  EXPECT_TRUE(j.at("residual_rms").contains("dx"));
  EXPECT_TRUE(j.at("residual_rms").contains("rz"));
  // The same file is a model: robot and springs read back give the same predictions.
  const auto robot = io::robot_from_json(j.at("robot"), "model.json");
  const hc::VjmModel m2(robot);
  const auto k = io::read_springs(j.at("springs"), m2, "model.json");
  for (const auto& d : data) EXPECT_TRUE(hil::test::near(hc::predict(m2, k, d), hc::predict(m, r.compliance, d), 1e-15, 1e-12));
}
