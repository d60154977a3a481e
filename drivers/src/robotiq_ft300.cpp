#include <hil/drivers/robotiq_ft300.hpp>

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace hil::drivers::robotiq {

std::uint16_t crc16(std::span<const std::uint8_t> bytes) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t b : bytes) {
    crc ^= b;
    for (int k = 0; k < 8; ++k)
      crc = (crc & 1U) != 0 ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001U) : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

std::array<double, 6> Reading::si() const noexcept {
  std::array<double, 6> w{};
  for (std::size_t i = 0; i < 3; ++i) w[i] = counts[i] / kCountsPerNewton;
  for (std::size_t i = 3; i < 6; ++i) w[i] = counts[i] / kCountsPerNewtonMetre;
  return w;
}

void encode_frame(const Reading& r, std::uint8_t* out) noexcept {
  out[0] = kFrameHeader0;
  out[1] = kFrameHeader1;
  for (std::size_t i = 0; i < 6; ++i) {
    const auto u = static_cast<std::uint16_t>(r.counts[i]);
    out[2 + 2 * i] = static_cast<std::uint8_t>(u & 0xFF);  // little-endian, unlike the Modbus registers
    out[3 + 2 * i] = static_cast<std::uint8_t>(u >> 8);
  }
  const std::uint16_t crc = crc16({out, kFrameBytes - 2});
  out[14] = static_cast<std::uint8_t>(crc & 0xFF);
  out[15] = static_cast<std::uint8_t>(crc >> 8);
}

bool decode_frame(const std::uint8_t* in, Reading& out) noexcept {
  if (in[0] != kFrameHeader0 || in[1] != kFrameHeader1) return false;
  const std::uint16_t crc = static_cast<std::uint16_t>(in[14] | (in[15] << 8));
  if (crc16({in, kFrameBytes - 2}) != crc) return false;
  for (std::size_t i = 0; i < 6; ++i)
    out.counts[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(in[2 + 2 * i] | (in[3 + 2 * i] << 8)));
  return true;
}

std::size_t StreamFramer::push(std::span<const std::uint8_t> bytes) noexcept {
  const std::size_t n = std::min(bytes.size(), buf_.size() - size_);
  if (n > 0) std::memcpy(buf_.data() + size_, bytes.data(), n);
  size_ += n;
  return n;
}

void StreamFramer::skip(std::size_t n) noexcept {
  if (!in_resync_) ++resyncs_;
  in_resync_ = true;
  skipped_bytes_ += n;
  std::memmove(buf_.data(), buf_.data() + n, size_ - n);
  size_ -= n;
}

bool StreamFramer::next(Reading& out) noexcept {
  while (size_ >= kFrameBytes) {
    // Bytes before a header belong to no frame.
    std::size_t h = 0;
    while (h + 1 < size_ && !(buf_[h] == kFrameHeader0 && buf_[h + 1] == kFrameHeader1)) ++h;
    if (h > 0) {
      skip(h);
      continue;
    }
    if (decode_frame(buf_.data(), out)) {
      in_resync_ = false;
      std::memmove(buf_.data(), buf_.data() + kFrameBytes, size_ - kFrameBytes);
      size_ -= kFrameBytes;
      return true;
    }
    // A header whose frame fails the CRC: corrupt, or a header pattern inside noise. The true
    // next header may lie within its 16 bytes, so only the header's first byte goes.
    ++bad_crc_;
    skip(1);
  }
  return false;
}

namespace {
/// A register byte as a character of an identity text: a corrupt byte (a NUL, a control code)
/// shows as '?' instead of cutting or garbling the text.
char printable(unsigned byte) noexcept { return byte >= 0x20 && byte < 0x7F ? static_cast<char>(byte) : '?'; }
}  // namespace

std::string decode_firmware(std::span<const std::uint16_t, 3> r) {
  if ((r[0] >> 8) != 'F') return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%c%c%c-%u.%u.%u", printable(r[0] >> 8), printable(r[0] & 0xFFU), printable(r[1] >> 8), r[1] & 0xFFU,
                r[2] >> 8, r[2] & 0xFFU);
  return buf;
}

std::string decode_serial(std::span<const std::uint16_t, 4> r) {
  const std::uint32_t number = (static_cast<std::uint32_t>(r[3]) << 16) | r[2];
  if (number == 0) return "UNKNOWN";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%c%c%c-%04u", printable(r[0] >> 8), printable(r[0] & 0xFFU), printable(r[1] >> 8), number);
  return buf;
}

std::array<std::uint16_t, 4> encode_serial(const std::string& p, std::uint32_t number) {
  const auto c = [&](std::size_t i) { return static_cast<std::uint16_t>(i < p.size() ? static_cast<unsigned char>(p[i]) : ' '); };
  return {static_cast<std::uint16_t>((c(0) << 8) | c(1)), static_cast<std::uint16_t>(c(2) << 8),
          static_cast<std::uint16_t>(number & 0xFFFF), static_cast<std::uint16_t>(number >> 16)};
}

std::array<std::uint16_t, 3> encode_firmware(const std::string& p, std::uint8_t major, std::uint8_t minor, std::uint8_t patch) {
  const auto c = [&](std::size_t i) { return static_cast<std::uint16_t>(i < p.size() ? static_cast<unsigned char>(p[i]) : ' '); };
  return {static_cast<std::uint16_t>((c(0) << 8) | c(1)), static_cast<std::uint16_t>((c(2) << 8) | major),
          static_cast<std::uint16_t>((minor << 8) | patch)};
}

}  // namespace hil::drivers::robotiq
