#include <hil/drivers/error.hpp>

namespace hil::drivers {

ConfigError::ConfigError(std::string field, const std::string& what)
    : std::runtime_error(field.empty() ? what : field + ": " + what), field_(std::move(field)) {}

}  // namespace hil::drivers
