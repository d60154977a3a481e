#pragma once
// Where a machine-readable output goes (a file, or stdout for "-"), and the tag every
// JSON output carries (docs/cli.md). Header-only.
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace hil::format {

/// Version of every `hil.<kind>` JSON format hil writes; bumped when a field changes meaning or goes.
inline constexpr int kJsonFormatVersion = 1;

/// "-" names stdout in every output option (--json, --out, --truth-out).
inline bool is_stdout(const std::string& path) { return path == "-"; }

/// Human-readable text: stdout, unless machine output already goes there (then stderr), so that
/// `hil CMD --json - | python3 -m json.tool` sees only the JSON.
inline std::ostream& human(bool stdout_taken) { return stdout_taken ? std::cerr : std::cout; }

/// An output file, or stdout for "-". close() (or the destructor, quietly) flushes it.
class Output {
 public:
  explicit Output(std::string path) : path_(std::move(path)) {
    if (is_stdout(path_)) return;
    file_.open(path_, std::ios::binary);
    if (!file_) throw std::runtime_error(path_ + ": cannot open for writing");
  }
  std::ostream& stream() { return is_stdout(path_) ? std::cout : file_; }
  /// \throws std::runtime_error naming the file if anything failed to reach it.
  void close() {
    auto& s = stream();
    s.flush();
    if (!s) throw std::runtime_error((is_stdout(path_) ? std::string("stdout") : path_) + ": cannot write");
    if (file_.is_open()) file_.close();
  }

 private:
  std::string path_;
  std::ofstream file_;
};

/// Sets the top-level "format": "hil.<kind>" and "format_version" of a JSON output.
inline void tag_format(nlohmann::json& j, const std::string& kind) {
  j["format"] = "hil." + kind;
  j["format_version"] = kJsonFormatVersion;
}

/// Writes `j` (indented, one trailing newline) to a file or to stdout for "-".
inline void write_json(const std::string& path, const nlohmann::json& j) {
  Output out(path);
  out.stream() << j.dump(2) << '\n';
  out.close();
}

}  // namespace hil::format
