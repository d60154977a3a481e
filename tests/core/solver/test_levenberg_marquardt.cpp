#include <hil/solver/levenberg_marquardt.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

namespace hs = hil::solver;

namespace {

/// A problem from a residual function, its Jacobian by forward differences.
hs::Problem make(std::function<Eigen::VectorXd(const Eigen::VectorXd&)> res, int* jacobians = nullptr) {
  hs::Problem p;
  p.residual = [res](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    r = res(x);
    return r.squaredNorm();
  };
  p.jacobian = [res, jacobians](const Eigen::VectorXd& x, const Eigen::VectorXd& r, Eigen::MatrixXd& J) {
    if (jacobians) ++*jacobians;
    J.resize(r.size(), x.size());
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      Eigen::VectorXd xh = x;
      const double h = 1e-7 * std::max(1.0, std::abs(x(j)));
      xh(j) += h;
      J.col(j) = (res(xh) - r) / h;
    }
  };
  return p;
}

Eigen::VectorXd rosenbrock(const Eigen::VectorXd& x) { return Eigen::Vector2d(10.0 * (x(1) - x(0) * x(0)), 1.0 - x(0)); }

hs::Options tight() {
  hs::Options o;
  o.max_iterations = 500;
  o.relative_decrease = 1e-14;
  o.step_absolute = 1e-12;
  return o;
}

}  // namespace

TEST(LevenbergMarquardt, Rosenbrock) {
  for (auto damping : {hs::Damping::gain_ratio, hs::Damping::fixed_factors}) {
    auto o = tight();
    o.damping = damping;
    const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
    EXPECT_TRUE(r.converged);
    EXPECT_NEAR(r.x(0), 1.0, 1e-6);
    EXPECT_NEAR(r.x(1), 1.0, 1e-6);
    EXPECT_LT(r.cost, 1e-12);
  }
}

TEST(LevenbergMarquardt, BoundActiveAtTheOptimum) {
  // min (x0 - 3)² + (x1 + 1)² with x0 ≤ 2, x1 ≥ 0: the optimum (2, 0) lies on both bounds.
  auto p = make([](const Eigen::VectorXd& x) { return Eigen::Vector2d(x(0) - 3.0, x(1) + 1.0); });
  p.lower = Eigen::Vector2d(-10.0, 0.0);
  p.upper = Eigen::Vector2d(2.0, 10.0);
  const auto r = hs::levenberg_marquardt(p, Eigen::Vector2d(0.0, 5.0), tight());
  EXPECT_DOUBLE_EQ(r.x(0), 2.0);
  EXPECT_DOUBLE_EQ(r.x(1), 0.0);
  EXPECT_NEAR(r.cost, 2.0, 1e-12);
}

TEST(LevenbergMarquardt, FixedParameterStaysAndOthersFitAroundIt) {
  // r = (x0 + x1 - 4, x0 - x1): free optimum (2, 2); x1 fixed at 1: min (x0 - 3)² + (x0 - 1)², x0 = 2.
  auto p = make([](const Eigen::VectorXd& x) { return Eigen::Vector2d(x(0) + x(1) - 4.0, x(0) - x(1)); });
  p.fixed = {false, true};
  const auto r = hs::levenberg_marquardt(p, Eigen::Vector2d(0.0, 1.0), tight());
  EXPECT_EQ(r.x(1), 1.0);
  EXPECT_NEAR(r.x(0), 2.0, 1e-6);
  EXPECT_NEAR(r.cost, 2.0, 1e-10);
}

TEST(LevenbergMarquardt, ScaledUnits) {
  // x1 in units 1e-3: the step and the bounds are in x, the Jacobian in u = x / scale.
  auto res = [](const Eigen::VectorXd& x) { return Eigen::Vector2d(x(0) - 1.0, 1e3 * x(1) - 2.0); };
  hs::Problem p;
  p.scale = Eigen::Vector2d(1.0, 1e-3);
  p.residual = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    r = res(x);
    return r.squaredNorm();
  };
  p.jacobian = [](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& J) { J = Eigen::Matrix2d::Identity(); };
  const auto r = hs::levenberg_marquardt(p, Eigen::Vector2d(0.0, 0.0), tight());
  EXPECT_NEAR(r.x(0), 1.0, 1e-9);
  EXPECT_NEAR(r.x(1), 2e-3, 1e-12);
}

