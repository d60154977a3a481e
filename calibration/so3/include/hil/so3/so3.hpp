#pragma once
/// \file Rotations as rotation vectors (the exponential and logarithm of SO(3)) and hil's 6-D
/// vector types: the one place they are written, used by the numerics, the drivers and the
/// acquisition alike. Eigen only.
#include <Eigen/Geometry>

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

}  // namespace so3
}  // namespace hil
