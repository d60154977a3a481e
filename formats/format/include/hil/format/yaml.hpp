#pragma once
// Strict YAML access on top of yaml-cpp's parser: every key read is checked against the keys the
// format knows and every value against the type it must have, so that a misspelt key or a bad
// value is an error naming its file, line, column and field instead of being silently ignored.
// The one YAML reader of hil: rig files, run info, import configurations and truth files.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cstddef>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <hil/error/error.hpp>

namespace hil::format {

/// One node of a document and where it is (`path`: "devices.force_plate.channels[2]"). `file`
/// names the document in messages and must outlive the node.
class YamlNode {
 public:
  YamlNode(YAML::Node node, std::string path, const std::string* file) : n_(std::move(node)), path_(std::move(path)), file_(file) {}

  const YAML::Node& raw() const { return n_; }
  const std::string& path() const { return path_; }
  /// This node's line and column; `sub` names a field below it (a missing key).
  error::Location where(const std::string& sub = "") const;
  [[noreturn]] void fail(const std::string& message, const std::string& sub = "") const;

  bool is_map() const { return n_.IsMap(); }
  bool is_scalar() const { return n_.IsScalar(); }
  bool has(const std::string& key) const { return n_.IsMap() && n_[key].IsDefined() && !n_[key].IsNull(); }
  YamlNode req(const std::string& key) const;  ///< child that must exist
  YamlNode child(const std::string& key) const;
  /// Refuses keys other than `allowed`, naming the closest allowed key.
  void only(std::initializer_list<const char*> allowed) const;
  void expect_map() const;
  std::vector<std::string> keys() const;  ///< a mapping's keys, each plain text
  std::vector<YamlNode> seq() const;      ///< elements of a sequence

  double num() const;  ///< finite; decimal, or a hexadecimal integer (0x...)
  double num_positive() const;
  long integer() const;
  std::size_t count(std::size_t min) const;  ///< an integer >= min (and <= 1e9)
  bool boolean() const;
  std::string str() const;
  Eigen::Vector3d vec3() const;
  std::vector<double> nums() const;
  /// One of `choices`, each with the value it maps to.
  template <typename T>
  T choice(std::initializer_list<std::pair<const char*, T>> choices) const {
    const auto s = str();
    std::string known;
    for (const auto& [name, value] : choices) {
      if (s == name) return value;
      known += std::string(known.empty() ? "" : ", ") + name;
    }
    fail("expected one of " + known + ", found '" + s + "'");
  }

  double num(const std::string& key, double dflt) const { return has(key) ? child(key).num() : dflt; }
  std::string str(const std::string& key, const std::string& dflt) const { return has(key) ? child(key).str() : dflt; }

 private:
  YAML::Node n_;
  std::string path_;
  const std::string* file_;
};

/// Parses a document; a YAML syntax error becomes a error::FormatError with its line and column.
YAML::Node load_yaml(const std::string& text, const std::string& file);
/// Reads and parses `path`; a file that cannot be read is a error::FormatError naming it.
YAML::Node load_yaml_file(const std::string& path);

}  // namespace hil::format
