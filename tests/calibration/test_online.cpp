// The online identifier: Givens updates give the batch answer after every configuration.
#include <gtest/gtest.h>

#include <hil/test/eigen.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/calibration/online.hpp>

namespace hc = hil::calibration;

TEST(Online, UpdatesMatchTheBatchSolutionAfterEveryConfiguration) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 25;
  plan.moment_nm = 200.0;
  plan.seed = 12;
  const hc::NoiseModel noise{10e-6, 10e-6};
  const auto data = hc::simulate(m, hc::example_compliance(m), plan, noise);
  hc::ParameterSet free;
  for (int j = 1; j <= 6; ++j) free.push_back({m.joint_spring(j), 0, 0, false, "J" + std::to_string(j) + ".k"});
  hc::ParameterSet fixed = {{m.link_spring(2), 3, 3, false, "L2.k44"}};
  Eigen::VectorXd fixed_values(1);
  fixed_values << 2e-8;
  hc::OnlineIdentifier online(m, free, fixed, fixed_values, noise);
  hc::ParameterSet all = free;
  all.push_back(fixed[0]);
  for (std::size_t i = 0; i < data.size(); ++i) {
    online.add(data[i]);
    if (i + 1 < 3 && i + 1 != data.size()) continue;
    const std::vector<hc::Measurement> so_far(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(i) + 1);
    const auto sys = hc::build_system(m, all, so_far, noise);
    const auto c = hc::compress(sys.A_w, sys.t_w);
    const auto batch = hc::solve(c, {0, 1, 2, 3, 4, 5}, {6}, fixed_values);
    const auto est = online.estimate();
    ASSERT_EQ(est.kept.size(), 6u);
    EXPECT_EQ(est.rank, batch.rank);
    EXPECT_EQ(est.measurements, i + 1);
    for (std::size_t k = 0; k < 6; ++k) {
      EXPECT_NEAR(est.kept[k].value, batch.value[static_cast<Eigen::Index>(k)], 1e-9 * std::abs(batch.value[static_cast<Eigen::Index>(k)]));
      EXPECT_NEAR(est.kept[k].std_dev, batch.std_dev[static_cast<Eigen::Index>(k)], 1e-6 * batch.std_dev[static_cast<Eigen::Index>(k)]);
    }
    // Residual RMS per axis, from the per-axis compressed systems, against the direct residuals.
    Eigen::VectorXd all_values(7);
    all_values << batch.value, fixed_values;
    const Eigen::VectorXd r = (sys.t_w - sys.A_w * all_values).cwiseProduct(sys.sigma);
    for (int a = 0; a < 6; ++a) {
      double ss = 0.0;
      int n = 0;
      for (Eigen::Index row = 0; row < r.size(); ++row)
        if (sys.axis[static_cast<std::size_t>(row)] == a) {
          ss += r[row] * r[row];
          ++n;
        }
      EXPECT_NEAR(est.residual_rms[static_cast<std::size_t>(a)], std::sqrt(ss / n), 1e-9 * std::sqrt(ss / n)) << a;
    }
  }
}

TEST(Online, ReducingWorkerReachesTheBatchPipelineModel) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 30;
  plan.moment_nm = 200.0;
  plan.seed = 13;
  const hc::NoiseModel noise{10e-6, 10e-6};
  const auto data = hc::simulate(m, hc::example_compliance(m), plan, noise);
  hc::PipelineOptions opt;
  std::vector<hc::ReductionLine> lines;
  const auto physical = hc::physical_reduction(m, opt, lines);
  hc::OnlineIdentifier online(m, physical, {}, Eigen::VectorXd(), noise, opt, true);
  for (const auto& d : data) online.add(d);
  const auto est = online.estimate();
  const auto batch = hc::calibrate(m, data, noise, opt);
  EXPECT_EQ(est.rank, batch.rank_final);
  ASSERT_EQ(est.kept.size(), batch.kept.size());
  for (std::size_t k = 0; k < est.kept.size(); ++k) {
    EXPECT_EQ(est.kept[k].parameter.name, batch.kept[k].parameter.name);
    EXPECT_NEAR(est.kept[k].value, batch.kept[k].value, 1e-6 * std::abs(batch.kept[k].value) + 1e-3 * batch.kept[k].std_dev);
  }
}
