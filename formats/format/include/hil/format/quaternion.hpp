#pragma once
#include <Eigen/Geometry>
#include <optional>

namespace hil::format {

/// Largest |‖q‖ - 1| accepted as rounding of a unit quaternion written with few digits
/// (4 significant digits per component give about 1e-4). Within it q is renormalised; beyond it
/// the input is refused: a quaternion that far from unit is a bug upstream, not rounding.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// The unit quaternion (w, x, y, z), or nothing if its norm is not 1 within the tolerance.
inline std::optional<Eigen::Quaterniond> checked_unit_quaternion(double w, double x, double y, double z) {
  const Eigen::Quaterniond q(w, x, y, z);
  const double n = q.norm();
  if (!(std::abs(n - 1.0) <= kQuaternionNormTolerance)) return std::nullopt;
  return q.normalized();
}

}  // namespace hil::format
