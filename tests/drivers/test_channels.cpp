// The in-process loopback bus and the candump -L log channel.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <filesystem>
#include <fstream>

#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/candump.hpp>
#include <hil/drivers/error.hpp>

using namespace hil::drivers;
using namespace std::chrono_literals;

namespace {

CanFrame frame(std::uint32_t id, std::uint8_t len = 2, bool ext = false) {
  CanFrame f;
  f.id = id;
  f.extended = ext;
  f.len = len;
  for (unsigned i = 0; i < len; ++i) f.data[i] = static_cast<std::uint8_t>(id + i);
  return f;
}

std::string temp_path(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto dir = std::filesystem::path(HIL_BINARY_DIR) / "test-tmp" / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

}  // namespace

TEST(Loopback, DeliversToOthersNotToSelf) {
  auto bus = CanLoopbackBus::create("loopA");
  auto a = bus->open();
  auto b = bus->open();
  ASSERT_EQ(a->send(frame(0x10), 1ms), IoStatus::ok);
  CanFrame got;
  ASSERT_EQ(b->receive(got, 1s), IoStatus::ok);
  EXPECT_TRUE(same_frame(got, frame(0x10)));
  EXPECT_EQ(got.stamp, StampSource::software);
  EXPECT_GT(got.t_ns, 0);
  EXPECT_EQ(a->receive(got, 0ns), IoStatus::timeout);
  EXPECT_EQ(a->stats().tx_frames, 1U);
  EXPECT_EQ(b->stats().rx_frames, 1U);
  EXPECT_EQ(b->name(), "loopA");
}

TEST(Loopback, ReceiveOwnFiltersAndErrorMask) {
  auto bus = CanLoopbackBus::create();
  CanChannelOptions own;
  own.receive_own = true;
  auto a = bus->open(own);
  CanChannelOptions filtered;
  filtered.filters = {CanFilter::masked(0x100, 0x7F0)};
  filtered.error_mask = kErrBusOff;
  auto b = bus->open(filtered);
  a->send(frame(0x105), 1ms);
  a->send(frame(0x205), 1ms);
  a->send(frame(0x105, 1, true), 1ms);
  a->send(make_error_frame(kErrCrtl), 1ms);
  a->send(make_error_frame(kErrBusOff), 1ms);
  CanFrame got;
  ASSERT_EQ(b->receive(got, 1s), IoStatus::ok);
  EXPECT_EQ(got.id, 0x105U);
  ASSERT_EQ(b->receive(got, 1s), IoStatus::ok);
  EXPECT_TRUE(got.error);
  EXPECT_EQ(got.id, kErrBusOff);
  EXPECT_EQ(b->receive(got, 0ns), IoStatus::timeout);
  EXPECT_EQ(b->stats().error_frames, 1U);
  int own_count = 0;
  while (a->receive(got, 0ns) == IoStatus::ok) ++own_count;
  EXPECT_EQ(own_count, 5);
}

TEST(Loopback, FullQueueCountsDrops) {
  auto bus = CanLoopbackBus::create();
  auto a = bus->open();
  CanChannelOptions small;
  small.rx_queue = 4;
  auto b = bus->open(small);
  for (int i = 0; i < 10; ++i) a->send(frame(0x1), 1ms);
  EXPECT_EQ(b->stats().rx_dropped, 6U);
}

TEST(Loopback, InvalidFramesAndFdPolicy) {
  auto bus = CanLoopbackBus::create();
  CanChannelOptions classic;
  classic.fd = false;
  auto a = bus->open(classic);
  auto b = bus->open();
  CanFrame bad = frame(0x800);
  EXPECT_EQ(a->send(bad, 1ms), IoStatus::error);
  EXPECT_NE(a->last_error().find("0x7FF"), std::string::npos);
  CanFrame fd = frame(0x1, 12);
  fd.fd = true;
  EXPECT_EQ(a->send(fd, 1ms), IoStatus::error);
  EXPECT_EQ(b->send(fd, 1ms), IoStatus::ok);
  CanFrame got;
  EXPECT_EQ(a->receive(got, 0ns), IoStatus::timeout);  // classic endpoint does not see FD frames
}

TEST(Loopback, CloseWakesReceivers) {
  auto bus = CanLoopbackBus::create();
  auto a = bus->open();
  std::thread t([&] { bus->close(); });
  CanFrame got;
  EXPECT_EQ(a->receive(got, 10s), IoStatus::closed);
  t.join();
}

TEST(CandumpLogChannel, WritesAndReadsBackExactly) {
  const std::string path = temp_path("bus.log");
  std::vector<CanFrame> frames;
  {
    CanLogOptions o;
    o.interface = "vcan0";
    auto w = CanLogChannel::open_write(path, o);
    for (int i = 0; i < 50; ++i) {
      CanFrame f = frame(static_cast<std::uint32_t>(0x100 + i), static_cast<std::uint8_t>(i % 9), i % 3 == 0);
      f.t_ns = 1700000000000000000LL + i * 1000000LL + 123000;
      if (i % 7 == 0) {
        f.fd = true;
        f.len = 16;
        f.fd_flags = 1;
      }
      if (i == 5) f = make_error_frame(kErrBusOff), f.t_ns = 1700000000005000000LL;
      frames.push_back(f);
      ASSERT_EQ(w->send(f, 0ns), IoStatus::ok) << w->last_error();
    }
    EXPECT_EQ(w->stats().tx_frames, 50U);
    CanFrame dummy;
    EXPECT_EQ(w->receive(dummy, 0ns), IoStatus::closed);
  }
  auto r = CanLogChannel::open_read(path);
  CanFrame got;
  for (const auto& f : frames) {
    ASSERT_EQ(r->receive(got, 0ns), IoStatus::ok) << r->last_error();
    EXPECT_TRUE(same_frame(f, got));
    EXPECT_EQ(got.t_ns, f.t_ns);
    EXPECT_EQ(r->last_interface(), "vcan0");
  }
  EXPECT_EQ(r->receive(got, 0ns), IoStatus::closed);
  EXPECT_EQ(r->send(frames[0], 0ns), IoStatus::error);
  // Line by line, the file is what format_candump_line writes.
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "(1700000000.000123) vcan0 00000100##1" + std::string(32, '0'));
}

