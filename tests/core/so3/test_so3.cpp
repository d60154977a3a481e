#include <hil/so3/so3.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace so3 = hil::so3;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kPi = std::numbers::pi;

/// Rotation vectors to test at: random directions with angles spread over (0, π), tiny angles down
/// to 1e-12 rad, either side of the series' threshold, and up to within 1e-6 rad of π.
std::vector<Vector3d> angles_up_to_pi() {
  std::mt19937 rng(26);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, kPi);
  auto direction = [&] { return Vector3d(normal(rng), normal(rng), normal(rng)).normalized(); };
  std::vector<Vector3d> phis;
  for (int i = 0; i < 40; ++i) phis.push_back(uniform(rng) * direction());
  for (double a : {1e-12, 1e-9, 1e-6, 1e-4, 1e-2, 0.5 * so3::kSmallAngle_rad, so3::kSmallAngle_rad * (1.0 - 1e-12), so3::kSmallAngle_rad,
                   so3::kSmallAngle_rad * (1.0 + 1e-12), 1.0, 3.0, kPi - 1e-3, kPi - 1e-6})
    phis.push_back(a * direction());
  phis.push_back(Vector3d(0.0, 0.0, kPi - 1e-4));  // along an axis, where the series' branches meet zeros
  return phis;
}

/// The rotation vector of exp(φ) seen from exp(φ0) on the right, log(exp(φ0)ᵀ exp(φ)).
Vector3d right_difference(const Vector3d& phi0, const Vector3d& phi) {
  return so3::log(Matrix3d(so3::exp(phi0).transpose() * so3::exp(phi)));
}
Vector3d left_difference(const Vector3d& phi0, const Vector3d& phi) {
  return so3::log(Matrix3d(so3::exp(phi) * so3::exp(phi0).transpose()));
}

/// Central differences of f: R³ → R³ at x, step h.
template <class F>
Matrix3d central_difference(F&& f, const Vector3d& x, double h = 1e-6) {
  Matrix3d J;
  for (int j = 0; j < 3; ++j) {
    const Vector3d e = h * Vector3d::Unit(j);
    J.col(j) = (f(x + e) - f(x - e)) / (2.0 * h);
  }
  return J;
}

// Central differences of step 1e-6 are good to ~1e-10 (rounding ~1e-16/h, truncation ~h²).
constexpr double kFdTolerance = 1e-8;

std::string at(const Vector3d& phi) {
  return "at φ = " + std::to_string(phi.x()) + " " + std::to_string(phi.y()) + " " + std::to_string(phi.z()) +
         " (|φ| = " + std::to_string(phi.norm()) + ")";
}

}  // namespace

TEST(So3, HatIsTheCrossProduct) {
  const Vector3d v(0.3, -1.2, 2.5), w(-0.7, 0.4, 1.1);
  EXPECT_TRUE((so3::hat(v) * w).isApprox(v.cross(w), 1e-15));
  EXPECT_TRUE(so3::hat(v).transpose().isApprox(-so3::hat(v)));
}

