// Model reduction M1-M6: counts of Table I, groups on cases with a known answer, completeness of
// the reduced model, M6 neglecting.
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include <hil/test/eigen.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/calibration/reduction.hpp>

#include "kr270_experiment.hpp"

namespace hc = hil::calibration;

namespace {

std::vector<int> cols_of(std::size_t n) {
  std::vector<int> c(n);
  std::iota(c.begin(), c.end(), 0);
  return c;
}

/// Columns with a known structure: c0 alone (G1), c1 = c2 (one coupled pair), c3 = 0 (G2),
/// c4 = c5 + c6 (a group of three of rank 2), c7 alone (G1).
hc::CompressedSystem known_case() {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(12, 8);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd B(12, 5);
  for (auto& v : B.reshaped()) v = g(rng);
  A.col(0) = B.col(0);
  A.col(1) = B.col(1);
  A.col(2) = 3.0 * B.col(1);
  A.col(5) = B.col(2);
  A.col(6) = 1e-3 * B.col(3);  // a small column: scaling must not hide it
  A.col(4) = A.col(5) + A.col(6);
  A.col(7) = B.col(4);
  return hc::compress(A, Eigen::VectorXd::Zero(12));
}

}  // namespace

TEST(Reduction, PhysicalStepsCountLikeTableI) {
  const hc::VjmModel m(hc::kr270_like());
  const auto complete = hc::complete_parameters(m);
  const auto m1 = hc::m1_symmetrise(complete);
  const auto m2 = hc::m2_sparsify(m, m1);
  const auto m3 = hc::m3_aggregate(m, m2);
  EXPECT_EQ(complete.size(), 258u);
  EXPECT_EQ(m1.size(), 153u);
  EXPECT_EQ(m2.size(), 62u);
  EXPECT_EQ(m3.size(), 56u);
  EXPECT_EQ(hc::find_parameter(m1, "L2.k62"), -1);
  EXPECT_GE(hc::find_parameter(m1, "L2.k26"), 0);
  EXPECT_GE(hc::find_parameter(m2, "L2.k35"), 0);
  EXPECT_EQ(hc::find_parameter(m2, "L2.k23"), -1);
  EXPECT_EQ(hc::find_parameter(m3, "J3.k"), -1);
  // A user template (full matrix) for link 6 keeps its 21 symmetric entries.
  const auto m2u = hc::m2_sparsify(m, m1, {{6, hc::full_template()}});
  EXPECT_EQ(m2u.size(), 62u + 13u);
  // A rigid link (no parameter) does not absorb its next joint.
  hc::ParameterSet no_l1;
  for (const auto& p : m2)
    if (m.springs()[static_cast<std::size_t>(p.spring)].name != "L1") no_l1.push_back(p);
  const auto m3b = hc::m3_aggregate(m, no_l1);
  EXPECT_GE(hc::find_parameter(m3b, "J2.k"), 0);
  EXPECT_EQ(m3b.size(), 49u);
}

