// The declarative CAN force-plate decoder: signal bit layouts (Intel and Motorola), configuration
// errors, and the decoder fed by a device on the loopback bus.
#include <gtest/gtest.h>

#include <random>

#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;
using namespace std::chrono_literals;

namespace {
CanSignal sig(unsigned start, unsigned len, bool big, bool is_signed = false) {
  CanSignal s;
  s.start_bit = start;
  s.length_bits = len;
  s.big_endian = big;
  s.is_signed = is_signed;
  return s;
}
}  // namespace

TEST(SignalBits, IntelAndMotorolaLayouts) {
  const std::uint8_t d[8] = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF0};
  EXPECT_EQ(extract_raw(sig(0, 16, false), d), 0x3412);
  EXPECT_EQ(extract_raw(sig(7, 16, true), d), 0x1234);
  EXPECT_EQ(extract_raw(sig(4, 12, false), d), 0x341);  // bits 4..15
  EXPECT_EQ(extract_raw(sig(3, 12, true), d), 0x234);   // MSB at byte 0 bit 3, then byte 1
  EXPECT_EQ(extract_raw(sig(8, 4, false), d), 0x4);
  EXPECT_EQ(extract_raw(sig(56, 8, false, true), d), -16);  // 0xF0
  EXPECT_EQ(extract_raw(sig(0, 64, false), d), static_cast<std::int64_t>(0xF0DEBC9A78563412ULL));
  EXPECT_EQ(extract_raw(sig(7, 64, true), d), static_cast<std::int64_t>(0x123456789ABCDEF0ULL));
  EXPECT_EQ(extract_raw(sig(7, 16, true, true), std::array<std::uint8_t, 2>{0xFF, 0xFE}.data()), -2);
  EXPECT_EQ(bytes_needed(sig(3, 12, true)), 2U);
  EXPECT_EQ(bytes_needed(sig(60, 8, false)), 9U);
}

TEST(SignalBits, InsertIsTheInverseOfExtract) {
  std::mt19937 rng(3);
  for (int k = 0; k < 5000; ++k) {
    const bool big = rng() % 2 == 0;
    const unsigned len = 1 + rng() % 32;
    CanSignal s = sig(rng() % 64, len, big, rng() % 2 == 0);
    if (bytes_needed(s) == 0 || bytes_needed(s) > 8) continue;
    std::uint8_t d[64];
    for (auto& x : d) x = static_cast<std::uint8_t>(rng());
    std::uint8_t before[64];
    std::copy(d, d + 64, before);
    const std::int64_t lo = s.is_signed ? -(std::int64_t{1} << (len - 1)) : 0;
    const std::int64_t span = std::int64_t{1} << (s.is_signed ? len - 1 : len);
    const std::int64_t v = lo + static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(s.is_signed ? 2 * span : span));
    insert_raw(s, v, d);
    ASSERT_EQ(extract_raw(s, d), v) << s.start_bit << " " << len << " " << big;
    // Only the signal's bits changed.
    insert_raw(s, extract_raw(s, before), d);
    ASSERT_TRUE(std::equal(d, d + 64, before));
  }
}

TEST(SignalConfig, ErrorsNameTheSignalAndField) {
  using hil::test::config_error;
  std::vector<CanSignal> s(2);
  s[0].component = WrenchComponent::fx;
  s[1].component = WrenchComponent::fx;
  EXPECT_TRUE(config_error([&] { validate_signals(s); }, "signals[1].component", "'fx' is decoded twice"));
  s[1].component = WrenchComponent::fy;
  s[1].length_bits = 0;
  EXPECT_TRUE(config_error([&] { validate_signals(s); }, "signals[1].length_bits", "1..64"));
  s[1].length_bits = 16;
  s[1].big_endian = true;
  s[1].start_bit = 511;
  s[1].length_bits = 16;
  EXPECT_TRUE(config_error([&] { validate_signals(s); }, "signals[1].start_bit", "runs outside the frame"));
  s[1] = CanSignal{};
  s[1].component = WrenchComponent::fy;
  s[1].frame_id = 0x800;
  EXPECT_TRUE(config_error([&] { validate_signals(s); }, "signals[1].frame_id", "exceeds 11 bits"));
  s[1].frame_id = 0x10;
  s[1].scale = 0.0;
  EXPECT_TRUE(config_error([&] { validate_signals(s); }, "signals[1].scale", "non-zero"));
  EXPECT_TRUE(config_error([] { validate_signals({}); }, "signals", "at least one signal"));
  EXPECT_TRUE(config_error([] { parse_wrench_component("fq", "signals[3].component"); }, "signals[3].component", "not a wrench component"));
}

