// A run recorded through the Net F/T box's RDT stream, as `hil acquire --play` does it: the fake box
// on 127.0.0.1 plays the shipped example run with records dropped, cut short and duplicated, and a
// status window; every reading the driver delivered is in the recording, flagged readings are
// never good samples, and the losses are counted where the run says so.
#include <gtest/gtest.h>

#include <hil/acquisition/streams.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/acquire.hpp>
#include <hil/test/files.hpp>
#include "bench_rigs.hpp"

using namespace hil;

namespace {

/// The shipped bench with its force plate replaced by a Net F/T box reading the shipped page.
std::string netft_rig(const test::TempDir& tmp) {
  const std::string page = std::string(HIL_SOURCE_DIR) + "/examples/netft/netftapi2.xml";
  return test::bench_with_plate(tmp, "netft_bench.yaml",
                                "    protocol: ati_netft_rdt\n    host: 127.0.0.1\n    port: 49152\n    calibration_xml: " + page +
                                    "\n    rate_hz: 1000\n    saturation_limits: [660, 660, 1980, 60, 60, 60]\n");
}

}  // namespace

TEST(NetFtAcquire, ARunThroughTheBoxsStreamLosesNothingDeliveredAndFlagsStatusBits) {
  test::TempDir tmp;
  auto o = test::played_options(tmp, netft_rig(tmp));
  o.stream_faults.drop_fraction = 0.02;
  o.stream_faults.corrupt_fraction = 0.01;
  o.stream_faults.duplicate_fraction = 0.01;
  o.stream_faults.status.push_back({{1.0, 0.3}, 0x00000004});
  const auto r = rig_service::run_acquisition(o, nullptr);
  ASSERT_GT(r.samples, 100U);
  const acquisition::DeviceHealth* plate = &test::plate_health(r);
  // Delivered = recorded: every reading the driver handed out is a row of the raw stream.
  const auto raw = format::read_csv(o.out + "/raw/force_plate.csv", format::CsvOptions{});
  EXPECT_EQ(raw.rows(), plate->samples);
  EXPECT_GT(plate->frames_dropped, 0U) << "dropped and cut-short records are counted as lost";
  // The box flagged readings in its status window: counted, and the output samples around them
  // are marked; the run's device identity says what it was.
  EXPECT_GT(plate->device_faults, 100U);
  std::size_t rows = 0;
  const std::size_t flagged = test::device_fault_samples(o.out, rows);
  EXPECT_GT(flagged, 5U);
  EXPECT_LT(flagged, rows / 2) << "only the window's samples";
  const auto run = format::load_run(o.out);
  bool udp = false;
  for (const auto& s : run.info.sources) udp = udp || (s.name == "force_plate" && s.kind == "udp");
  EXPECT_TRUE(udp);
  EXPECT_NE(test::read_text(o.out + "/run.yaml").find("ati_netft_rdt"), std::string::npos);
}

// The same box in CAN mode (short data), polled over the in-process bus as `hil acquire --play`
// does: answers dropped and cut short, a status window. Every reading the driver delivered is
// recorded; flagged readings are device faults in the recording.
TEST(NetFtAcquire, ARunThroughTheBoxsCanModeRecordsEveryReadingAndFlagsStatusBits) {
  test::TempDir tmp;
  auto o = test::played_options(tmp, test::bench_with_plate(tmp, "netft_can_bench.yaml",
                                                            "    protocol: ati_netft_can\n    interface: can0\n    base_id: 0x120\n"
                                                            "    counts_per_force: 50\n    counts_per_torque: 1000\n    rate_hz: 500\n"));
  o.plate_faults.drop_fraction = 0.02;
  o.plate_faults.corrupt_fraction = 0.02;
  o.plate_faults.status.push_back({{1.0, 0.3}, 0x0004});
  const auto r = rig_service::run_acquisition(o, nullptr);
  ASSERT_GT(r.samples, 100U);
  const acquisition::DeviceHealth* plate = &test::plate_health(r);
  const auto raw = format::read_csv(o.out + "/raw/force_plate.csv", format::CsvOptions{});
  EXPECT_EQ(raw.rows(), plate->samples) << "every reading the driver delivered is recorded";
  EXPECT_GT(plate->samples, 1000U);
  EXPECT_GT(plate->errors, 0U) << "cut answers are reported";
  EXPECT_GT(plate->device_faults, 50U) << "0.3 s of flagged readings at 500 Hz";
  std::size_t rows = 0;
  const std::size_t flagged = test::device_fault_samples(o.out, rows);
  EXPECT_GT(flagged, 5U);
  EXPECT_LT(flagged, rows / 2);
  EXPECT_NE(test::read_text(o.out + "/run.yaml").find("ati_netft_can"), std::string::npos);
  // The CAN frames both ways are recorded as candump -L beside the readings.
  EXPECT_NE(test::read_text(o.out + "/raw/force_plate.candump.log").find(" 120#02"), std::string::npos);
}
