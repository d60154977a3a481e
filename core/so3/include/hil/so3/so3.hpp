#pragma once
/// \file Rotations as rotation vectors (the exponential and logarithm of SO(3), their Jacobians and
/// those of the action on a point) and hil's 6-D vector types: the one place they are written, used
/// by the numerics, the drivers and the acquisition alike. Eigen only.
#include <Eigen/Geometry>

#include <cmath>

namespace hil {

/// A 6-D small displacement, twist or wrench, [linear; angular] unless its name says otherwise.
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

namespace so3 {

/// The rotation by |φ| rad about φ/|φ|; the identity for φ = 0.
inline Eigen::Matrix3d exp(const Eigen::Vector3d& phi_rad) {
  const double angle = phi_rad.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, phi_rad / angle).toRotationMatrix();
}

/// The rotation vector (axis times angle, the angle in [0, π]) of a rotation matrix.
inline Eigen::Vector3d log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

/// The rotation vector of a quaternion (any norm: only its direction counts), angle in [0, π].
inline Eigen::Vector3d log(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis();
}

/// The angle of a rotation matrix, in [0, π] rad.
inline double angle(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle(); }

// Jacobians (the conventions of Solà et al., "A micro Lie theory", as in manif and Sophus).
// They are dimensionless (rad per rad). Below kSmallAngle_rad the coefficients of the closed forms
// are Taylor series: the closed forms divide differences that cancel by powers of the angle.

/// Below this angle the Jacobians' coefficients are series to θ⁶ (the first term left out: < 6e-15
/// relative); above it closed forms, which lose up to ~1e-13 relative just above it to cancellation
/// (on a coefficient of [φ]×², itself ~θ²: the matrices stay within a few ulp either way).
inline constexpr double kSmallAngle_rad = 0.1;

/// [v]×, the matrix of the cross product: hat(v) w = v × w.
inline Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

namespace detail {

/// (1 - cos θ)/θ², (θ - sin θ)/θ³ and 1/θ² - (1 + cos θ)/(2θ sin θ) = (1 - (θ/2) cot(θ/2))/θ², the
/// coefficients of [φ]× and [φ]×² in the Jacobians, at θ = |φ| rad.
struct JacobianCoefficients {
  double a, b, c;
};

inline JacobianCoefficients jacobian_coefficients(double angle_rad) {
  const double t = angle_rad, t2 = t * t;
  if (t < kSmallAngle_rad)
    return {0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0)),           // 1/2 - θ²/24 + θ⁴/720 - θ⁶/40320
            1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)),    // 1/6 - θ²/120 + θ⁴/5040 - θ⁶/362880
            1.0 / 12.0 + t2 / 720.0 * (1.0 + t2 / 42.0 * (1.0 + t2 / 40.0))};  // 1/12 + θ²/720 + θ⁴/30240 + θ⁶/1209600
  const double half = 0.5 * t, s = std::sin(half);
  // 1 - cos θ = 2 sin²(θ/2): no cancellation. cot(θ/2) is finite up to θ = π (0 there); the inverse
  // Jacobians are singular at θ = 2π only.
  return {2.0 * s * s / t2, (t - std::sin(t)) / (t2 * t), (1.0 - half * std::cos(half) / s) / t2};
}

}  // namespace detail

/// The right Jacobian Jr(φ): exp(φ + δ) ≈ exp(φ) exp(Jr(φ) δ) for small δ, i.e. an increment of the
/// rotation vector is a rotation Jr δ in the rotated (body) frame. Jr = I - a [φ]× + b [φ]×².
inline Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi_rad) {
  const auto k = detail::jacobian_coefficients(phi_rad.norm());
  const Eigen::Matrix3d P = hat(phi_rad);
  return Eigen::Matrix3d::Identity() - k.a * P + k.b * P * P;
}

/// The left Jacobian Jl(φ) = Jr(-φ) = exp(φ) Jr(φ): exp(φ + δ) ≈ exp(Jl(φ) δ) exp(φ), the rotation in
/// the fixed (world) frame.
inline Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& phi_rad) { return right_jacobian(-phi_rad); }

/// Jr(φ)⁻¹ = I + ½ [φ]× + c [φ]×², for |φ| < 2π. It is also the derivative of log for a
/// perturbation on the right: log(exp(φ) exp(δ)) ≈ φ + Jr(φ)⁻¹ δ (|φ| < π).
inline Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi_rad) {
  const auto k = detail::jacobian_coefficients(phi_rad.norm());
  const Eigen::Matrix3d P = hat(phi_rad);
  return Eigen::Matrix3d::Identity() + 0.5 * P + k.c * P * P;
}

/// Jl(φ)⁻¹ = Jr(-φ)⁻¹; the derivative of log on the left: log(exp(δ) exp(φ)) ≈ φ + Jl(φ)⁻¹ δ.
inline Eigen::Matrix3d left_jacobian_inverse(const Eigen::Vector3d& phi_rad) { return right_jacobian_inverse(-phi_rad); }

/// ∂(exp(φ) p)/∂φ for the rotation vector itself (additive increments, as a least-squares fit of φ
/// takes them): -exp(φ) [p]× Jr(φ), in the units of p per rad. With exp(φ) = R_a_b, p is in frame b
/// and the result in frame a.
inline Eigen::Matrix3d rotate_jacobian(const Eigen::Vector3d& phi_a_b_rad, const Eigen::Vector3d& p_b) {
  return -exp(phi_a_b_rad) * hat(p_b) * right_jacobian(phi_a_b_rad);
}

/// ∂(R exp(δ) p)/∂δ at δ = 0 (a perturbation on the right, in frame b): -R [p]×.
inline Eigen::Matrix3d rotate_jacobian_right(const Eigen::Matrix3d& R_a_b, const Eigen::Vector3d& p_b) { return -R_a_b * hat(p_b); }

/// ∂(exp(δ) R p)/∂δ at δ = 0 (a perturbation on the left, in frame a): -[R p]×.
inline Eigen::Matrix3d rotate_jacobian_left(const Eigen::Matrix3d& R_a_b, const Eigen::Vector3d& p_b) { return -hat(R_a_b * p_b); }

}  // namespace so3
}  // namespace hil
