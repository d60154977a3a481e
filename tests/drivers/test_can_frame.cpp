// Pure frame codecs: the kernel byte layout, validation, filters, error frames.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include <hil/drivers/can_frame.hpp>

using namespace hil::drivers;

namespace {

CanFrame data_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes, bool ext = false) {
  CanFrame f;
  f.id = id;
  f.extended = ext;
  for (auto b : bytes) f.data[f.len++] = b;
  return f;
}

std::array<std::uint8_t, kCanFdMtu> encode(const CanFrame& f, std::size_t& n) {
  std::array<std::uint8_t, kCanFdMtu> buf{};
  n = encode_kernel_frame(f, std::span<std::uint8_t, kCanFdMtu>(buf));
  return buf;
}

}  // namespace

TEST(CanKernelCodec, ClassicLayoutIsTheKernelsStruct) {
  std::size_t n = 0;
  const auto buf = encode(data_frame(0x123, {0xDE, 0xAD, 0xBE, 0xEF}), n);
  ASSERT_EQ(n, kCanMtu);
  std::uint32_t id;
  std::memcpy(&id, buf.data(), 4);
  EXPECT_EQ(id, 0x123U);
  EXPECT_EQ(buf[4], 4);  // can_dlc
  EXPECT_EQ(buf[8], 0xDE);
  EXPECT_EQ(buf[11], 0xEF);
  EXPECT_EQ(buf[12], 0);
}

TEST(CanKernelCodec, FlagsInTheIdWord) {
  std::size_t n = 0;
  CanFrame f = data_frame(0x1ABCDEF0, {1}, true);
  auto buf = encode(f, n);
  std::uint32_t id;
  std::memcpy(&id, buf.data(), 4);
  EXPECT_EQ(id, 0x1ABCDEF0U | kCanEffFlag);

  CanFrame r;
  r.id = 0x7FF;
  r.rtr = true;
  r.len = 3;
  buf = encode(r, n);
  std::memcpy(&id, buf.data(), 4);
  EXPECT_EQ(id, 0x7FFU | kCanRtrFlag);
  EXPECT_EQ(buf[4], 3);

  buf = encode(make_error_frame(kErrBusOff), n);
  std::memcpy(&id, buf.data(), 4);
  EXPECT_EQ(id, kErrBusOff | kCanErrFlag);
  EXPECT_EQ(buf[4], 8);
}

TEST(CanKernelCodec, FdFrameWithFlags) {
  CanFrame f;
  f.fd = true;
  f.id = 0x456;
  f.fd_flags = 0x3;
  f.len = 12;
  for (int i = 0; i < 12; ++i) f.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i * 17);
  std::size_t n = 0;
  const auto buf = encode(f, n);
  ASSERT_EQ(n, kCanFdMtu);
  EXPECT_EQ(buf[4], 12);
  EXPECT_EQ(buf[5], 0x3);
  CanFrame back;
  ASSERT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), n), back), CanCodecStatus::ok);
  EXPECT_TRUE(same_frame(f, back));
  EXPECT_TRUE(back.fd);
}

TEST(CanKernelCodec, RoundTripOfRandomFrames) {
  std::mt19937 rng(7);
  for (int k = 0; k < 2000; ++k) {
    CanFrame f;
    const int kind = static_cast<int>(rng() % 5);
    f.extended = kind == 1 || (kind == 4 && rng() % 2);
    f.id = f.extended ? rng() & kCanEffMask : rng() & kCanSffMask;
    if (kind == 2) {
      f.rtr = true;
      f.len = static_cast<std::uint8_t>(rng() % 9);
    } else if (kind == 3) {
      f = make_error_frame(rng() & 0x3FF, {1, 2, 3, 4, 5, 6, 7, 8});
    } else if (kind == 4) {
      f.fd = true;
      f.fd_flags = static_cast<std::uint8_t>(rng() & 0xF);
      static const std::uint8_t lens[] = {0, 1, 5, 8, 12, 16, 20, 24, 32, 48, 64};
      f.len = lens[rng() % 11];
      for (unsigned i = 0; i < f.len; ++i) f.data[i] = static_cast<std::uint8_t>(rng());
    } else {
      f.len = static_cast<std::uint8_t>(rng() % 9);
      for (unsigned i = 0; i < f.len; ++i) f.data[i] = static_cast<std::uint8_t>(rng());
    }
    std::size_t n = 0;
    const auto buf = encode(f, n);
    ASSERT_NE(n, 0U) << frame_problem(f);
    CanFrame back;
    ASSERT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), n), back), CanCodecStatus::ok);
    ASSERT_TRUE(same_frame(f, back)) << k;
  }
}

