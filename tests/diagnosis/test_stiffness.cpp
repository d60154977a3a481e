// The diagnosis of a stiffness table (issue 6, "the same for a stiffness-experiment table"): a
// table simulated by the calibration module with a hidden effect; the diagnosis runs blind against
// the joint-compliance model and must name the effect, or `none` on a clean table.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/robot.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/diagnose/stiffness_family.hpp>

namespace hil::diagnose {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace hc = hil::calibration;

const hc::VjmModel& robot() {
  static const hc::VjmModel m(hc::kr270_like());
  return m;
}

/// Joint compliances like the paper's Table II, rigid links.
hc::ComplianceSet joints_only() {
  const auto& m = robot();
  auto k = m.zero_compliance();
  const double c[6] = {0.25e-6, 0.30e-6, 0.41e-6, 3.0e-6, 3.3e-6, 2.4e-6};
  for (int j = 1; j <= 6; ++j) k[static_cast<std::size_t>(m.joint_spring(j))](0, 0) = c[j - 1];
  return k;
}

/// 60 configurations x 2 loads (1 kN, 100 N m), 10 µm / 10 µrad noise.
std::vector<hc::Measurement> table(const hc::ComplianceSet& truth, std::uint64_t seed) {
  hc::ExperimentPlan plan;
  plan.configurations = 60;
  plan.loads_per_config = 2;
  plan.force_n = 1000.0;
  plan.moment_nm = 100.0;
  plan.seed = seed;
  return hc::simulate(robot(), truth, plan, {1e-5, 1e-5});
}

Diagnosis run(const std::vector<hc::Measurement>& rows) {
  const auto d = make_stiffness_data(robot(), rows);
  return diagnose([&d](const std::set<std::string>& e) { return std::make_unique<StiffnessFamily>(d, e); }, stiffness_extensions(), d.obs,
                  {});
}

/// What the diagnosis reports for `name` in the extended model (NaN if absent).
Reported reported(const Diagnosis& r, const std::string& name) {
  for (const auto& q : r.extended->full.reported)
    if (q.name == name) return q;
  return {name, "", std::nan(""), std::nan("")};
}

TEST(StiffnessTable, CleanTableIsNone) {
  const auto r = run(table(joints_only(), 11));
  EXPECT_EQ(r.cause, "none") << "gain " << r.gain_percent;
}

TEST(StiffnessTable, LinkComplianceIsNamed) {
  // The links bend as steel tubes do (the calibration module's plausible set), the joints as above.
  const auto& m = robot();
  auto k = hc::example_compliance(m, 1.0, 0.0);
  const auto j = joints_only();
  for (int s = 1; s <= 6; ++s) k[static_cast<std::size_t>(m.joint_spring(s))] = j[static_cast<std::size_t>(m.joint_spring(s))];
  const auto r = run(table(k, 12));
  EXPECT_EQ(r.cause, "link_compliance");
  EXPECT_GT(r.gain_percent, 5.0);
}

TEST(StiffnessTable, HiddenMeasurementBiasIsNamedWithinItsInterval) {
  auto rows = table(joints_only(), 13);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(0.5, 1.0);
  Eigen::Matrix<double, 6, 1> b;
  b << 2e-4 * u(rng), -1.5e-4 * u(rng), 1e-4 * u(rng), 5e-5 * u(rng), -8e-5 * u(rng), 6e-5 * u(rng);
  for (auto& row : rows) row.displacement += b;
  const auto r = run(rows);
  ASSERT_EQ(r.cause, "sensor_bias");
  EXPECT_GT(r.gain_percent, 5.0);
  const char* n[6] = {"bias_dx", "bias_dy", "bias_dz", "bias_rx", "bias_ry", "bias_rz"};
  for (int c = 0; c < 6; ++c) {
    const auto q = reported(r, n[c]);
    EXPECT_LT(std::abs(q.value - b(c)), 3 * q.std) << n[c] << " " << q.value << " ± " << q.std << " vs " << b(c);
  }
}

TEST(StiffnessTable, UnmodelledToolWeightIsNamedAsALoadOffset) {
  // The table's loads omit a 150 N tool hanging from the flange: the robot carried w + (0, 0, -150).
  auto rows = table(joints_only(), 14);
  const auto truth = joints_only();
  Eigen::Matrix<double, 6, 1> w0;
  w0 << 0, 0, -150, 0, 0, 0;
  std::mt19937 rng(14);
  std::normal_distribution<double> g(0.0, 1e-5);
  for (auto& row : rows) {
    const auto t = robot().deflection(truth, row.q_rad, row.w_world + w0);
    for (int c = 0; c < 6; ++c) row.displacement(c) = t(c) + g(rng);
  }
  const auto r = run(rows);
  ASSERT_EQ(r.cause, "load_offset");
  const auto fz = reported(r, "load_offset_fz");
  EXPECT_LT(std::abs(fz.value - w0(2)), 3 * fz.std) << fz.value << " ± " << fz.std;
}

TEST(StiffnessTable, BadInputNamesTheRow) {
  auto rows = table(joints_only(), 15);
  rows[3].displacement(2) = std::nan("");
  try {
    make_stiffness_data(robot(), rows);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("row 4"), std::string::npos) << e.what();
  }
  // A table of 3-D point displacements: the diagnosis needs the 6-D tool displacement.
  auto points = table(joints_only(), 17);
  points[2].kind = hc::MeasurementKind::point3;
  points[2].displacement.conservativeResize(3);
  try {
    make_stiffness_data(robot(), points);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("row 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("6-D tool displacement"), std::string::npos) << e.what();
  }
  // Joint values of another robot.
  auto q = table(joints_only(), 18);
  q[0].q_rad.conservativeResize(5);
  EXPECT_THAT([&] { make_stiffness_data(robot(), q); },
              ThrowsMessage<std::runtime_error>(HasSubstr(": 5 joint values for a 6-joint robot")));
  rows.resize(5);
  EXPECT_THAT([&] { make_stiffness_data(robot(), rows); },
              ThrowsMessage<std::runtime_error>(HasSubstr("too few rows to diagnose a stiffness table (5 < 10)")));
  const auto d = make_stiffness_data(robot(), table(joints_only(), 16));
  EXPECT_THAT([&] { StiffnessFamily(d, {"time_offset"}); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("'time_offset' does not apply to a stiffness table")));
}

}  // namespace
}  // namespace hil::diagnose
