#include <hil/error/error.hpp>

namespace hil::error {

std::string Location::str() const {
  std::string s = file.empty() ? std::string("<input>") : file;
  if (line > 0) {
    s += ':' + std::to_string(line);
    if (column > 0) s += ':' + std::to_string(column);
  }
  if (!field.empty()) s += ": field '" + field + "'";
  return s;
}

FormatError::FormatError(Location where, std::string message)
    : std::runtime_error(where.str() + ": " + message), where_(std::move(where)), message_(std::move(message)) {}

}  // namespace hil::error
