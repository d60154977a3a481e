#pragma once
// Where `hil` finds its shipped data (examples/): $HIL_DATA_DIR, else <prefix>/share/hil beside an
// installed binary (<prefix>/bin/hil), else the source tree it was built from. docs/install.md.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hil::cli {

struct DataDirLookup {
  std::optional<std::filesystem::path> found;  ///< the first place holding examples/
  std::vector<std::string> looked;             ///< every place tried, in order, with why it was refused
};

/// Never throws: for defaults shown in --help.
DataDirLookup find_data_dir();

/// `relative` (e.g. "examples/acu/acu.yaml") under the data dir.
/// \throws std::runtime_error naming every place looked at, or the missing file.
std::filesystem::path data_file(const std::string& relative);

/// `data_file(relative)` as a string, or "" when there is none (the error comes when it is used).
std::string data_file_or_empty(const std::string& relative);

}  // namespace hil::cli
