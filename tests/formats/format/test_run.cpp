#include <gtest/gtest.h>

#include <hil/format/run.hpp>
#include <hil/test/files.hpp>

using hil::test::fails_with;

namespace {
const std::string kInfo = "format_version: 1\nrig: press_bench\nstart_time: 2026-11-21T09:00:00.000Z\noutput_rate_hz: 50\n";
}

TEST(Run, ShippedExampleLoads) {
  const auto run = hil::format::load_run(std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide");
  EXPECT_EQ(run.info.rig, "press_bench");
  ASSERT_TRUE(run.rig.has_value());
  EXPECT_GT(run.samples.size(), 300u);
  const auto s = hil::format::summarize(run.samples);
  EXPECT_NEAR(s.rate_hz, 50.0, 1e-6);
  EXPECT_TRUE(s.gaps.empty());
}

TEST(Run, InfoFields) {
  const auto info = hil::format::parse_run_info(kInfo + "sources:\n  - {name: fp, kind: can, rate_hz: 1000}\n", "run.yaml");
  EXPECT_EQ(info.sources.at(0).kind, "can");
  EXPECT_TRUE(fails_with([] { hil::format::parse_run_info(kInfo + "sources:\n  - {name: fp, kind: usb}\n", "run.yaml"); }, 6,
                         "sources[0].kind", "expected can, modbus"));
  EXPECT_TRUE(
      fails_with([] { hil::format::parse_run_info("format_version: 1\nrig: x\nstart_time: yesterday\noutput_rate_hz: 50\n", "run.yaml"); },
                 3, "start_time", "ISO 8601"));
  EXPECT_TRUE(fails_with([] { hil::format::parse_run_info("format_version: 1\nrig: x\nstart_time: 2026-11-21T09:00:00Z\n", "run.yaml"); },
                         0, "output_rate_hz", "required field is missing"));
  EXPECT_TRUE(fails_with([] { hil::format::parse_run_info(kInfo + "output_rate: 5\n", "run.yaml"); }, 5, "output_rate",
                         "did you mean 'output_rate_hz'"));
}

TEST(Run, Iso8601) {
  EXPECT_TRUE(hil::format::is_iso8601_utc("2026-11-21T10:00:00Z"));
  EXPECT_TRUE(hil::format::is_iso8601_utc("2026-11-21T10:00:00.123456Z"));
  EXPECT_FALSE(hil::format::is_iso8601_utc("2026-11-21 10:00:00Z"));
  EXPECT_FALSE(hil::format::is_iso8601_utc("2026-13-21T10:00:00Z"));
  EXPECT_FALSE(hil::format::is_iso8601_utc("2026-11-21T10:00:00+01:00"));
}

TEST(Run, WriteInfoRoundTrips) {
  hil::test::TempDir dir;
  hil::format::RunInfo info;
  info.rig = "r";
  info.start_time_utc = "2026-11-21T10:00:00.5Z";
  info.output_rate_hz = 50;
  info.sources.push_back({"force_plate", "can", 1000, "raw/force_plate.log"});
  info.notes = "two\nlines";
  hil::format::write_run_info(dir.path() + "/run.yaml", info);
  const auto back = hil::format::load_run_info(dir.path() + "/run.yaml");
  EXPECT_EQ(back.rig, "r");
  EXPECT_EQ(back.sources.at(0).raw, "raw/force_plate.log");
  EXPECT_EQ(back.notes.substr(0, 9), "two\nlines");
}

TEST(Run, DeviceIdentityRoundTripsAsText) {
  hil::test::TempDir dir;
  hil::format::RunInfo info;
  info.rig = "r";
  info.start_time_utc = "2026-11-21T10:00:00.5Z";
  info.output_rate_hz = 50;
  info.sources.push_back({"force_plate", "can", 1000, "", {{"serial", "0123"}, {"firmware", "1.10"}, {"units", "N, N m"}}});
  info.sources.push_back({"robot", "modbus", 125, "", {}});
  hil::format::write_run_info(dir.path() + "/run.yaml", info);
  const auto back = hil::format::load_run_info(dir.path() + "/run.yaml");
  // A serial with a leading zero and a firmware like 1.10 stay the same text, in the same order.
  EXPECT_EQ(back.sources.at(0).identity, info.sources.at(0).identity);
  EXPECT_TRUE(back.sources.at(1).identity.empty());
}

TEST(Run, DeviceIdentityMustBeAMapOfValues) {
  const std::string src = kInfo + "sources:\n  - name: fp\n    kind: can\n    identity:\n";
  const auto ok = hil::format::parse_run_info(src + "      serial: FT-1\n      counts_per_force: 1000000\n", "run.yaml");
  EXPECT_EQ(ok.sources.at(0).identity.at(1).second, "1000000");
  EXPECT_TRUE(fails_with([&] { hil::format::parse_run_info(src + "      serial: [1, 2]\n", "run.yaml"); }, 9, "sources[0].identity.serial",
                         "expected a single value"));
  EXPECT_TRUE(fails_with([&] { hil::format::parse_run_info(src + "      bad key: x\n", "run.yaml"); }, 0, "sources[0].identity",
                         "identity keys are names"));
  EXPECT_TRUE(fails_with([&] { hil::format::parse_run_info(kInfo + "sources:\n  - {name: fp, kind: can, identity: FT-1}\n", "run.yaml"); },
                         0, "sources[0].identity", "expected a mapping"));
}

TEST(Run, MissingPartsAndRigMismatch) {
  hil::test::TempDir dir;
  EXPECT_TRUE(fails_with([&] { hil::format::load_run(dir.path()); }, 0, "", "needs run.yaml"));
  dir.file("run.yaml", kInfo);
  EXPECT_TRUE(fails_with([&] { hil::format::load_run(dir.path()); }, 0, "", "needs samples.csv"));
  dir.file("samples.csv", "t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,mx,my,mz\n0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_EQ(hil::format::load_run(dir.path()).samples.size(), 1u);
  const auto rig = dir.file("other.yaml", "format_version: 1\nname: other_rig\n");
  EXPECT_TRUE(fails_with([&] { hil::format::load_run(dir.path(), rig); }, 0, "rig", "describes 'other_rig'"));
}
