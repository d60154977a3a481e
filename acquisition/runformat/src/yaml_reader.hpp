#pragma once
// Strict YAML access: every key read is checked against the keys the format knows, so that a
// misspelt or unknown key is an error naming its line instead of being silently ignored.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <initializer_list>
#include <string>
#include <vector>

#include "hil/format/error.hpp"

namespace hil::format::detail {

class YNode {
 public:
  YNode(YAML::Node node, std::string path, const std::string* file) : n_(std::move(node)), path_(std::move(path)), file_(file) {}

  const YAML::Node& raw() const { return n_; }
  const std::string& path() const { return path_; }
  Location where(const std::string& sub = "") const;
  [[noreturn]] void fail(const std::string& message, const std::string& sub = "") const;

  bool has(const std::string& key) const { return n_.IsMap() && n_[key].IsDefined() && !n_[key].IsNull(); }
  YNode req(const std::string& key) const;  ///< child that must exist
  YNode child(const std::string& key) const;
  /// Refuses keys other than `allowed`, naming the closest allowed key.
  void only(std::initializer_list<const char*> allowed) const;
  void expect_map() const;
  std::vector<YNode> seq() const;  ///< elements of a sequence

  double num() const;
  double num_positive() const;
  long integer() const;
  bool boolean() const;
  std::string str() const;
  Eigen::Vector3d vec3() const;
  std::vector<double> nums() const;

  double num(const std::string& key, double dflt) const { return has(key) ? child(key).num() : dflt; }
  std::string str(const std::string& key, const std::string& dflt) const { return has(key) ? child(key).str() : dflt; }

 private:
  YAML::Node n_;
  std::string path_;
  const std::string* file_;
};

/// Loads a document; a YAML syntax error becomes a FormatError with its line.
YAML::Node load_yaml(const std::string& text, const std::string& file);

}  // namespace hil::format::detail
