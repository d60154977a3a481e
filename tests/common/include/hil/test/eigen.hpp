#pragma once
// Tolerance-aware comparisons that print both operands on failure.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

namespace hil::test {

template <class A, class B>
::testing::AssertionResult near(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b, double abs_tol, double rel_tol = 0.0) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "shape " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x" << b.cols();
  const double err = (a - b).cwiseAbs().maxCoeff();
  const double tol = abs_tol + rel_tol * std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  if (err <= tol) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os << "max |a - b| = " << err << " > " << tol << "\na =\n" << a << "\nb =\n" << b;
  return ::testing::AssertionFailure() << os.str();
}

/// The mean of `x` and its standard error (sample std / √n; n >= 2), for rules over many draws.
inline std::pair<double, double> mean_and_se(const std::vector<double>& x) {
  const Eigen::Map<const Eigen::VectorXd> v(x.data(), static_cast<Eigen::Index>(x.size()));
  const double mean = v.mean();
  const double n = static_cast<double>(v.size());
  return {mean, std::sqrt((v.array() - mean).square().sum() / (n - 1) / n)};
}

}  // namespace hil::test