TEST(Reduction, M4PartitionAndM5GroupsOnAKnownCase) {
  const auto c = known_case();
  const auto part = hc::m4a_partition(c, cols_of(8));
  EXPECT_EQ(part.rank, 5);
  EXPECT_EQ(part.g1, (std::vector<int>{0, 7}));
  EXPECT_EQ(part.g2, (std::vector<int>{3}));
  EXPECT_EQ(part.g3, (std::vector<int>{1, 2, 4, 5, 6}));
  EXPECT_EQ(hc::m4b_eliminate(cols_of(8), part), (std::vector<int>{0, 1, 2, 4, 5, 6, 7}));
  const auto split = hc::m5a_split(c, part.g3);
  EXPECT_EQ(split.rank, 3);
  ASSERT_EQ(split.groups.size(), 2u);
  EXPECT_EQ(split.groups[0].cols, (std::vector<int>{1, 2}));
  EXPECT_EQ(split.groups[0].rank, 1);
  EXPECT_EQ(split.groups[1].cols, (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(split.groups[1].rank, 2);
  // L restricted to each group's columns is identity on the chosen pivots: rows sum to the rank.
  EXPECT_EQ(split.L.rows(), 3);
  // Priorities decide which parameters are kept.
  std::vector<double> prio(8, 1.0);
  auto sel = hc::m5bc_select(c, split, prio);
  EXPECT_EQ(sel.identifiable, (std::vector<int>{1, 4, 5}));
  EXPECT_EQ(sel.fixed, (std::vector<int>{2, 6}));
  prio[2] = 5.0;
  prio[6] = 5.0;
  sel = hc::m5bc_select(c, split, prio);
  EXPECT_EQ(sel.identifiable, (std::vector<int>{2, 4, 6}));
  EXPECT_EQ(sel.fixed, (std::vector<int>{1, 5}));
}

TEST(Reduction, M3LosesNothingAndTheFinalModelIsCompleteAndIrreducible) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ExperimentPlan plan;
  plan.configurations = 40;
  plan.loads_per_config = 2;
  plan.moment_nm = 300.0;
  plan.seed = 3;
  const hc::ComplianceSet truth = hc::example_compliance(m);
  const auto clean = hc::simulate(m, truth, plan, {});
  hc::PipelineOptions opt;
  opt.neglect_below = 0.0;  // M6 off: check the algebraic model
  const auto r = hc::calibrate(m, clean, {1e-5, 1e-5}, opt);
  // M3 keeps the rank of the M2 set.
  const auto& lines = r.reduction;
  ASSERT_GE(lines.size(), 7u);
  EXPECT_EQ(lines[2].step, "M2");
  EXPECT_EQ(lines[3].step, "M3");
  EXPECT_EQ(lines[2].rank, lines[3].rank);
  // rank(A_reduced) = rank(A_physical) = dim(π_reduced)
  EXPECT_EQ(r.rank_algebraic, r.rank_physical);
  EXPECT_EQ(static_cast<int>(r.kept.size()), r.rank_physical);
  EXPECT_TRUE(r.solution.full_rank);
  EXPECT_EQ(r.partition.g1.size() + r.partition.g2.size() + r.partition.g3.size(), 56u);
  // Complete: noise-free data of the full VJM truth (joints and links) is fitted exactly.
  for (int a = 0; a < 6; ++a) EXPECT_LT(r.residual_rms[static_cast<std::size_t>(a)], 1e-12) << a;
  // And the identified compliance predicts new configurations like the truth.
  plan.seed = 4;
  plan.configurations = 10;
  for (const auto& d : hc::simulate(m, truth, plan, {}))
    EXPECT_TRUE(hil::test::near(hc::predict(m, r.compliance, d), d.displacement, 1e-12, 1e-7));
}

TEST(Reduction, M6NeglectsAParameterThatIsZero) {
  const hc::VjmModel m(hc::kr270_like());
  hc::ComplianceSet truth = hc::example_compliance(m);
  for (int l = 0; l <= 6; ++l) truth[static_cast<std::size_t>(m.link_spring(l))].setZero();
  truth[static_cast<std::size_t>(m.joint_spring(6))](0, 0) = 0.0;  // J6 rigid
  hc::ParameterSet set;
  for (int j = 1; j <= 6; ++j) set.push_back({m.joint_spring(j), 0, 0, false, "J" + std::to_string(j) + ".k"});
  hc::ExperimentPlan plan;
  plan.configurations = 30;
  plan.moment_nm = 100.0;
  plan.seed = 8;
  const hc::NoiseModel noise{20e-6, 20e-6};
  const auto data = hc::simulate(m, truth, plan, noise);
  const auto sys = hc::build_system(m, set, data, noise);
  const auto c = hc::compress(sys.A_w, sys.t_w);
  hc::PipelineOptions opt;
  const auto a = hc::reduce_algebraic(m, c, set, cols_of(6), opt);
  EXPECT_EQ(a.partition.g1.size(), 6u);
  ASSERT_EQ(a.fixed_cols.size(), 1u);
  EXPECT_EQ(a.fixed_cols[0], 5);
  EXPECT_EQ(a.fixed_steps[0], "M6");
  EXPECT_EQ(a.free_cols, (std::vector<int>{0, 1, 2, 3, 4}));
  for (Eigen::Index i = 0; i < 5; ++i) EXPECT_GT(std::abs(a.solution.value[i]) / a.solution.std_dev[i], 5.0);
  // With M6 off the zero stays, with a ratio below 2.
  opt.neglect_below = 0.0;
  const auto b = hc::reduce_algebraic(m, c, set, cols_of(6), opt);
  EXPECT_EQ(b.free_cols.size(), 6u);
  EXPECT_LT(std::abs(b.solution.value[5]) / b.solution.std_dev[5], 2.0);
}

namespace {

/// The compressed system of the physical set for the first `configs` configurations of a stream.
hc::CompressedSystem physical_system(const hc::VjmModel& m, const hc::ParameterSet& physical, const std::vector<hc::Measurement>& data,
                                     std::size_t configs, const hc::NoiseModel& noise) {
  const std::vector<hc::Measurement> first(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(configs));
  const auto sys = hc::build_system(m, physical, first, noise);
  return hc::compress(sys.A_w, sys.t_w);
}

void expect_same_reduction(const hc::AlgebraicResult& a, const hc::AlgebraicResult& b) {
  EXPECT_EQ(a.partition.g1, b.partition.g1);
  EXPECT_EQ(a.partition.g2, b.partition.g2);
  EXPECT_EQ(a.partition.g3, b.partition.g3);
  EXPECT_EQ(a.partition.rank, b.partition.rank);
  ASSERT_EQ(a.splitting.groups.size(), b.splitting.groups.size());
  for (std::size_t g = 0; g < a.splitting.groups.size(); ++g) {
    EXPECT_EQ(a.splitting.groups[g].cols, b.splitting.groups[g].cols);
    EXPECT_EQ(a.splitting.groups[g].rank, b.splitting.groups[g].rank);
  }
  EXPECT_EQ(a.rank_algebraic, b.rank_algebraic);
  EXPECT_EQ(a.free_cols, b.free_cols);
  EXPECT_EQ(a.fixed_cols, b.fixed_cols);
  EXPECT_EQ(a.fixed_steps, b.fixed_steps);
  EXPECT_EQ(a.fixed_values, b.fixed_values);
  ASSERT_EQ(a.solution.value.size(), b.solution.value.size());
  for (Eigen::Index k = 0; k < a.solution.value.size(); ++k) {
    EXPECT_NEAR(a.solution.value[k], b.solution.value[k], 1e-9 * std::abs(b.solution.value[k]));
    EXPECT_NEAR(a.solution.std_dev[k], b.solution.std_dev[k], 1e-9 * b.solution.std_dev[k]);
  }
}

}  // namespace

// Issue 29: a cached reduction is confirmed on a system with more rows of the same structure (and
// then gives reduce_algebraic's answer), and refused when the structure changed or was tampered with.
TEST(Reduction, ReverifyConfirmsAnUnchangedStructureAndRefusesAChangedOne) {
  const auto e = hil::test::kr270_experiment(40, 300.0, 29);
  const auto& [m, noise, opt, data, physical] = e;
  const auto cols = cols_of(physical.size());

  const auto c30 = physical_system(m, physical, data, 30, noise);
  const auto c40 = physical_system(m, physical, data, 40, noise);
  const auto a30 = hc::reduce_algebraic(m, c30, physical, cols, opt);
  const auto a40 = hc::reduce_algebraic(m, c40, physical, cols, opt);
  hc::AlgebraicResult v;
  // Its own system: confirmed, identical.
  ASSERT_TRUE(hc::reverify_algebraic(m, c30, physical, cols, opt, a30, v));
  expect_same_reduction(v, a30);
  // Ten more configurations, same M4/M5 structure: confirmed, and equal to the full run on them.
  ASSERT_EQ(a30.partition.g1, a40.partition.g1);
  ASSERT_TRUE(hc::reverify_algebraic(m, c40, physical, cols, opt, a30, v));
  expect_same_reduction(v, a40);

  // Two configurations: a lower rank, the cached structure must be refused.
  const auto c2 = physical_system(m, physical, data, 2, noise);
  EXPECT_LT(hc::reduce_algebraic(m, c2, physical, cols, opt).partition.rank, a30.partition.rank);
  EXPECT_FALSE(hc::reverify_algebraic(m, c2, physical, cols, opt, a30, v));
  // ...and the other way: a structure of few configurations on the full data (more is identifiable).
  EXPECT_FALSE(hc::reverify_algebraic(m, c40, physical, cols, opt, hc::reduce_algebraic(m, c2, physical, cols, opt), v));

  // Tampered caches. (1) A kept G3 column swapped with an M5c one such that the kept columns still
  // form a basis: the rank and partition checks pass, only the replayed M5b choice can refuse it.
  ASSERT_FALSE(a30.splitting.groups.empty());
  hc::AlgebraicResult t = a30;
  std::vector<int> free_alg = a30.free_cols;
  for (std::size_t i = 0; i < a30.fixed_cols.size(); ++i)
    if (a30.fixed_steps[i] == "M6") free_alg.push_back(a30.fixed_cols[i]);
  bool swapped = false;
  for (std::size_t f = 0; f < a30.fixed_cols.size() && !swapped; ++f) {
    if (a30.fixed_steps[f] != "M5c") continue;
    for (int k : a30.free_cols) {
      if (std::find(a30.partition.g1.begin(), a30.partition.g1.end(), k) != a30.partition.g1.end()) continue;
      std::vector<int> basis = free_alg;
      std::replace(basis.begin(), basis.end(), k, a30.fixed_cols[f]);
      if (hc::rank_of(c30, basis, opt.algebraic.rank) != static_cast<int>(basis.size())) continue;
      std::replace(t.free_cols.begin(), t.free_cols.end(), k, a30.fixed_cols[f]);
      std::sort(t.free_cols.begin(), t.free_cols.end());
      t.fixed_cols[f] = k;
      swapped = true;
      break;
    }
  }
  ASSERT_TRUE(swapped);
  EXPECT_FALSE(hc::reverify_algebraic(m, c30, physical, cols, opt, t, v));
  // (2) A G1 column moved to G3.
  ASSERT_FALSE(a30.partition.g1.empty());
  t = a30;
  t.partition.g3.push_back(t.partition.g1.back());
  t.partition.g1.pop_back();
  std::sort(t.partition.g3.begin(), t.partition.g3.end());
  EXPECT_FALSE(hc::reverify_algebraic(m, c30, physical, cols, opt, t, v));
}
