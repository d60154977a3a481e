// can-utils text formats: frames (cansend/candump) and `candump -L` log lines, bit-exact.
#include <gtest/gtest.h>

#include <random>

#include <hil/drivers/candump.hpp>

using namespace hil::drivers;

namespace {

CanFrame parse_ok(const std::string& text) {
  CanFrame f;
  const std::string e = parse_frame_text(text, f);
  EXPECT_EQ(e, "") << text;
  return f;
}

std::string parse_error(const std::string& text) {
  CanFrame f;
  return parse_frame_text(text, f);
}

}  // namespace

// Each line as can-utils 2020.11 prints it; parse, check the fields, format back to the same text.
TEST(CanFrameText, CanUtilsExamplesRoundTrip) {
  struct Case {
    const char* text;
    std::uint32_t id;
    bool ext, rtr, err, fd;
    unsigned len;
    unsigned flags;
  };
  const Case cases[] = {
      {"123#DEADBEEF", 0x123, false, false, false, false, 4, 0},
      {"1F334455#1122334455667788", 0x1F334455, true, false, false, false, 8, 0},
      {"123#R", 0x123, false, true, false, false, 0, 0},
      {"123#R3", 0x123, false, true, false, false, 3, 0},
      {"00000123#R8", 0x123, true, true, false, false, 8, 0},
      {"7FF#", 0x7FF, false, false, false, false, 0, 0},
      {"00000000#", 0, true, false, false, false, 0, 0},
      {"20000040#0000000000000000", 0x40, false, false, true, false, 8, 0},
      {"20000004#0010000000000000", 0x4, false, false, true, false, 8, 0},
      {"213##1112233", 0x213, false, false, false, true, 3, 1},
      {"213##0", 0x213, false, false, false, true, 0, 0},
      {"1F334455##F00112233445566778899AABB", 0x1F334455, true, false, false, true, 12, 0xF},
  };
  for (const auto& c : cases) {
    const std::string text = c.text;
    const CanFrame f = parse_ok(text);
    EXPECT_EQ(f.id, c.id) << text;
    EXPECT_EQ(f.extended, c.ext) << text;
    EXPECT_EQ(f.rtr, c.rtr) << text;
    EXPECT_EQ(f.error, c.err) << text;
    EXPECT_EQ(f.fd, c.fd) << text;
    EXPECT_EQ(f.len, c.len) << text;
    EXPECT_EQ(f.fd_flags, c.flags) << text;
    EXPECT_EQ(format_frame_text(f), text);
  }
}

TEST(CanFrameText, AcceptsWhatCansendAccepts) {
  // Lower case and '.' separators parse; output is canonical (upper case, no separators).
  EXPECT_EQ(format_frame_text(parse_ok("1ab#de.ad.be.ef")), "1AB#DEADBEEF");
  EXPECT_EQ(format_frame_text(parse_ok("213##1.11.22.33")), "213##1112233");
  EXPECT_EQ(format_frame_text(parse_ok("123#r")), "123#R");
  const CanFrame fd64 = parse_ok("321##4" + std::string(128, 'A'));
  EXPECT_EQ(fd64.len, 64);
  EXPECT_EQ(fd64.fd_flags, 4);
}

TEST(CanFrameText, ErrorsNameWhatAndWhere) {
  EXPECT_EQ(parse_error("12#11"), "identifier: expected 3 hex digits (standard) or 8 (extended) before '#'");
  EXPECT_EQ(parse_error("1G3#11"), "column 2: identifier: 'G' is not a hex digit");
  EXPECT_EQ(parse_error("123#1"), "column 5: odd number of hex digits in the data");
  EXPECT_EQ(parse_error("123#11X2"), "column 7: data: 'X' is not a hex digit");
  EXPECT_EQ(parse_error("123#112233445566778899"), "column 21: more than 8 data bytes");
  EXPECT_EQ(parse_error("800#"), "column 1: standard identifier exceeds 0x7FF");
  EXPECT_EQ(parse_error("123##"), "column 6: CAN FD flags nibble missing after '##'");
  EXPECT_EQ(parse_error("123##0112233445566778899"), "data: 9 bytes is not a CAN FD length (0..8, 12, 16, 20, 24, 32, 48, 64)");
  EXPECT_EQ(parse_error("123#R9"), "column 6: RTR length must be one digit 0..8");
  EXPECT_EQ(parse_error("20000040#R"), "column 10: error frames cannot be RTR");
}

