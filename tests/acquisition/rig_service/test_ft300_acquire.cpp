// A run recorded through a Robotiq FT 300, as `hil acquire --play` does it: the fake sensor on a
// pseudo-terminal plays the shipped example run. Streaming (the rig allows the stream-start write)
// with frames dropped and corrupted and a silence: every reading the driver delivered is in the
// recording and the losses are counted. Read-only (no write allowed) with a burst of Modbus
// exceptions: the samples across the burst are device faults, the others are not.
#include <gtest/gtest.h>

#include <hil/acquisition/streams.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/rig_service/acquire.hpp>
#include <hil/test/files.hpp>
#include "bench_rigs.hpp"

using namespace hil;

TEST(Ft300Acquire, AStreamedRunLosesNothingDeliveredAndCountsWhatTheLineLost) {
  test::TempDir tmp;
  auto o = test::played_options(tmp, test::bench_with_plate(tmp, "ft300_bench.yaml",
                                                            "    protocol: robotiq_ft300\n    serial_device: /dev/ttyUSB0\n"
                                                            "    allowed_writes: [stream_start]\n    rate_hz: 100\n"));
  o.output_rate_hz = 50.0;
  o.stream_faults.drop_fraction = 0.03;
  o.stream_faults.corrupt_fraction = 0.03;
  o.stream_faults.silent.push_back({1.5, 0.2});
  const auto r = rig_service::run_acquisition(o, nullptr);
  ASSERT_GT(r.samples, 60U);
  const auto& plate = test::plate_health(r);
  const auto raw = format::read_csv(o.out + "/raw/force_plate.csv", format::CsvOptions{});
  EXPECT_EQ(raw.rows(), plate.samples) << "every reading the driver delivered is recorded";
  EXPECT_GT(plate.samples, 200U);
  EXPECT_GT(plate.frames_dropped, 3U) << "frames lost on the line and the silence are counted";
  EXPECT_GT(plate.errors, 0U) << "corrupt frames are reported";
  const auto run = format::load_run(o.out);
  bool serial = false;
  for (const auto& s : run.info.sources) serial = serial || (s.name == "force_plate" && s.kind == "serial" && s.rate_hz == 100.0);
  EXPECT_TRUE(serial);
  const auto yaml = test::read_text(o.out + "/run.yaml");
  EXPECT_NE(yaml.find("robotiq_ft300"), std::string::npos);
  EXPECT_NE(yaml.find("FTS-3.1.4"), std::string::npos) << "the sensor's firmware is the run's identity";
}

TEST(Ft300Acquire, ReadOnlyRunMarksTheSamplesAcrossAModbusExceptionBurst) {
  test::TempDir tmp;
  auto o = test::played_options(tmp, test::bench_with_plate(tmp, "ft300_ro.yaml",
                                                            "    protocol: robotiq_ft300\n    serial_device: /dev/ttyUSB0\n"));
  o.output_rate_hz = 25.0;  // divides the 50 Hz polling
  o.plate_modbus_faults.exception_windows.push_back({1.2, 0.3});
  const auto r = rig_service::run_acquisition(o, nullptr);
  const auto& plate = test::plate_health(r);
  EXPECT_GT(plate.device_faults, 5U) << "each refused poll is a device fault";
  std::size_t rows = 0;
  const std::size_t flagged = test::device_fault_samples(o.out, rows);
  ASSERT_GT(rows, 40U);
  EXPECT_GE(flagged, 1U) << "the samples across the burst";
  EXPECT_LT(flagged, rows / 4) << "only those";
}
