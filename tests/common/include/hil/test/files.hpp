#pragma once
// A temporary folder per test and the check that bad input is refused with its file, line, field
// and message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <hil/error/error.hpp>

namespace hil::test {

/// A fresh folder under the build tree, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(HIL_BINARY_DIR) / "test-tmp" / (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name, const std::string& text) const {
    const auto p = (path_ / name).string();
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

/// Runs f, expects a FormatError whose message names `line` (0: any), `field` and contains `what`.
inline ::testing::AssertionResult fails_with(const std::function<void()>& f, std::size_t line, const std::string& field,
                                             const std::string& what) {
  try {
    f();
  } catch (const hil::error::FormatError& e) {
    const std::string msg = e.what();
    if (line != 0 && e.where().line != line)
      return ::testing::AssertionFailure() << "line " << e.where().line << " != " << line << " in: " << msg;
    if (!field.empty() && e.where().field != field)
      return ::testing::AssertionFailure() << "field '" << e.where().field << "' != '" << field << "' in: " << msg;
    if (msg.find(what) == std::string::npos) return ::testing::AssertionFailure() << "'" << what << "' not in: " << msg;
    if (e.where().file.empty()) return ::testing::AssertionFailure() << "no file named in: " << msg;
    return ::testing::AssertionSuccess() << msg;
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "wrong exception type: " << e.what();
  }
  return ::testing::AssertionFailure() << "no error raised";
}

}  // namespace hil::test
