// A run recorded through the Net F/T box's RDT stream, as `hil acquire --play` does it: the fake box
// on 127.0.0.1 plays the shipped example run with records dropped, cut short and duplicated, and a
// status window; every reading the driver delivered is in the recording, flagged readings are
// never good samples, and the losses are counted where the run says so.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include <hil/acquisition/streams.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/acquire.hpp>
#include <hil/test/files.hpp>

using namespace hil;

namespace {

std::string read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The shipped bench with its force plate replaced by a Net F/T box reading the shipped page.
std::string netft_rig(const test::TempDir& tmp) {
  std::string rig = read(std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml");
  const std::regex plate(R"(  force_plate:\n(    .*\n)+)");
  const std::string page = std::string(HIL_SOURCE_DIR) + "/examples/netft/netftapi2.xml";
  const std::string with = "  force_plate:\n    protocol: ati_netft_rdt\n    host: 127.0.0.1\n    port: 49152\n    calibration_xml: " +
                           page + "\n    rate_hz: 1000\n    saturation_limits: [660, 660, 1980, 60, 60, 60]\n";
  const std::string out = std::regex_replace(rig, plate, with, std::regex_constants::format_first_only);
  EXPECT_NE(out, rig) << "the example rig's force_plate section was not found";
  return tmp.file("netft_bench.yaml", out);
}

}  // namespace

TEST(NetFtAcquire, ARunThroughTheBoxsStreamLosesNothingDeliveredAndFlagsStatusBits) {
  test::TempDir tmp;
  rig_service::AcquireOptions o;
  o.rig = netft_rig(tmp);
  o.out = tmp.path() + "/run";
  o.play = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";
  o.duration_s = 3.0;
  o.no_bus = true;
  o.progress = false;
  o.netft_faults.drop_fraction = 0.02;
  o.netft_faults.corrupt_fraction = 0.01;
  o.netft_faults.duplicate_fraction = 0.01;
  o.netft_faults.status.push_back({{1.0, 0.3}, 0x00000004});
  const auto r = rig_service::run_acquisition(o, nullptr);
  ASSERT_GT(r.samples, 100U);
  const acquisition::DeviceHealth* plate = nullptr;
  for (const auto& h : r.health)
    if (h.device == "force_plate") plate = &h;
  ASSERT_NE(plate, nullptr);
  // Delivered = recorded: every reading the driver handed out is a row of the raw stream.
  const auto raw = format::read_csv(o.out + "/raw/force_plate.csv", format::CsvOptions{});
  EXPECT_EQ(raw.rows(), plate->samples);
  EXPECT_GT(plate->frames_dropped, 0U) << "dropped and cut-short records are counted as lost";
  // The box flagged readings in its status window: counted, and the output samples around them
  // are marked; the run's device identity says what it was.
  EXPECT_GT(plate->device_faults, 100U);
  format::CsvOptions with_quality;
  with_quality.required = {"t", "quality"};
  const auto samples = format::read_csv(o.out + "/samples.csv", with_quality);
  std::size_t flagged = 0;
  for (double q : samples.numeric("quality")) flagged += (static_cast<std::uint32_t>(q) & acquisition::kDeviceFault) != 0;
  EXPECT_GT(flagged, 5U);
  EXPECT_LT(flagged, samples.rows() / 2) << "only the window's samples";
  const auto run = format::load_run(o.out);
  bool udp = false;
  for (const auto& s : run.info.sources) udp = udp || (s.name == "force_plate" && s.kind == "udp");
  EXPECT_TRUE(udp);
  EXPECT_NE(read(o.out + "/run.yaml").find("ati_netft_rdt"), std::string::npos);
}
