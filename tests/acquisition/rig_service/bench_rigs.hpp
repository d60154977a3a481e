#pragma once
// The shipped bench (examples/rigs/press_bench.yaml) with its force plate replaced, played by the
// fake rig: the runs the acquisition tests of each force-plate transport record and check.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <hil/acquisition/streams.hpp>
#include <hil/format/csv.hpp>
#include <hil/rig_service/acquire.hpp>
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

/// `hil acquire --rig RIG --play press_slide --duration 3` into tmp/run, without the bus.
inline rig_service::AcquireOptions played_options(const TempDir& tmp, const std::string& rig) {
  rig_service::AcquireOptions o;
  o.rig = rig;
  o.out = tmp.path() + "/run";
  o.play = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";
  o.duration_s = 3.0;
  o.no_bus = true;
  o.progress = false;
  return o;
}

inline const acquisition::DeviceHealth& plate_health(const rig_service::AcquireResult& r) {
  for (const auto& h : r.health)
    if (h.device == "force_plate") return h;
  throw std::runtime_error("no force_plate health");
}

/// The rows of RUN/samples.csv recorded DEVICE_FAULT, and (`rows`) how many rows there are.
inline std::size_t device_fault_samples(const std::string& run, std::size_t& rows) {
  format::CsvOptions with_quality;
  with_quality.required = {"t", "quality"};
  const auto samples = format::read_csv(run + "/samples.csv", with_quality);
  rows = samples.rows();
  std::size_t flagged = 0;
  for (double q : samples.numeric("quality")) flagged += (static_cast<std::uint32_t>(q) & acquisition::kDeviceFault) != 0;
  return flagged;
}

}  // namespace hil::test
