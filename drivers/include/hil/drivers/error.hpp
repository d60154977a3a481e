#pragma once
/// \file Errors of the device layer. Configuration and start-up failures throw; polling loops
/// return a PollStatus instead (see status.hpp).
#include <stdexcept>
#include <string>

namespace hil::drivers {

/// A configuration value is wrong. The message names the field (e.g. `signals[2].length_bits`)
/// and what is wrong with it.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string field, const std::string& what);
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

/// A device could not be opened or did not answer during start-up. Names the device and the step.
class DeviceError : public std::runtime_error {
 public:
  explicit DeviceError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace hil::drivers
