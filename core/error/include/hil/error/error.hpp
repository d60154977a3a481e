#pragma once
/// \file The error every reader of hil's inputs raises (run and rig files, model JSON, configurations, bus profiles): where and what.
#include <cstddef>
#include <stdexcept>
#include <string>

namespace hil::error {

/// Where in an input a problem sits. Line and column are 1-based; 0 means "not applicable".
struct Location {
  std::string file;
  std::size_t line = 0;
  std::size_t column = 0;
  std::string field;  ///< column name, YAML key path (e.g. `objects[0].features[1].name`) or empty

  /// "file:line:column: field 'x'" with the parts that are known.
  std::string str() const;
};

/// Thrown on bad input. `what()` reads "FILE:LINE:COL: field 'F': MESSAGE" so that a user can go
/// straight to the cell or key at fault.
class FormatError : public std::runtime_error {
 public:
  FormatError(Location where, std::string message);
  const Location& where() const noexcept { return where_; }
  const std::string& message() const noexcept { return message_; }

 private:
  Location where_;
  std::string message_;
};

}  // namespace hil::error
