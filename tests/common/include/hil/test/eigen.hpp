#pragma once
// Tolerance-aware comparisons that print both operands on failure.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <sstream>

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

}  // namespace hil::test