TEST(LevenbergMarquardt, VShapedKinkConvergesWithPerParameterDamping) {
  // f = 10 |x0 - 0.3| + smooth in x1 (the kink as a residual sqrt(10|x0 - 0.3|)): the minimum
  // is on the kink. Per-parameter damping brings x0 to it in 16 iterations while x1 still converges;
  // one damping for both crawls (84 iterations), so 40 are not enough without it.
  auto res = [](const Eigen::VectorXd& x) { return Eigen::Vector2d(std::sqrt(10.0 * std::abs(x(0) - 0.3) + 1e-300), x(1) - 2.0); };
  auto o = tight();
  o.max_iterations = 40;
  o.max_trials = 30;
  o.kink_damping = true;
  const auto r = hs::levenberg_marquardt(make(res), Eigen::Vector2d(1.0, -1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.x(0), 0.3, 1e-4);
  EXPECT_NEAR(r.x(1), 2.0, 1e-6);
}

TEST(LevenbergMarquardt, RelativeDecreaseStopsEarly) {
  auto o = tight();
  o.relative_decrease = 0.5;  // any step gaining less than half the cost stops
  const auto loose = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  const auto full = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), tight());
  EXPECT_TRUE(loose.converged);
  EXPECT_LT(loose.iterations, full.iterations);
  EXPECT_GT(loose.cost, 1e-6);
}

TEST(LevenbergMarquardt, IterationLimitIsNotConvergence) {
  auto o = tight();
  o.max_iterations = 2;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 2);
  EXPECT_EQ(r.stop_reason, hs::StopReason::max_iterations);
}

TEST(LevenbergMarquardt, SecantUpdatesSaveJacobiansAndStopOnAFreshOne) {
  int fd = 0, secant = 0;
  const auto r_fd = hs::levenberg_marquardt(make(rosenbrock, &fd), Eigen::Vector2d(-1.2, 1.0), tight());
  auto o = tight();
  o.secant_updates = 5;
  const auto r_s = hs::levenberg_marquardt(make(rosenbrock, &secant), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r_s.converged);
  EXPECT_NEAR(r_s.x(0), 1.0, 1e-5);
  EXPECT_NEAR(r_s.x(1), 1.0, 1e-5);
  EXPECT_LT(secant, fd);
  EXPECT_EQ(secant, r_s.jacobians);
}

TEST(LevenbergMarquardt, StatisticalToleranceStopsOnInsignificantGains) {
  // With a huge statistical tolerance every gain is insignificant against the residual left: the
  // first accepted step stops the fit although no other rule would.
  auto o = tight();
  o.relative_decrease = 0.0;
  o.step_absolute = 0.0;
  o.statistical_tolerance = 1e6;
  o.degrees_of_freedom = 1.0;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);  // the first accepted step already counts as insignificant
}

// Each stopping rule alone (the others off) on a problem built to reach it: the result names it.
namespace {

hs::Options rules_off() {
  hs::Options o;
  o.max_iterations = 500;
  o.relative_decrease = 0.0;
  return o;
}

}  // namespace

TEST(LevenbergMarquardtStopReason, RelativeDecrease) {
  auto o = rules_off();
  o.relative_decrease = 0.5;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::relative_decrease);
  EXPECT_GT(r.cost, 1e-6);  // stopped early, far from the optimum
}

TEST(LevenbergMarquardtStopReason, StatisticalWinsOverRelativeDecreaseWhenBothHold) {
  auto o = rules_off();
  o.statistical_tolerance = 1e6;
  o.relative_decrease = 1.0;  // also holds on every accepted step: the statistical rule is named
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::statistical);
  EXPECT_EQ(r.iterations, 0);
}

TEST(LevenbergMarquardtStopReason, StatisticalAfterRepeats) {
  auto o = rules_off();
  o.statistical_tolerance = 1e6;
  o.statistical_repeats = 3;  // three insignificant steps in a row: iterations 0, 1, 2
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::statistical);
  EXPECT_EQ(r.iterations, 2);
}

