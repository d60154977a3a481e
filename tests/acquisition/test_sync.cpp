#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <cmath>
#include <vector>

#include <hil/acquisition/sync.hpp>

using namespace hil::acquisition;

namespace {
constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // an epoch time, as the kernel stamps give
constexpr double kPi = 3.14159265358979323846;

PoseReading pose_at(std::int64_t t_ns, std::uint64_t seq) {
  // Linear motion along x at 0.1 m/s and a constant rotation about z at 0.5 rad/s.
  const double t = (t_ns - kT0) * 1e-9;
  PoseReading p;
  p.t_ns = t_ns;
  p.seq = seq;
  p.p_world_ee_m = {0.1 * t, 0.2, 0.3};
  p.q_world_ee = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * t, Eigen::Vector3d::UnitZ()));
  p.joints_rad = Eigen::VectorXd::Constant(2, t);
  return p;
}
}  // namespace

TEST(Sync, RatesMustDivide) {
  EXPECT_THAT(
      [] {
        Synchronizer({1000.0, 300.0}, [](const SyncedSample&) {});
      },
      ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("the output rate must divide the force-plate rate (1000")));
  EXPECT_NO_THROW(Synchronizer({1000.0, 50.0}, [](const SyncedSample&) {}));
}

TEST(Sync, FilterHasUnitDcGainAndRemovesAliases) {
  std::vector<SyncedSample> out;
  Synchronizer sync({1000.0, 50.0}, [&](const SyncedSample& s) { out.push_back(s); });
  ASSERT_EQ(sync.decimation(), 20);
  // A constant 10 N plus a 200 Hz, 5 N disturbance: well above the 25 Hz output Nyquist rate.
  for (int i = 0; i < 2000; ++i) {
    const std::int64_t t = kT0 + i * 1'000'000LL;
    if (i % 8 == 0) sync.push_pose(pose_at(t, static_cast<std::uint64_t>(i / 8)));
    WrenchReading w;
    w.t_ns = t;
    w.seq = static_cast<std::uint64_t>(i);
    w.wrench_fp(2) = 10.0 + 5.0 * std::sin(2 * kPi * 200.0 * i * 1e-3);
    sync.push_wrench(w);
  }
  sync.flush();
  ASSERT_GT(out.size(), 90u);
  for (const auto& s : out) EXPECT_NEAR(s.wrench_fp(2), 10.0, 0.05) << "alias not removed at index " << s.index;
  // Output times are spaced by the output period and indices count up from 0.
  for (std::size_t i = 1; i < out.size(); ++i) {
    EXPECT_EQ(out[i].t_ns - out[i - 1].t_ns, 20'000'000);
    EXPECT_EQ(out[i].index, i);
  }
}