TEST(So3Jacobians, RightJacobianIsTheDerivativeOfExpInTheBodyFrame) {
  // Jr(φ) = ∂ log(exp(φ)ᵀ exp(φ + δ)) / ∂δ at δ = 0.
  for (const Vector3d& phi : angles_up_to_pi()) {
    const Matrix3d fd = central_difference([&](const Vector3d& p) { return right_difference(phi, p); }, phi);
    EXPECT_LT((so3::right_jacobian(phi) - fd).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
  }
}

TEST(So3Jacobians, LeftJacobianIsTheDerivativeOfExpInTheWorldFrame) {
  for (const Vector3d& phi : angles_up_to_pi()) {
    const Matrix3d fd = central_difference([&](const Vector3d& p) { return left_difference(phi, p); }, phi);
    EXPECT_LT((so3::left_jacobian(phi) - fd).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
  }
}

TEST(So3Jacobians, BeyondPiTheJacobiansStillDifferentiateExp) {
  // exp takes any rotation vector; its Jacobians hold past π (only log wraps).
  for (const Vector3d& phi : {Vector3d(0.0, 0.0, kPi), Vector3d(2.0, -2.5, 1.0), Vector3d(-4.0, 3.0, 2.0)}) {
    const Matrix3d fd_r = central_difference([&](const Vector3d& p) { return right_difference(phi, p); }, phi);
    const Matrix3d fd_l = central_difference([&](const Vector3d& p) { return left_difference(phi, p); }, phi);
    EXPECT_LT((so3::right_jacobian(phi) - fd_r).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
    EXPECT_LT((so3::left_jacobian(phi) - fd_l).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
  }
}

TEST(So3Jacobians, LeftIsRightOfMinusPhiAndTheRotatedRight) {
  for (const Vector3d& phi : angles_up_to_pi()) {
    EXPECT_TRUE(so3::left_jacobian(phi).isApprox(so3::right_jacobian(-phi), 1e-15)) << at(phi);
    // Jl(φ) = exp(φ) Jr(φ): the same increment seen in the world frame.
    EXPECT_LT((so3::left_jacobian(phi) - so3::exp(phi) * so3::right_jacobian(phi)).cwiseAbs().maxCoeff(), 1e-14) << at(phi);
  }
}

TEST(So3Jacobians, InversesAreInverses) {
  auto phis = angles_up_to_pi();
  phis.push_back(Vector3d(0.0, kPi, 0.0));
  phis.push_back(Vector3d(1.0, 2.0, -5.0).normalized() * 6.0);  // beyond π, short of the singularity at 2π
  for (const Vector3d& phi : phis) {
    const double tol = phi.norm() > kPi ? 1e-12 : 1e-14;
    EXPECT_LT((so3::right_jacobian(phi) * so3::right_jacobian_inverse(phi) - Matrix3d::Identity()).cwiseAbs().maxCoeff(), tol) << at(phi);
    EXPECT_LT((so3::right_jacobian_inverse(phi) * so3::right_jacobian(phi) - Matrix3d::Identity()).cwiseAbs().maxCoeff(), tol) << at(phi);
    EXPECT_LT((so3::left_jacobian(phi) * so3::left_jacobian_inverse(phi) - Matrix3d::Identity()).cwiseAbs().maxCoeff(), tol) << at(phi);
    EXPECT_TRUE(so3::left_jacobian_inverse(phi).isApprox(so3::right_jacobian_inverse(-phi), 1e-15)) << at(phi);
  }
}

TEST(So3Jacobians, InverseJacobiansAreTheDerivativesOfLog) {
  // log(exp(φ) exp(δ)) ≈ φ + Jr⁻¹(φ) δ and log(exp(δ) exp(φ)) ≈ φ + Jl⁻¹(φ) δ, for |φ| < π.
  for (const Vector3d& phi : angles_up_to_pi()) {
    const Matrix3d R = so3::exp(phi);
    const Matrix3d fd_r = central_difference([&](const Vector3d& d) { return so3::log(Matrix3d(R * so3::exp(d))); }, Vector3d::Zero());
    const Matrix3d fd_l = central_difference([&](const Vector3d& d) { return so3::log(Matrix3d(so3::exp(d) * R)); }, Vector3d::Zero());
    EXPECT_LT((so3::right_jacobian_inverse(phi) - fd_r).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
    EXPECT_LT((so3::left_jacobian_inverse(phi) - fd_l).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
  }
}

TEST(So3Jacobians, DerivativeOfARotationResidualByTheChainRule) {
  // A fit's residual e(φ) = log(R_measᵀ exp(φ)): ∂e/∂φ = Jr⁻¹(e) Jr(φ).
  const Matrix3d R_meas = so3::exp(Vector3d(0.4, -1.1, 0.9));
  for (const Vector3d& phi : angles_up_to_pi()) {
    auto residual = [&](const Vector3d& p) { return so3::log(Matrix3d(R_meas.transpose() * so3::exp(p))); };
    const Vector3d e = residual(phi);
    if (e.norm() > kPi - 1e-3) continue;  // log wraps at π: no derivative across it
    const Matrix3d J = so3::right_jacobian_inverse(e) * so3::right_jacobian(phi);
    EXPECT_LT((J - central_difference(residual, phi)).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
  }
}

TEST(So3Jacobians, ExpOfASumIsAProductToSecondOrder) {
  // exp(φ + dφ) = exp(φ) exp(Jr(φ) dφ) + O(|dφ|²): the error falls 100-fold when dφ falls 10-fold,
  // while without Jr (exp(φ) exp(dφ)) it is first order and only falls 10-fold.
  const Vector3d dir = Vector3d(0.3, -0.8, 0.5).normalized();
  for (const Vector3d& phi : angles_up_to_pi()) {
    auto error = [&](double size, bool with_jacobian) {
      const Vector3d d = size * dir;
      const Matrix3d approx = so3::exp(phi) * so3::exp(with_jacobian ? Vector3d(so3::right_jacobian(phi) * d) : d);
      return (so3::exp(phi + d) - approx).norm();
    };
    const double e3 = error(1e-3, true), e4 = error(1e-4, true);
    EXPECT_LT(e3, 2e-6) << at(phi);
    EXPECT_LT(e4, 2e-8) << at(phi);
    if (phi.norm() > 0.1) {  // Jr matters
      EXPECT_GT(error(1e-4, false), 1e-6 * phi.norm()) << at(phi);
    }
  }
}

TEST(So3Jacobians, SeriesAndClosedFormsMeetAtTheThreshold) {
  // Either side of kSmallAngle_rad (and at it) the Jacobians agree to rounding: no step at the switch.
  const Vector3d dir = Vector3d(-0.2, 0.9, 0.4).normalized();
  const Vector3d below = std::nextafter(so3::kSmallAngle_rad, 0.0) * dir, above = std::nextafter(so3::kSmallAngle_rad, 1.0) * dir;
  ASSERT_LT(below.norm(), so3::kSmallAngle_rad);
  ASSERT_GE(above.norm(), so3::kSmallAngle_rad);
  EXPECT_LT((so3::right_jacobian(below) - so3::right_jacobian(above)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((so3::right_jacobian_inverse(below) - so3::right_jacobian_inverse(above)).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(So3Jacobians, AtZeroTheyAreTheIdentityAndNearItFirstOrder) {
  EXPECT_EQ(so3::right_jacobian(Vector3d::Zero()), Matrix3d::Identity());
  EXPECT_EQ(so3::left_jacobian_inverse(Vector3d::Zero()), Matrix3d::Identity());
  // |φ| = 1e-8: Jr = I - ½[φ]× to rounding (the [φ]×² term is 1e-16 / 6).
  const Vector3d phi(6e-9, -8e-9, 0.0);
  EXPECT_LT((so3::right_jacobian(phi) - (Matrix3d::Identity() - 0.5 * so3::hat(phi))).cwiseAbs().maxCoeff(), 1e-16);
  EXPECT_LT((so3::right_jacobian_inverse(phi) - (Matrix3d::Identity() + 0.5 * so3::hat(phi))).cwiseAbs().maxCoeff(), 1e-16);
  // No overflow or 0/0 at angles whose square underflows.
  EXPECT_TRUE(so3::right_jacobian_inverse(Vector3d(1e-200, 0.0, 0.0)).allFinite());
}

TEST(So3Jacobians, RotatingAPoint) {
  const Vector3d p_b(0.7, -0.2, 1.5);
  for (const Vector3d& phi : angles_up_to_pi()) {
    const Matrix3d R_a_b = so3::exp(phi);
    // Additive in φ.
    const Matrix3d fd = central_difference([&](const Vector3d& q) { return Vector3d(so3::exp(q) * p_b); }, phi);
    EXPECT_LT((so3::rotate_jacobian(phi, p_b) - fd).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
    // Perturbed on the right (frame b) and on the left (frame a).
    const Matrix3d fd_r = central_difference([&](const Vector3d& d) { return Vector3d(R_a_b * so3::exp(d) * p_b); }, Vector3d::Zero());
    const Matrix3d fd_l = central_difference([&](const Vector3d& d) { return Vector3d(so3::exp(d) * R_a_b * p_b); }, Vector3d::Zero());
    EXPECT_LT((so3::rotate_jacobian_right(R_a_b, p_b) - fd_r).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
    EXPECT_LT((so3::rotate_jacobian_left(R_a_b, p_b) - fd_l).cwiseAbs().maxCoeff(), kFdTolerance) << at(phi);
    // The additive one is the right-perturbed one through Jr, or the left one through Jl.
    EXPECT_LT((so3::rotate_jacobian(phi, p_b) - so3::rotate_jacobian_left(R_a_b, p_b) * so3::left_jacobian(phi)).cwiseAbs().maxCoeff(),
              1e-14)
        << at(phi);
  }
}