TEST(LevenbergMarquardtStopReason, StepSize) {
  auto o = rules_off();
  o.step_absolute = 1e-6;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::step_size);
  EXPECT_NEAR(r.x(0), 1.0, 1e-4);
}

TEST(LevenbergMarquardtStopReason, NoDecreaseAtThePrecisionOfTheResidual) {
  // No tolerance at all: the fit goes on until no damped trial lowers the cost any more.
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), rules_off());
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::no_decrease);
  EXPECT_NEAR(r.x(0), 1.0, 1e-8);
  EXPECT_LT(r.iterations, 500);
}

// A Jacobian of the wrong sign: every step goes uphill and is rejected, the damping shrinks it.
hs::Problem uphill() {
  hs::Problem p;
  p.residual = [](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    r = x - Eigen::Vector2d(1.0, 2.0);
    return r.squaredNorm();
  };
  p.jacobian = [](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& J) {
    J = -Eigen::Matrix2d::Identity();  // the true one is +I
  };
  return p;
}

TEST(LevenbergMarquardtStopReason, NoDecreaseWhenEveryTrialIsRejected) {
  int evaluations = 0;
  auto p = uphill();
  p.residual = [inner = p.residual, &evaluations](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    ++evaluations;
    return inner(x, r);
  };
  auto o = rules_off();
  o.step_absolute = 0.1;  // the step rule alone does not end the trials
  const auto r = hs::levenberg_marquardt(p, Eigen::Vector2d::Zero(), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::no_decrease);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(evaluations, 1 + o.max_trials);  // the start and every trial
  EXPECT_EQ(r.x, Eigen::Vector2d::Zero());
}

TEST(LevenbergMarquardtStopReason, SmallRejectedStep) {
  auto o = rules_off();
  o.step_absolute = 0.1;
  o.stop_on_small_rejected_step = true;
  const auto r = hs::levenberg_marquardt(uphill(), Eigen::Vector2d::Zero(), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::small_rejected_step);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_LT(r.evaluations, 1 + o.max_trials);  // the trials ended early
}

TEST(LevenbergMarquardtStopReason, Stall) {
  // With a huge stall tolerance any stall_iterations accepted steps gain too little: the check at
  // the start of iteration 3 stops.
  auto o = rules_off();
  o.stall_iterations = 3;
  o.stall_tolerance = 1e6;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::stall);
  EXPECT_EQ(r.iterations, 3);
}

TEST(LevenbergMarquardtStopReason, Gradient) {
  auto o = rules_off();
  o.gradient_tolerance = 1e-6;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::gradient);
  EXPECT_NEAR(r.x(0), 1.0, 1e-5);
}

TEST(LevenbergMarquardtStopReason, GradientConfirmedOnAFreshJacobianWithSecantUpdates) {
  auto o = rules_off();
  o.gradient_tolerance = 1e-6;
  o.secant_updates = 5;
  const auto r = hs::levenberg_marquardt(make(rosenbrock), Eigen::Vector2d(-1.2, 1.0), o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::gradient);
  EXPECT_NEAR(r.x(0), 1.0, 1e-5);
}

TEST(LevenbergMarquardtStopReason, NoParameters) {
  const auto r = hs::levenberg_marquardt(make([](const Eigen::VectorXd&) { return Eigen::Vector2d(1.0, 2.0); }), Eigen::VectorXd(),
                                         rules_off());
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop_reason, hs::StopReason::no_parameters);
  EXPECT_DOUBLE_EQ(r.cost, 5.0);
}

TEST(LevenbergMarquardtStopReason, EachReasonHasItsOwnWords) {
  std::set<std::string> words;
  for (auto reason : {hs::StopReason::relative_decrease, hs::StopReason::statistical, hs::StopReason::step_size,
                      hs::StopReason::small_rejected_step, hs::StopReason::no_decrease, hs::StopReason::stall, hs::StopReason::gradient,
                      hs::StopReason::max_iterations, hs::StopReason::no_parameters}) {
    const std::string w = hs::to_string(reason);
    EXPECT_FALSE(w.empty());
    EXPECT_EQ(w.find("unknown"), std::string::npos) << w;
    words.insert(w);
  }
  EXPECT_EQ(words.size(), 9u);
  EXPECT_STREQ(hs::to_string(hs::StopReason::max_iterations), "iteration limit reached");
}
