// The hidden-effect test: a link compliance (upper-arm torsion and bending) that a joint-only model
// cannot explain is recovered by the reduced complete model, whose held-out prediction error falls
// below the measurement noise.
#include <gtest/gtest.h>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/reduction.hpp>

namespace hc = hil::calibration;

TEST(HiddenEffect, ReducedCompleteModelExplainsWhatJointsCannot) {
  const hc::VjmModel m(hc::kr270_like());
  // Truth: Table II-like joints, rigid links except the upper arm (L2), which twists and bends.
  hc::ComplianceSet truth = hc::example_compliance(m);
  for (int l = 0; l <= 6; ++l) truth[static_cast<std::size_t>(m.link_spring(l))].setZero();
  truth[static_cast<std::size_t>(m.link_spring(2))] = hc::beam_compliance(1.15, 2e9, 1.5e7, 1.2e7, 4e6);
  const hc::NoiseModel noise{10e-6, 10e-6};
  hc::ExperimentPlan plan;
  plan.configurations = 60;
  plan.loads_per_config = 2;
  plan.moment_nm = 200.0;
  plan.seed = 42;
  const auto train = hc::simulate(m, truth, plan, noise);
  plan.seed = 43;
  plan.configurations = 30;
  const auto held_out = hc::simulate(m, truth, plan, {});  // noise-free truth to compare against

  hc::ParameterSet joints;
  for (int j = 1; j <= 6; ++j) joints.push_back({m.joint_spring(j), 0, 0, false, "J" + std::to_string(j) + ".k"});
  const auto joint_only = hc::identify_fixed_set(m, joints, train, noise);
  const auto reduced = hc::calibrate(m, train, noise);

  auto held_out_rms = [&](const hc::ComplianceSet& k) {
    double ss = 0.0;
    Eigen::Index n = 0;
    for (const auto& d : held_out) {
      const Eigen::VectorXd e = hc::predict(m, k, d) - d.displacement;
      ss += e.head<3>().squaredNorm();
      n += 3;
    }
    return std::sqrt(ss / static_cast<double>(n));
  };
  const double rms_joint = held_out_rms(joint_only.compliance);
  const double rms_reduced = held_out_rms(reduced.compliance);
  // The joint-only model leaves residuals well above the noise ...
  EXPECT_GT(joint_only.residual_rms[0], 3.0 * noise.position_m);
  EXPECT_GT(joint_only.solution.sigma0_sq, 9.0);
  EXPECT_GT(rms_joint, 3.0 * noise.position_m);
  // ... the reduced complete model fits to the noise and predicts new configurations better than it.
  for (int a = 0; a < 6; ++a) EXPECT_LT(reduced.residual_rms[static_cast<std::size_t>(a)], 1.3 * noise.position_m) << a;
  EXPECT_NEAR(reduced.solution.sigma0_sq, 1.0, 0.2);
  EXPECT_LT(rms_reduced, noise.position_m);
  EXPECT_TRUE(reduced.solution.full_rank);
  EXPECT_EQ(static_cast<int>(reduced.kept.size()), reduced.rank_final);
}