TEST(Sync, PoseInterpolationAndTwist) {
  std::vector<SyncedSample> out;
  Synchronizer sync({1000.0, 50.0}, [&](const SyncedSample& s) { out.push_back(s); });
  for (int i = 0; i < 1000; ++i) {
    const std::int64_t t = kT0 + i * 1'000'000LL;
    // Robot polled at 125 Hz with a 3 ms offset: pose times never coincide with sample times.
    if (i % 8 == 3) sync.push_pose(pose_at(t, static_cast<std::uint64_t>(i)));
    WrenchReading w;
    w.t_ns = t;
    sync.push_wrench(w);
  }
  ASSERT_GT(out.size(), 40u);
  for (const auto& s : out) {
    if (s.quality & kPoseExtrapolated) continue;
    const auto truth = pose_at(s.t_ns, 0);
    EXPECT_NEAR((s.p_world_ee_m - truth.p_world_ee_m).norm(), 0.0, 1e-12);
    EXPECT_NEAR(s.q_world_ee.angularDistance(truth.q_world_ee), 0.0, 1e-9);
    EXPECT_NEAR(s.joints_rad(1), truth.joints_rad(1), 1e-12);
    EXPECT_NEAR((s.v_world_ee_m_per_s - Eigen::Vector3d(0.1, 0, 0)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((s.w_world_ee_rad_per_s - Eigen::Vector3d(0, 0, 0.5)).norm(), 0.0, 1e-6);
    EXPECT_LE(s.pose_age_s, 0.004 + 1e-12);
  }
  EXPECT_EQ(out.front().quality & kPoseStale, 0u);
}

TEST(Sync, GapRestartsFilterAndIsFlagged) {
  std::vector<SyncedSample> out;
  Synchronizer sync({1000.0, 50.0}, [&](const SyncedSample& s) { out.push_back(s); });
  for (int i = 0; i < 1000; ++i) {
    if (i >= 400 && i < 460) continue;  // 60 frames lost: longer than the 50 ms that are bridged
    const std::int64_t t = kT0 + i * 1'000'000LL;
    if (i % 8 == 0) sync.push_pose(pose_at(t, 0));
    WrenchReading w;
    w.t_ns = t;
    w.wrench_fp(0) = 1.0;
    sync.push_wrench(w);
  }
  sync.flush();
  EXPECT_EQ(sync.wrench_gaps(), 1u);
  int flagged = 0;
  for (const auto& s : out) {
    if (s.quality & kGapBefore) {
      ++flagged;
      EXPECT_GT(s.t_ns, kT0 + 460'000'000LL);
    }
    EXPECT_NEAR(s.wrench_fp(0), 1.0, 1e-12);
  }
  EXPECT_EQ(flagged, 1);
}

TEST(Sync, JitterAndShortGapsAreBridgedOnAUniformGrid) {
  std::vector<SyncedSample> out;
  Synchronizer sync({1000.0, 50.0}, [&](const SyncedSample& s) { out.push_back(s); });
  std::uint64_t lcg = 12345;
  for (int i = 0; i < 1000; ++i) {
    if (i >= 500 && i < 505) continue;  // 5 frames lost: bridged, not a restart
    lcg = lcg * 6364136223846793005ULL + 1442695040888963407ULL;
    const std::int64_t jitter = static_cast<std::int64_t>((lcg >> 33) % 1500000) - 750000;  // +-0.75 ms
    const std::int64_t t = kT0 + i * 1'000'000LL + jitter;
    if (i % 8 == 0) sync.push_pose(pose_at(t, 0));
    WrenchReading w;
    w.t_ns = t;
    w.wrench_fp(1) = 2.0;
    sync.push_wrench(w);
  }
  sync.flush();
  ASSERT_GE(out.size(), 45u) << "jitter must not starve the output";
  int flagged = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_NEAR(out[i].wrench_fp(1), 2.0, 1e-12);
    if (i > 0) {
      EXPECT_EQ(out[i].t_ns - out[i - 1].t_ns, 20000000) << "output times are exactly uniform";
    }
    flagged += (out[i].quality & kGapBefore) != 0;
  }
  EXPECT_EQ(flagged, 1);
}

TEST(Sync, MissingPoseTimesOutAndIsFlagged) {
  std::vector<SyncedSample> out;
  SyncConfig cfg{1000.0, 100.0};
  cfg.pose_timeout_s = 0.05;
  Synchronizer sync(cfg, [&](const SyncedSample& s) { out.push_back(s); });
  for (int i = 0; i < 500; ++i) {
    const std::int64_t t = kT0 + i * 1'000'000LL;
    if (i < 100 && i % 8 == 0) sync.push_pose(pose_at(t, 0));  // the robot goes silent at 0.1 s
    WrenchReading w;
    w.t_ns = t;
    sync.push_wrench(w);
  }
  ASSERT_FALSE(out.empty());
  // Nothing is held back for longer than the timeout: outputs keep coming while the robot is silent.
  EXPECT_GT(out.back().t_ns, kT0 + 400'000'000LL);
  EXPECT_TRUE(out.back().quality & kPoseExtrapolated);
  EXPECT_TRUE(out.back().quality & kPoseStale);
  EXPECT_GT(out.back().pose_age_s, 0.2);
}

TEST(Sync, SamplesAcrossARefusedPollAreDeviceFaultsAndOnlyThose) {
  // The robot answers every 8 ms, refuses (Modbus exceptions) from 200 ms to 300 ms, then answers
  // again. The samples whose pose spans the refusal are device faults; those well before and
  // after are not.
  std::vector<SyncedSample> out;
  Synchronizer sync({1000.0, 100.0}, [&](const SyncedSample& s) { out.push_back(s); });
  for (int i = 0; i < 600; ++i) {
    const std::int64_t t = kT0 + i * 1'000'000LL;
    if (i % 8 == 0) {
      if (i >= 200 && i < 300) sync.pose_refused();
      else sync.push_pose(pose_at(t, static_cast<std::uint64_t>(i)));
    }
    WrenchReading w;
    w.t_ns = t;
    sync.push_wrench(w);
  }
  sync.flush();
  ASSERT_GT(out.size(), 50u);
  int faults = 0;
  for (const auto& s : out) {
    const double t_ms = (s.t_ns - kT0) * 1e-6;
    const bool fault = (s.quality & kDeviceFault) != 0;
    faults += fault ? 1 : 0;
    // The last pose before the refusal is at 192 ms, the first after it at 304 ms.
    if (t_ms > 193.0 && t_ms < 303.0) {
      EXPECT_TRUE(fault) << "sample at " << t_ms << " ms spans the refusal";
    }
    if (t_ms < 191.0 || t_ms > 305.0) {
      EXPECT_FALSE(fault) << "sample at " << t_ms << " ms was read normally";
    }
  }
  EXPECT_GE(faults, 10);
}
