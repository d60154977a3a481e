#include <hil/format/yaml.hpp>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include <hil/format/edit_distance.hpp>

namespace hil::format {
namespace {

// Found by fuzzing: a null, list or mapping key (`? [a]: 1`, `&x : 1`) made as<string>() throw
// yaml-cpp's bare "bad conversion".
std::string key_text(const YAML::Node& key, const std::string& file, const std::string& path) {
  if (key.IsScalar()) return key.Scalar();
  const auto m = key.Mark();
  throw error::FormatError(error::Location{file, static_cast<std::size_t>(m.line + 1), static_cast<std::size_t>(m.column + 1), path},
                           "a field name must be plain text");
}

}  // namespace

error::Location YamlNode::where(const std::string& sub) const {
  const auto m = n_.Mark();
  error::Location loc{*file_, m.line >= 0 ? static_cast<std::size_t>(m.line + 1) : 0,
                      m.column >= 0 ? static_cast<std::size_t>(m.column + 1) : 0, path_};
  if (!sub.empty()) loc.field = path_.empty() ? sub : path_ + "." + sub;
  return loc;
}

void YamlNode::fail(const std::string& message, const std::string& sub) const { throw error::FormatError(where(sub), message); }

YamlNode YamlNode::child(const std::string& key) const { return YamlNode(n_[key], path_.empty() ? key : path_ + "." + key, file_); }

YamlNode YamlNode::req(const std::string& key) const {
  expect_map();
  if (!has(key)) fail("required field is missing", key);
  return child(key);
}

void YamlNode::expect_map() const {
  if (!n_.IsMap()) fail("expected a mapping of fields");
}

void YamlNode::only(std::initializer_list<const char*> allowed) const {
  expect_map();
  for (const auto& kv : n_) {
    const auto key = key_text(kv.first, *file_, path_);
    bool ok = false;
    std::string best;
    std::size_t best_d = 4;
    for (const char* a : allowed) {
      if (key == a) ok = true;
      const auto d = edit_distance(key, a);
      if (d < best_d) best_d = d, best = a;
    }
    if (!ok) {
      const auto m = kv.first.Mark();
      error::Location loc{*file_, static_cast<std::size_t>(m.line + 1), static_cast<std::size_t>(m.column + 1),
                          path_.empty() ? key : path_ + "." + key};
      std::string known;
      for (const char* a : allowed) known += std::string(known.empty() ? "" : ", ") + a;
      throw error::FormatError(loc, "unknown field" + (best.empty() ? "" : " (did you mean '" + best + "'?)") + "; known here: " + known);
    }
  }
}

std::vector<std::string> YamlNode::keys() const {
  expect_map();
  std::vector<std::string> out;
  for (const auto& kv : n_) out.push_back(key_text(kv.first, *file_, path_));
  return out;
}

std::vector<YamlNode> YamlNode::seq() const {
  if (!n_.IsSequence()) fail("expected a list");
  std::vector<YamlNode> out;
  for (std::size_t i = 0; i < n_.size(); ++i) out.emplace_back(n_[i], path_ + "[" + std::to_string(i) + "]", file_);
  return out;
}

double YamlNode::num() const {
  if (!n_.IsScalar()) fail("expected a number");
  const auto s = n_.Scalar();
  double v = 0.0;
  const char* b = s.data();
  if (!s.empty() && *b == '+') ++b;
  const auto [p, ec] = std::from_chars(b, s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size()) {
    // YAML's own spellings of NaN and infinity.
    std::string lower;
    for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == ".nan" || lower == ".inf" || lower == "-.inf" || lower == "+.inf") fail("expected a finite number, found '" + s + "'");
    // Accept hexadecimal integers (CAN ids are written that way).
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      unsigned long long u = 0;
      const auto [p2, ec2] = std::from_chars(s.data() + 2, s.data() + s.size(), u, 16);
      if (ec2 == std::errc() && p2 == s.data() + s.size()) return static_cast<double>(u);
    }
    fail("expected a number, found '" + s + "'");
  }
  if (!std::isfinite(v)) fail("expected a finite number, found '" + s + "'");
  return v;
}

double YamlNode::num_positive() const {
  const double v = num();
  if (!(v > 0.0)) fail("expected a positive number, found " + n_.Scalar());
  return v;
}

long YamlNode::integer() const {
  const double v = num();
  if (v != std::floor(v) || std::fabs(v) > 9.0e15) fail("expected an integer, found '" + n_.Scalar() + "'");
  return static_cast<long>(v);
}

std::size_t YamlNode::count(std::size_t min) const {
  const double v = num();
  if (v != std::floor(v) || v < static_cast<double>(min) || v > 1e9)
    fail("expected an integer >= " + std::to_string(min) + ", found '" + n_.Scalar() + "'");
  return static_cast<std::size_t>(v);
}

bool YamlNode::boolean() const {
  if (!n_.IsScalar()) fail("expected true or false");
  const auto s = n_.Scalar();
  if (s == "true") return true;
  if (s == "false") return false;
  fail("expected true or false, found '" + s + "'");
}

std::string YamlNode::str() const {
  if (!n_.IsScalar()) fail("expected a text value");
  return n_.Scalar();
}

std::vector<double> YamlNode::nums() const {
  std::vector<double> out;
  for (const auto& e : seq()) out.push_back(e.num());
  return out;
}

Eigen::Vector3d YamlNode::vec3() const {
  const auto v = nums();
  if (v.size() != 3) fail("expected a list of 3 numbers, found " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

YAML::Node load_yaml(const std::string& text, const std::string& file) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw error::FormatError({file, static_cast<std::size_t>(e.mark.line + 1), static_cast<std::size_t>(e.mark.column + 1), ""},
                             "YAML syntax error: " + e.msg);
  }
}

YAML::Node load_yaml_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return load_yaml(text.str(), path);
}

}  // namespace hil::format
