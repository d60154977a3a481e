#pragma once
// The shipped bench (examples/rigs/press_bench.yaml) with its force plate replaced: the rigs the
// acquisition tests of each force-plate transport run.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <hil/test/files.hpp>

namespace hil::test {

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes `name` into `tmp`: the bench with `plate_fields` (lines indented by four spaces, each
/// ending in a newline) as its force_plate section. \returns its path.
inline std::string bench_with_plate(const TempDir& tmp, const std::string& name, const std::string& plate_fields) {
  const std::string rig = read_text(std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml");
  const std::regex plate(R"(  force_plate:\n(    .*\n)+)");
  const std::string out = std::regex_replace(rig, plate, "  force_plate:\n" + plate_fields, std::regex_constants::format_first_only);
  EXPECT_NE(out, rig) << "the example rig's force_plate section was not found";
  return tmp.file(name, out);
}

}  // namespace hil::test