namespace {

/// A plate that sends forces in frame 0x100 (3 × int16 LE, 0.1 N) and moments plus status in
/// extended frame 0x18FF0001 (3 × int16 big endian, 1 mN·m; status byte).
ForcePlateConfig declarative_config() {
  ForcePlateConfig c;
  c.protocol = ForcePlateProtocol::declarative;
  c.rate_hz = 1000;
  c.response_timeout_s = 0.5;
  const char* names[] = {"fx", "fy", "fz"};
  for (unsigned i = 0; i < 3; ++i) {
    CanSignal s;
    s.component = parse_wrench_component(names[i], "component");
    s.frame_id = 0x100;
    s.start_bit = 16 * i;
    s.length_bits = 16;
    s.is_signed = true;
    s.scale = 0.1;
    c.signals.push_back(s);
  }
  for (unsigned i = 0; i < 3; ++i) {
    CanSignal s;
    s.component = static_cast<WrenchComponent>(3 + i);
    s.frame_id = 0x18FF0001;
    s.extended_id = true;
    s.start_bit = 7 + 16 * i;
    s.length_bits = 16;
    s.big_endian = true;
    s.scale = 1e-3;
    s.offset = 0.5;
    c.signals.push_back(s);
  }
  CanSignal st;
  st.component = WrenchComponent::status;
  st.frame_id = 0x18FF0001;
  st.extended_id = true;
  st.start_bit = 48;
  st.length_bits = 8;
  st.is_signed = false;
  c.signals.push_back(st);
  return c;
}

std::array<CanFrame, 2> device_frames(const ForcePlateConfig& c, const Vector6d& w, std::uint8_t status) {
  std::array<CanFrame, 2> f;
  f[0].id = 0x100;
  f[0].len = 6;
  f[1].id = 0x18FF0001;
  f[1].extended = true;
  f[1].len = 7;
  for (const auto& s : c.signals) {
    CanFrame& fr = s.frame_id == 0x100 ? f[0] : f[1];
    const double v = s.component == WrenchComponent::status ? status : w[static_cast<int>(s.component)];
    insert_raw(s, static_cast<std::int64_t>(std::llround((v - s.offset) / s.scale)), fr.data.data());
  }
  return f;
}

}  // namespace

TEST(DeclarativePlate, DecodesACompleteFrameSet) {
  auto bus = CanLoopbackBus::create();
  const ForcePlateConfig c = declarative_config();
  auto plate = make_force_plate(c, bus->open());
  auto device = bus->open();
  EXPECT_EQ(plate->start().protocol, "declarative");
  Vector6d w;
  w << 12.3, -45.6, 789.0, 1.234, -0.5, 2.0;
  const auto frames = device_frames(c, w, 0x81);
  device->send(frames[0], 1ms);
  device->send(frames[1], 1ms);
  WrenchSample s;
  ASSERT_EQ(plate->poll(s), PollStatus::ok) << plate->last_problem();
  Vector6d tol;
  tol << 0.05, 0.05, 0.05, 5e-4, 5e-4, 5e-4;
  EXPECT_TRUE(hil::test::near6(s.w_fp, w, tol));
  EXPECT_EQ(s.status_word, 0x81);
  EXPECT_GT(s.t_ns, 0);
  // Half a set is not a sample; the other half completes it.
  device->send(frames[1], 1ms);
  DeclarativeForcePlate* d = dynamic_cast<DeclarativeForcePlate*>(plate.get());
  ASSERT_NE(d, nullptr);
  WrenchSample s2;
  EXPECT_FALSE(d->feed(frames[0], s2));
  EXPECT_TRUE(d->feed(frames[1], s2));
}

TEST(DeclarativePlate, ShortFrameIsABadFrameAndSilenceTimesOut) {
  auto bus = CanLoopbackBus::create();
  ForcePlateConfig c = declarative_config();
  c.response_timeout_s = 0.02;
  auto plate = make_force_plate(c, bus->open());
  auto device = bus->open();
  plate->start();
  auto frames = device_frames(c, Vector6d::Zero(), 0);
  frames[0].len = 4;
  device->send(frames[0], 1ms);
  WrenchSample s;
  EXPECT_EQ(plate->poll(s), PollStatus::bad_frame);
  EXPECT_EQ(plate->last_problem(), "frame 0x100 has 4 bytes, the signals need more");
  EXPECT_EQ(plate->poll(s), PollStatus::timeout);
  device->send(make_error_frame(kErrBusOff), 1ms);
  EXPECT_EQ(plate->poll(s), PollStatus::bus_error);
  EXPECT_TRUE(plate->counters().bus_off);
}