TEST(CanKernelCodec, RejectsBadInput) {
  std::array<std::uint8_t, 72> buf{};
  CanFrame f;
  EXPECT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), 15), f), CanCodecStatus::bad_size);
  buf[4] = 9;
  EXPECT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), 16), f), CanCodecStatus::bad_length);
  buf[4] = 65;
  EXPECT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), 72), f), CanCodecStatus::bad_length);
  buf[4] = 1;
  const std::uint32_t bad_sff = 0x800;  // standard frame with id bits above 0x7FF
  std::memcpy(buf.data(), &bad_sff, 4);
  EXPECT_EQ(decode_kernel_frame(std::span<const std::uint8_t>(buf.data(), 16), f), CanCodecStatus::bad_id);
}

TEST(CanFrameCheck, ProblemsAreNamed) {
  CanFrame f = data_frame(0x800, {});
  EXPECT_STREQ(frame_problem(f), "standard id exceeds 11 bits (0x7FF)");
  f = data_frame(0x20000000, {}, true);
  EXPECT_NE(frame_problem(f), nullptr);
  f = data_frame(0x1, {});
  f.len = 9;
  EXPECT_NE(frame_problem(f), nullptr);
  f.fd = true;
  EXPECT_NE(frame_problem(f), nullptr);  // 9 is no FD length
  f.len = 12;
  EXPECT_EQ(frame_problem(f), nullptr);
  f.rtr = true;
  EXPECT_NE(frame_problem(f), nullptr);
  std::size_t n = 1;
  encode(f, n);
  EXPECT_EQ(n, 0U);
}

TEST(CanFilter, KernelSemantics) {
  const CanFrame a = data_frame(0x120, {});
  const CanFrame b = data_frame(0x12F, {});
  const CanFrame c = data_frame(0x130, {});
  const CanFrame ext = data_frame(0x120, {}, true);
  const std::vector<CanFilter> group{CanFilter::masked(0x120, 0x7F0)};
  EXPECT_TRUE(passes(group, a));
  EXPECT_TRUE(passes(group, b));
  EXPECT_FALSE(passes(group, c));
  EXPECT_FALSE(passes(group, ext));  // the EFF flag is part of the mask
  const std::vector<CanFilter> one{CanFilter::exact(0x120, true)};
  EXPECT_TRUE(passes(one, ext));
  EXPECT_FALSE(passes(one, a));
  CanFilter inv = CanFilter::exact(0x120);
  inv.inverted = true;
  EXPECT_FALSE(passes(std::vector<CanFilter>{inv}, a));
  EXPECT_TRUE(passes(std::vector<CanFilter>{inv}, c));
  EXPECT_TRUE(passes(group, make_error_frame(kErrBusOff)));  // error frames go by the error mask
  EXPECT_TRUE(passes({}, c));
}

TEST(CanErrorFrame, DecodesTheLinuxClasses) {
  auto e = decode_error_frame(make_error_frame(kErrBusOff));
  EXPECT_TRUE(e.bus_off);
  EXPECT_EQ(describe(e), "bus-off");

  e = decode_error_frame(make_error_frame(kErrCrtl | kErrCnt, {0, kErrCrtlRxPassive, 0, 0, 0, 0, 97, 130}));
  EXPECT_TRUE(e.error_passive);
  EXPECT_FALSE(e.bus_off);
  EXPECT_EQ(e.tx_error_count, 97);
  EXPECT_EQ(e.rx_error_count, 130);
  EXPECT_EQ(describe(e), "error-passive, tx errors 97, rx errors 130");

  e = decode_error_frame(make_error_frame(kErrLostArb, {5}));
  EXPECT_EQ(e.lost_arbitration_bit, 5);
  EXPECT_EQ(describe(e), "lost arbitration at bit 5");

  e = decode_error_frame(make_error_frame(kErrRestarted | kErrAck | kErrProt, {0, 0, 0x08, 0x0F}));
  EXPECT_TRUE(e.restarted);
  EXPECT_TRUE(e.no_ack);
  EXPECT_EQ(e.protocol_type, 0x08);
  EXPECT_EQ(describe(e), "protocol violation (type 0x08, location 0x0F), no ACK, controller restarted");

  EXPECT_EQ(decode_error_frame(data_frame(0x40, {})).classes, 0U);  // not an error frame
}
