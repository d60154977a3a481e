// Private to hil_contact_id: helpers shared by the identification's sources (problem.cpp,
// linear_estimation.cpp, variable_projection.cpp, observability.cpp, l_curve.cpp).
#pragma once

#include <hil/contact_id/identification.hpp>

#include <Eigen/Core>

namespace hil::contact_id::detail {

/// Residual variance of the force rows and of the moment rows (rows come as 3 force + 3 moment
/// per sample); `p` parameters were fitted. The paper's W_Y equalises the relative errors but is
/// not the noise covariance, so one pooled variance would misstate the intervals.
Eigen::VectorXd row_variances(const Eigen::VectorXd& e, int p);

/// The prior standard deviation an uncertainty is fitted in units of: its prior_std, or when that
/// is not > 0, 0.1 mm for a translation and 1 mrad for a rotation.
inline double fitting_std(const Uncertainty& u) {
  return u.prior_std > 0.0 ? u.prior_std : (u.kind == Uncertainty::Kind::translation ? 1e-4 : 1e-3);
}

}  // namespace hil::contact_id::detail
