#include <gtest/gtest.h>

#include <hil/acquisition/monitor.hpp>

using namespace hil::acquisition;

namespace {
constexpr std::int64_t ms = 1'000'000;
}

TEST(Monitor, SilenceIsSeenWithinThreePeriodsAndRecovers) {
  DeviceMonitor m("force_plate", 1000.0);
  std::int64_t t = 0;
  for (; t < 100 * ms; t += ms) {
    m.sample(t);
    m.update(t);
  }
  EXPECT_EQ(m.state(), DeviceState::ok);
  const std::int64_t last = t - ms;
  // The device goes silent; update() runs every millisecond.
  std::int64_t seen = -1;
  for (std::int64_t now = last + ms; now < last + 20 * ms; now += ms) {
    if (m.update(now) && m.state() == DeviceState::degraded) {
      seen = now;
      break;
    }
  }
  ASSERT_GE(seen, 0);
  EXPECT_LE(seen - last, 4 * ms) << "reported after " << (seen - last) / ms << " ms";
  EXPECT_NE(m.reason().find("silent"), std::string::npos);
  m.sample(last + 50 * ms);
  EXPECT_TRUE(m.update(last + 50 * ms));
  EXPECT_EQ(m.state(), DeviceState::ok);
}

TEST(Monitor, FaultHoldsUntilSamplesFlowAgain) {
  DeviceMonitor m("force_plate", 1000.0);
  m.sample(0);
  m.update(0);
  m.error("bus-off", 1 * ms);
  EXPECT_TRUE(m.update(1 * ms));
  EXPECT_EQ(m.state(), DeviceState::fault);
  EXPECT_EQ(m.health(1 * ms).last_error, "bus-off");
  m.sample(2 * ms);
  m.update(2 * ms);
  EXPECT_EQ(m.state(), DeviceState::fault) << "one sample right after the fault is not recovery";
  m.sample(3 * ms);
  m.update(3 * ms);
  EXPECT_EQ(m.state(), DeviceState::ok);
  EXPECT_EQ(m.health(3 * ms).errors, 1u);
}

TEST(Monitor, DropsAndLinkLoss) {
  DeviceMonitor m("robot", 125.0);
  m.sample(0);
  m.update(0);
  EXPECT_EQ(m.state(), DeviceState::ok);
  m.dropped(1, 1 * ms);
  m.sample(2 * ms);
  EXPECT_FALSE(m.update(2 * ms)) << "one lost reading in a second is tolerated at 125 Hz";
  m.dropped(6, 3 * ms);
  m.sample(4 * ms);
  EXPECT_TRUE(m.update(4 * ms)) << "7 lost in a second is over 5 % of 125 Hz";
  EXPECT_EQ(m.state(), DeviceState::degraded);
  EXPECT_NE(m.reason().find("7 readings lost"), std::string::npos) << m.reason();
  EXPECT_EQ(m.health(4 * ms).frames_dropped, 7u);
  m.sample(1100 * ms);
  EXPECT_TRUE(m.update(1100 * ms)) << "a second later the losses are forgotten";
  EXPECT_EQ(m.state(), DeviceState::ok);
  m.link(false, 1101 * ms);
  m.update(1101 * ms);
  EXPECT_EQ(m.state(), DeviceState::disconnected);
  const auto h = m.health(2200 * ms);
  EXPECT_FALSE(h.connected);
  EXPECT_DOUBLE_EQ(h.rate_hz, 0.0);
}

TEST(StateLog, AFlappingDeviceIsLoggedOncePerWindowAndEndsOnItsState) {
  StateLog log(1.0);
  int held = -1;
  EXPECT_TRUE(log.change(DeviceState::degraded, 0, held));  // the first change is logged
  EXPECT_EQ(held, 0);
  // Flapping between ok and degraded within the second: held back, counted.
  EXPECT_FALSE(log.change(DeviceState::ok, 10 * ms, held));
  EXPECT_FALSE(log.change(DeviceState::degraded, 20 * ms, held));
  EXPECT_FALSE(log.change(DeviceState::ok, 30 * ms, held));
  // A fault or a lost link is always logged, with the count held back so far.
  EXPECT_TRUE(log.change(DeviceState::fault, 40 * ms, held));
  EXPECT_EQ(held, 3);
  EXPECT_FALSE(log.change(DeviceState::ok, 50 * ms, held));
  EXPECT_FALSE(log.flush(500 * ms, held)) << "not before the window has passed";
  EXPECT_TRUE(log.flush(1050 * ms, held)) << "the log must end on the current state (ok)";
  EXPECT_EQ(held, 1);
  EXPECT_FALSE(log.flush(3000 * ms, held)) << "nothing held back";
  EXPECT_TRUE(log.change(DeviceState::degraded, 3100 * ms, held));  // a new window
  EXPECT_EQ(held, 0);
}

TEST(StateLog, TheSameFaultRepeatedIsLoggedOncePerWindowAnotherAtOnce) {
  StateLog log(1.0);
  int held = -1;
  const std::string corrupt = "bad frame: gauge frame 1 (id 0x000) has length 5, expected 8";
  EXPECT_TRUE(log.change(DeviceState::fault, 0, held, corrupt));
  // The plate recovers and fails again for the same reason, many times a second: held back.
  for (int k = 1; k <= 20; ++k) {
    EXPECT_FALSE(log.change(DeviceState::ok, (10 * k - 5) * ms, held, ""));
    EXPECT_FALSE(log.change(DeviceState::fault, 10 * k * ms, held, corrupt)) << k;
  }
  // Another fault is news: logged at once, with what was held back.
  EXPECT_TRUE(log.change(DeviceState::fault, 250 * ms, held, "bus error: bus-off"));
  EXPECT_EQ(held, 40);
  EXPECT_TRUE(log.change(DeviceState::disconnected, 260 * ms, held, "not connected"));
  // The same fault again after the window: logged.
  EXPECT_TRUE(log.change(DeviceState::fault, 1300 * ms, held, corrupt));
}