TEST(CandumpLog, LinesRoundTripBitExact) {
  const std::string lines[] = {
      "(1700000000.123456) vcan0 123#DEADBEEF",
      "(0000000001.000001) can1 1F334455#R",
      "(1732184000.999999) vcan0 20000044#0004000000000000",
      "(1732184000.000000) any 456##5112233445566778899AABBCC",
      "(1732184000.000010) vcan0 7FF#R8",
  };
  for (const auto& l : lines) {
    CanFrame f;
    std::string iface;
    ASSERT_EQ(parse_candump_line(l, f, iface), "") << l;
    EXPECT_EQ(format_candump_line(f, iface), l);
  }
  CanFrame f;
  std::string iface;
  ASSERT_EQ(parse_candump_line("(1700000000.123456) vcan0 123#DEADBEEF\n", f, iface), "");
  EXPECT_EQ(f.t_ns, 1700000000123456000LL);
  EXPECT_EQ(iface, "vcan0");
  EXPECT_EQ(f.stamp, StampSource::software);
  // Newer can-utils append a direction flag; accepted.
  ASSERT_EQ(parse_candump_line("(1700000000.123456) vcan0 123#DEADBEEF T", f, iface), "");
}

TEST(CandumpLog, FormatPadsTheTimestampLikeCandump) {
  CanFrame f;
  f.id = 0x1;
  f.t_ns = 42'000'007'999LL;  // truncated to microseconds
  EXPECT_EQ(format_candump_line(f, "vcan0"), "(0000000042.000007) vcan0 001#");
}

TEST(CandumpLog, ErrorsNameTheColumn) {
  CanFrame f;
  std::string iface;
  EXPECT_EQ(parse_candump_line("1700000000.1 vcan0 123#", f, iface), "timestamp: line does not start with '('");
  EXPECT_EQ(parse_candump_line("(1700000000.) vcan0 123#", f, iface), "column 13: timestamp: expected 1 to 6 digits of microseconds");
  EXPECT_EQ(parse_candump_line("(1700000000.1234567) vcan0 123#", f, iface),
            "column 20: timestamp: expected 1 to 6 digits of microseconds");
  EXPECT_EQ(parse_candump_line("(1.5) vcan0", f, iface), "column 7: interface name or frame missing");
  EXPECT_EQ(parse_candump_line("(1.5) vcan0 123#XY", f, iface), "frame at column 13: column 5: data: 'X' is not a hex digit");
  EXPECT_EQ(parse_candump_line("(1.5) vcan0 123#11 junk", f, iface), "column 19: unexpected text after the frame");
}

TEST(CandumpLog, RandomFramesSurviveFormatAndParse) {
  std::mt19937_64 rng(11);
  for (int k = 0; k < 5000; ++k) {
    CanFrame f;
    const auto kind = rng() % 4;
    f.extended = rng() % 2 == 0;
    f.id = static_cast<std::uint32_t>(f.extended ? rng() & kCanEffMask : rng() & kCanSffMask);
    if (kind == 0) {
      f.rtr = true;
      f.len = static_cast<std::uint8_t>(rng() % 9);
    } else if (kind == 1) {
      f.fd = true;
      f.fd_flags = static_cast<std::uint8_t>(rng() & 0xF);
      static const std::uint8_t lens[] = {0, 3, 8, 12, 16, 20, 24, 32, 48, 64};
      f.len = lens[rng() % 10];
    } else if (kind == 2) {
      f = make_error_frame(static_cast<std::uint32_t>(rng() & 0x3FF));
    } else {
      f.len = static_cast<std::uint8_t>(rng() % 9);
    }
    if (!f.rtr)
      for (unsigned i = 0; i < f.len; ++i) f.data[i] = static_cast<std::uint8_t>(rng());
    f.t_ns = static_cast<std::int64_t>(rng() % 4000000000ULL) * 1000000000LL + static_cast<std::int64_t>(rng() % 1000000000ULL);
    const std::string line = format_candump_line(f, "vcan0");
    CanFrame back;
    std::string iface;
    ASSERT_EQ(parse_candump_line(line, back, iface), "") << line;
    ASSERT_TRUE(same_frame(f, back)) << line;
    ASSERT_EQ(back.t_ns, f.t_ns / 1000 * 1000) << line;
    ASSERT_EQ(format_candump_line(back, iface), line);
  }
}