TEST(CandumpLogChannel, BadLineIsReportedWithFileAndLineThenSkipped) {
  const std::string path = temp_path("bad.log");
  std::ofstream(path) << "(1.000001) can0 123#11\n\n(1.000002) can0 123#1\n(1.000003) can1 456#\n(1.000004) can0 789#AA\n";
  CanLogOptions o;
  o.interface = "can0";
  auto r = CanLogChannel::open_read(path, o);
  CanFrame got;
  ASSERT_EQ(r->receive(got, 0ns), IoStatus::ok);
  EXPECT_EQ(got.id, 0x123U);
  ASSERT_EQ(r->receive(got, 0ns), IoStatus::error);
  EXPECT_EQ(r->last_error(), path + ":3: frame at column 17: column 5: odd number of hex digits in the data");
  ASSERT_EQ(r->receive(got, 0ns), IoStatus::ok);  // line 4 is can1: skipped
  EXPECT_EQ(got.id, 0x789U);
  EXPECT_EQ(r->receive(got, 0ns), IoStatus::closed);
}

TEST(CandumpLogChannel, MissingFileThrows) {
  EXPECT_THAT(
      [] { CanLogChannel::open_read("/nonexistent/x.log"); },
      ::testing::ThrowsMessage<DeviceError>(::testing::HasSubstr("candump log /nonexistent/x.log: cannot open for reading: No such file")));
}

TEST(RecordingChannel, RecordsBothDirectionsInCandumpFormat) {
  const std::string path = temp_path("rec.log");
  auto bus = CanLoopbackBus::create();
  auto peer = bus->open();
  {
    CanLogOptions o;
    o.interface = "can7";
    CanRecordingChannel rec(bus->open(), CanLogChannel::open_write(path, o));
    ASSERT_EQ(rec.send(frame(0x10), 1ms), IoStatus::ok);
    peer->send(frame(0x20, 8, true), 1ms);
    CanFrame got;
    ASSERT_EQ(rec.receive(got, 1s), IoStatus::ok);
    EXPECT_EQ(got.id, 0x20U);
    EXPECT_EQ(rec.log_failures(), 0U);
    rec.log().flush();
  }
  auto r = CanLogChannel::open_read(path);
  CanFrame got;
  ASSERT_EQ(r->receive(got, 0ns), IoStatus::ok);
  EXPECT_TRUE(same_frame(got, frame(0x10)));
  ASSERT_EQ(r->receive(got, 0ns), IoStatus::ok);
  EXPECT_TRUE(same_frame(got, frame(0x20, 8, true)));
  EXPECT_EQ(r->last_interface(), "can7");
  EXPECT_EQ(r->receive(got, 0ns), IoStatus::closed);
}
