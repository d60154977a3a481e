// hil::services::stiffness: what `hil stiffness predict|simulate|worker` compute, checked against
// the physics rather than against the code's own formulas: compensated joints put the deflected
// tool on the target, a simulated table reads back as what was simulated, and the worker's
// identifier from a model file estimates exactly the file's kept parameters.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include <hil/calibration/experiment.hpp>
#include <hil/format/output.hpp>
#include <hil/models/stiffness_model.hpp>
#include <hil/services/stiffness.hpp>
#include <hil/test/files.hpp>

namespace hc = hil::calibration;
namespace st = hil::services::stiffness;

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) out.push_back(cell);
  return out;
}

hc::ExperimentPlan plan_of(int configs, unsigned seed) {
  hc::ExperimentPlan p;
  p.configurations = configs;
  p.loads_per_config = 1;
  p.force_n = 2000.0;
  p.moment_nm = 200.0;
  p.seed = seed;
  return p;
}

}  // namespace

TEST(StiffnessService, CompensatedJointsPutTheDeflectedToolOnTheTarget) {
  const hc::VjmModel model(hc::kr270_like());
  const auto k = hc::example_compliance(model);
  std::ostringstream table_csv;
  st::write_simulated_table(table_csv, model, k, plan_of(5, 7), {}, "test");
  const auto table = hil::models::parse_stiffness_table(table_csv.str(), "t.csv", 6, true);
  ASSERT_EQ(table.rows.size(), 5U);

  std::ostringstream out;
  const auto failures = st::write_predictions(out, {model, k}, table, true);
  // Configuration 1 of this draw sits 1e-4 from a wrist singularity (the tool Jacobian's smallest
  // singular value): its Newton steps do not settle, and the service must say so.
  ASSERT_EQ(failures.size(), 1U);
  EXPECT_EQ(failures[0].config, table.rows[0].config);
  EXPECT_GT(failures[0].residual, st::kCompensationResidual);
  EXPECT_LT(failures[0].smallest_singular_value, 1e-3);
  std::istringstream in(out.str());
  std::string line;
  std::getline(in, line);
  const auto header = split(line);
  ASSERT_EQ(header.size(), 1U + 6U + 6U + 12U + 6U);
  EXPECT_EQ(header[13], "x");
  EXPECT_EQ(header[25], "cj1");
  for (const auto& row : table.rows) {
    ASSERT_TRUE(std::getline(in, line));
    const auto cells = split(line);
    ASSERT_EQ(cells.size(), header.size());
    Eigen::VectorXd qc(6), d(6);
    for (int j = 0; j < 6; ++j) qc[j] = std::stod(cells[static_cast<std::size_t>(25 + j)]);
    for (int i = 0; i < 6; ++i) d[i] = std::stod(cells[static_cast<std::size_t>(7 + i)]);
    // The predicted deflection is the simulated (noise-free) displacement.
    EXPECT_LT((d - row.displacement).norm(), 1e-9 + 1e-5 * row.displacement.norm());
    // Without compensation the tool would miss by the deflection (the check below is not vacuous).
    EXPECT_GT(row.displacement.head<3>().norm(), 1e-5);
    if (row.config == failures[0].config) continue;
    // The tool at the compensated joints, deflected by the load there, is where the nominal robot
    // puts it at the target joints: forward kinematics plus the deflection, not the CSV's pose.
    const Eigen::Isometry3d target = hc::tool_pose(model.robot(), row.q_rad);
    const Eigen::Isometry3d at_qc = hc::tool_pose(model.robot(), qc);
    const hc::Vector6d t = model.deflection(k, qc, row.w_world);
    const Eigen::Vector3d p_reached = at_qc.translation() + t.head<3>();
    EXPECT_LT((p_reached - target.translation()).norm(), 1e-7) << "configuration " << row.config;
    // The deflection's rotation composes on the left; the model adds it to the rotation vector
    // (first order), so the orientation matches to |δθ|^2 (δθ ~ 1 mrad here).
    const Eigen::Matrix3d R_reached = hil::so3::exp(t.tail<3>()) * at_qc.linear();
    const double angle_rad = hil::so3::log(Eigen::Matrix3d(R_reached.transpose() * target.linear())).norm();
    EXPECT_LT(angle_rad, 1e-7 + t.tail<3>().squaredNorm()) << "configuration " << row.config;
  }
}

TEST(StiffnessService, TheWorkersIdentifierFromAModelFileEstimatesItsKeptParameters) {
  const hc::VjmModel model(hc::kr270_like());
  const auto rows = hc::simulate(model, hc::example_compliance(model), plan_of(40, 3), {1e-5, 1e-5});
  hc::PipelineOptions opt;
  const auto r = hc::calibrate(model, rows, {1e-5, 1e-5}, opt);
  ASSERT_FALSE(r.kept.empty());
  hil::test::TempDir dir;
  const auto path = dir.file("model.json", hil::models::result_to_json(model, r).dump());
  const auto id = st::make_online_identifier(model, path, {1e-5, 1e-5}, opt);
  const auto& params = id->parameters();
  ASSERT_EQ(params.size(), r.kept.size() + r.fixed.size());
  for (std::size_t i = 0; i < r.kept.size(); ++i) EXPECT_EQ(params[i].name, r.kept[i].parameter.name);
  for (const auto& m : rows) id->add(m);
  const auto e = id->estimate();
  ASSERT_EQ(e.kept.size(), r.kept.size());
  // The same data through the same reduced model: the online QR gives the batch values.
  for (std::size_t i = 0; i < r.kept.size(); ++i)
    EXPECT_NEAR(e.kept[i].value, r.kept[i].value, 1e-6 * std::abs(r.kept[i].value) + 1e-12) << r.kept[i].parameter.name;
}

TEST(StiffnessService, AModelFileOfAnotherKindIsRefusedNamingIt) {
  const hc::VjmModel model(hc::kr270_like());
  hil::test::TempDir dir;
  const auto path = dir.file("diag.json", R"({"format": "hil.diagnosis", "format_version": 1})");
  EXPECT_TRUE(hil::test::fails_with(
      [&] {
        st::make_online_identifier(model, path, {1e-5, 1e-5}, {});
      },
      0, "format", "this is a 'hil.diagnosis' file, not a stiffness model"));
}
