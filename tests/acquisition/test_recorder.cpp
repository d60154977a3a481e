#include <gtest/gtest.h>
#include <gmock/gmock.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include <hil/test/files.hpp>
#include <hil/acquisition/recorder.hpp>

using namespace hil::acquisition;

namespace {
constexpr std::int64_t kT0 = 1'763'715'600'000'000'000;
SyncedSample sample(std::uint64_t i) {
  SyncedSample s;
  s.t_ns = kT0 + static_cast<std::int64_t>(i) * 1'000'000;
  s.index = i;
  s.p_world_ee_m = {0.001 * static_cast<double>(i), 0, 0};
  s.wrench_fp(2) = -static_cast<double>(i);
  s.joints_rad = Eigen::VectorXd::Constant(2, 0.5);
  if (i == 10) s.quality = kGapBefore;
  return s;
}
hil::format::RunInfo info() {
  hil::format::RunInfo r;
  r.rig = "press_bench";
  r.output_rate_hz = 1000;
  r.sources.push_back({"force_plate", "can", 1000, "raw/force_plate.log"});
  return r;
}
}  // namespace

TEST(Recorder, WritesAReadableRunWithQualityColumns) {
  hil::test::TempDir tmp;
  const auto dir = tmp.path() + "/run";
  {
    RunRecorder rec(dir, info(), "", kT0, 2);
    for (std::uint64_t i = 0; i < 100; ++i) rec.append(sample(i));
    rec.close("samples: 100");
    EXPECT_EQ(rec.gaps(), 1u);
  }
  const auto run = hil::format::load_run(dir);
  ASSERT_EQ(run.samples.size(), 100u);
  EXPECT_EQ(run.info.start_time_utc, "2025-11-21T09:00:00.000000000Z");
  EXPECT_DOUBLE_EQ(run.samples.samples[99].t_s, 0.099);
  EXPECT_DOUBLE_EQ(run.samples.samples[42].f_fp_n.z(), -42.0);
  EXPECT_EQ(run.samples.joint_count(), 2u);
  ASSERT_EQ(run.samples.extra_columns.size(), 3u);
  EXPECT_EQ(run.samples.extra_columns[0], "quality");
  EXPECT_NE(run.info.notes.find("samples: 100"), std::string::npos);
  EXPECT_THAT([&] { RunRecorder(dir, info(), "", kT0, 2); },
              ::testing::ThrowsMessage<std::runtime_error>(::testing::HasSubstr(dir +
                                                                                ": exists and is not empty; refusing to overwrite a run")));
}

TEST(Recorder, KillMinus9LosesAtMostTheLastSecond) {
  hil::test::TempDir tmp;
  const auto dir = tmp.path() + "/run";
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(fds[0]);
    RunRecorder rec(dir, info(), "format_version: 1\nname: press_bench\n", kT0, 2, 1.0);
    // 3.5 s of 1 kHz samples, then tell the parent and wait to be killed.
    for (std::uint64_t i = 0; i < 3500; ++i) rec.append(sample(i));
    char c = 'x';
    if (write(fds[1], &c, 1) != 1) _exit(3);
    for (;;) pause();
  }
  close(fds[1]);
  char c = 0;
  ASSERT_EQ(read(fds[0], &c, 1), 1);
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  const auto run = hil::format::load_run(dir);  // readable: no truncated line, valid yaml
  EXPECT_GE(run.samples.size(), 2500u) << "lost more than the last second";
  EXPECT_LE(run.samples.size(), 3500u);
  ASSERT_TRUE(run.rig.has_value());
  for (std::size_t i = 0; i < run.samples.size(); ++i) ASSERT_DOUBLE_EQ(run.samples.samples[i].f_fp_n.z(), -static_cast<double>(i));
}
