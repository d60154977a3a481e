#include "data_dir.hpp"

#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace hil::cli {
namespace fs = std::filesystem;

namespace {
// A data dir is any folder holding examples/ (the source tree is one).
bool holds_examples(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir / "examples", ec);
}

// <prefix>/<datadir>/hil for a binary in <prefix>/<bindir>: as many levels up as bindir has parts.
std::optional<fs::path> installed_data_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return std::nullopt;
  fs::path prefix = exe.parent_path();
  for (const auto& part : fs::path(HIL_INSTALL_BINDIR)) {
    if (!part.empty()) prefix = prefix.parent_path();
  }
  return (prefix / HIL_INSTALL_DATADIR / "hil").lexically_normal();
}
}  // namespace

DataDirLookup find_data_dir() {
  DataDirLookup r;
  if (const char* env = std::getenv("HIL_DATA_DIR"); env && *env) {
    // Set explicitly: used or refused, never silently passed over.
    if (holds_examples(env)) r.found = fs::path(env);
    else r.looked.push_back(std::string("$HIL_DATA_DIR=") + env + " (no examples/ folder there)");
    return r;
  }
  r.looked.push_back("$HIL_DATA_DIR (unset)");
  if (auto installed = installed_data_dir()) {
    if (holds_examples(*installed)) {
      r.found = *installed;
      return r;
    }
    r.looked.push_back(installed->string() + " (beside the hil binary: no examples/ there)");
  } else {
    r.looked.push_back("the install prefix (/proc/self/exe unreadable)");
  }
  if (holds_examples(HIL_SOURCE_DIR)) {
    r.found = fs::path(HIL_SOURCE_DIR);
    return r;
  }
  r.looked.push_back(std::string(HIL_SOURCE_DIR) + " (the source tree hil was built from: no examples/ there)");
  return r;
}

fs::path data_file(const std::string& relative) {
  const DataDirLookup lookup = find_data_dir();
  if (!lookup.found) {
    std::string msg = "hil's data dir (a folder holding examples/) not found; looked at ";
    for (std::size_t i = 0; i < lookup.looked.size(); ++i) msg += (i ? "; " : "") + lookup.looked[i];
    msg += ". Set HIL_DATA_DIR to one (an installed tree's share/hil)";
    throw std::runtime_error(msg);
  }
  const fs::path file = *lookup.found / relative;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw std::runtime_error("data file not found: " + file.string());
  return file;
}

std::string data_file_or_empty(const std::string& relative) {
  try {
    return data_file(relative).string();
  } catch (const std::runtime_error&) {
    return {};
  }
}

}  // namespace hil::cli
