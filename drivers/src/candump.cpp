#include <hil/drivers/candump.hpp>

#include <cinttypes>
#include <cstdio>
#include <cstring>

namespace hil::drivers {
namespace {

constexpr char kHex[] = "0123456789ABCDEF";

inline int nibble(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

std::string at(std::size_t col, const std::string& what) { return "column " + std::to_string(col + 1) + ": " + what; }

}  // namespace

std::size_t format_frame_text(const CanFrame& f, char* buf) noexcept {
  std::size_t o = 0;
  auto put_id = [&](std::uint32_t id, int digits) {
    for (int i = digits - 1; i >= 0; --i) buf[o++] = kHex[(id >> (4 * i)) & 0xF];
  };
  if (f.error) {
    put_id((f.id & kCanErrMask) | kCanErrFlag, 8);
  } else if (f.extended) {
    put_id(f.id & kCanEffMask, 8);
  } else {
    put_id(f.id & kCanSffMask, 3);
  }
  buf[o++] = '#';
  if (!f.fd && f.rtr) {
    buf[o++] = 'R';
    if (f.len != 0 && f.len <= 8) buf[o++] = kHex[f.len];
    buf[o] = '\0';
    return o;
  }
  const unsigned maxlen = f.fd ? 64U : 8U;
  const unsigned len = f.len > maxlen ? maxlen : f.len;
  if (f.fd) {
    buf[o++] = '#';
    buf[o++] = kHex[f.fd_flags & 0xF];
  }
  for (unsigned i = 0; i < len; ++i) {
    buf[o++] = kHex[f.data[i] >> 4];
    buf[o++] = kHex[f.data[i] & 0xF];
  }
  buf[o] = '\0';
  return o;
}

std::string format_frame_text(const CanFrame& f) {
  char buf[kMaxFrameText];
  const std::size_t n = format_frame_text(f, buf);
  return std::string(buf, n);
}

std::string parse_frame_text(std::string_view s, CanFrame& out) {
  out = CanFrame{};
  std::size_t idx;
  std::uint32_t id = 0;
  auto read_id = [&](std::size_t digits) -> std::string {
    for (std::size_t i = 0; i < digits; ++i) {
      const int v = nibble(s[i]);
      if (v < 0) return at(i, std::string("identifier: '") + s[i] + "' is not a hex digit");
      id = (id << 4) | static_cast<std::uint32_t>(v);
    }
    return {};
  };
  if (s.size() >= 4 && s[3] == '#') {
    if (auto e = read_id(3); !e.empty()) return e;
    if (id > kCanSffMask) return at(0, "standard identifier exceeds 0x7FF");
    out.id = id;
    idx = 4;
  } else if (s.size() >= 9 && s[8] == '#') {
    if (auto e = read_id(8); !e.empty()) return e;
    if ((id & kCanErrFlag) != 0) {
      out.error = true;
      out.id = id & kCanErrMask;
    } else {
      if ((id & ~kCanEffMask) != 0) return at(0, "extended identifier exceeds 29 bits");
      out.extended = true;
      out.id = id;
    }
    idx = 9;
  } else {
    return "identifier: expected 3 hex digits (standard) or 8 (extended) before '#'";
  }
  unsigned maxlen = 8;
  if (idx < s.size() && (s[idx] == 'R' || s[idx] == 'r')) {
    if (out.error) return at(idx, "error frames cannot be RTR");
    out.rtr = true;
    ++idx;
    if (idx < s.size()) {
      const int v = nibble(s[idx]);
      if (v < 0 || v > 8) return at(idx, "RTR length must be one digit 0..8");
      out.len = static_cast<std::uint8_t>(v);
      ++idx;
    }
    if (idx != s.size()) return at(idx, "unexpected text after the RTR length");
    return {};
  }
  if (idx < s.size() && s[idx] == '#') {
    if (out.error) return at(idx, "error frames are classic frames, not CAN FD");
    out.fd = true;
    maxlen = 64;
    if (idx + 1 >= s.size()) return at(idx + 1, "CAN FD flags nibble missing after '##'");
    const int v = nibble(s[idx + 1]);
    if (v < 0) return at(idx + 1, "CAN FD flags must be one hex digit");
    out.fd_flags = static_cast<std::uint8_t>(v);
    idx += 2;
  }
  unsigned len = 0;
  while (idx < s.size()) {
    if (s[idx] == '.') {
      ++idx;
      continue;
    }
    if (len == maxlen) return at(idx, "more than " + std::to_string(maxlen) + " data bytes");
    if (idx + 1 >= s.size()) return at(idx, "odd number of hex digits in the data");
    const int hi = nibble(s[idx]);
    const int lo = nibble(s[idx + 1]);
    if (hi < 0) return at(idx, std::string("data: '") + s[idx] + "' is not a hex digit");
    if (lo < 0) return at(idx + 1, std::string("data: '") + s[idx + 1] + "' is not a hex digit");
    out.data[len++] = static_cast<std::uint8_t>((hi << 4) | lo);
    idx += 2;
  }
  if (out.fd && !valid_fd_length(len))
    return "data: " + std::to_string(len) + " bytes is not a CAN FD length (0..8, 12, 16, 20, 24, 32, 48, 64)";
  out.len = static_cast<std::uint8_t>(len);
  return {};
}

std::string format_candump_line(const CanFrame& f, std::string_view interface) {
  char head[48];
  const std::int64_t t = f.t_ns < 0 ? 0 : f.t_ns;
  const int n = std::snprintf(head, sizeof head, "(%010" PRIu64 ".%06" PRIu64 ") ", static_cast<std::uint64_t>(t / 1000000000),
                              static_cast<std::uint64_t>((t / 1000) % 1000000));
  char frame[kMaxFrameText];
  const std::size_t fl = format_frame_text(f, frame);
  std::string line;
  line.reserve(static_cast<std::size_t>(n) + interface.size() + 1 + fl);
  line.append(head, static_cast<std::size_t>(n));
  line.append(interface);
  line.push_back(' ');
  line.append(frame, fl);
  return line;
}

std::string parse_candump_line(std::string_view line, CanFrame& out, std::string& interface) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
  if (line.empty() || line[0] != '(') return "timestamp: line does not start with '('";
  std::size_t i = 1;
  std::uint64_t sec = 0;
  std::size_t digits = 0;
  while (i < line.size() && line[i] >= '0' && line[i] <= '9') {
    sec = sec * 10 + static_cast<std::uint64_t>(line[i] - '0');
    ++i;
    if (++digits > 12) return at(i, "timestamp: too many digits in the seconds");
  }
  if (digits == 0 || i >= line.size() || line[i] != '.') return at(i, "timestamp: expected (seconds.microseconds)");
  // Found by fuzzing: 12 digits fit in sec but not in t_ns (int64 ns), which wrapped silently.
  if (sec > 9223372035) return at(i, "timestamp: seconds beyond 2262-04-11 (int64 nanoseconds)");
  ++i;
  std::uint64_t usec = 0;
  digits = 0;
  while (i < line.size() && line[i] >= '0' && line[i] <= '9') {
    usec = usec * 10 + static_cast<std::uint64_t>(line[i] - '0');
    ++i;
    ++digits;
  }
  if (digits == 0 || digits > 6) return at(i, "timestamp: expected 1 to 6 digits of microseconds");
  if (i >= line.size() || line[i] != ')') return at(i, "timestamp: missing ')'");
  ++i;
  if (i >= line.size() || line[i] != ' ') return at(i, "expected a space after the timestamp");
  while (i < line.size() && line[i] == ' ') ++i;
  const std::size_t ifs = i;
  while (i < line.size() && line[i] != ' ') ++i;
  if (i == ifs || i >= line.size()) return at(ifs, "interface name or frame missing");
  interface.assign(line.substr(ifs, i - ifs));
  while (i < line.size() && line[i] == ' ') ++i;
  const std::size_t fs = i;
  while (i < line.size() && line[i] != ' ') ++i;
  std::string_view text = line.substr(fs, i - fs);
  std::string_view rest = line.substr(i);
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  if (!rest.empty() && rest != "T" && rest != "R") return at(i, "unexpected text after the frame");
  if (auto e = parse_frame_text(text, out); !e.empty()) return "frame at column " + std::to_string(fs + 1) + ": " + e;
  out.t_ns = static_cast<std::int64_t>(sec * 1000000000ULL + usec * 1000ULL);
  out.stamp = StampSource::software;
  return {};
}

}  // namespace hil::drivers
