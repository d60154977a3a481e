#pragma once
// Helpers of the device tests (drivers, rig_drivers): wrench comparison and the ConfigError check.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/test/process.hpp>

namespace hil::test {

/// Element-wise |a - b| <= tol, printing both on failure.
inline ::testing::AssertionResult near6(const drivers::Vector6d& a, const drivers::Vector6d& b, const drivers::Vector6d& tol) {
  for (int i = 0; i < 6; ++i)
    if (!(std::abs(a[i] - b[i]) <= tol[i]))
      return ::testing::AssertionFailure() << "component " << i << ": " << a.transpose() << " vs " << b.transpose() << " (tol "
                                           << tol.transpose() << ")";
  return ::testing::AssertionSuccess();
}

/// Runs f, expects a ConfigError whose field is `field` and whose message contains `what`.
inline ::testing::AssertionResult config_error(const std::function<void()>& f, const std::string& field, const std::string& what) {
  try {
    f();
  } catch (const drivers::ConfigError& e) {
    const std::string msg = e.what();
    if (e.field() != field) return ::testing::AssertionFailure() << "field '" << e.field() << "' != '" << field << "' in: " << msg;
    if (msg.find(what) == std::string::npos) return ::testing::AssertionFailure() << "'" << what << "' not in: " << msg;
    return ::testing::AssertionSuccess();
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "wrong exception: " << e.what();
  }
  return ::testing::AssertionFailure() << "no error";
}

}  // namespace hil::test
