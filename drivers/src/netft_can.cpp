#include <hil/drivers/netft_can.hpp>

namespace hil::drivers::netft_can {
namespace {
void put(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);  // least significant byte first (manual §15)
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
std::uint16_t get(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
}  // namespace

CanFrame request(std::uint32_t base, std::uint8_t command) noexcept {
  CanFrame f;
  f.id = base;
  f.len = 1;
  f.data[0] = command;
  return f;
}

std::array<CanFrame, 2> encode_short(std::uint32_t base, const ShortData& d) noexcept {
  std::array<CanFrame, 2> out;
  out[0].id = base + kShortFirst;
  out[0].len = 8;
  put(&out[0].data[0], static_cast<std::uint16_t>(d.counts[0]));  // Fx
  put(&out[0].data[2], static_cast<std::uint16_t>(d.counts[3]));  // Tx
  put(&out[0].data[4], static_cast<std::uint16_t>(d.counts[1]));  // Fy
  put(&out[0].data[6], static_cast<std::uint16_t>(d.counts[4]));  // Ty
  out[1].id = base + kShortSecond;
  out[1].len = 8;
  put(&out[1].data[0], static_cast<std::uint16_t>(d.counts[2]));  // Fz
  put(&out[1].data[2], static_cast<std::uint16_t>(d.counts[5]));  // Tz
  put(&out[1].data[4], d.status);
  put(&out[1].data[6], d.sample);
  return out;
}

bool decode_short_first(const CanFrame& f, ShortData& d) noexcept {
  if (f.len != 8) return false;
  d.counts[0] = static_cast<std::int16_t>(get(&f.data[0]));
  d.counts[3] = static_cast<std::int16_t>(get(&f.data[2]));
  d.counts[1] = static_cast<std::int16_t>(get(&f.data[4]));
  d.counts[4] = static_cast<std::int16_t>(get(&f.data[6]));
  return true;
}

bool decode_short_second(const CanFrame& f, ShortData& d) noexcept {
  if (f.len != 8) return false;
  d.counts[2] = static_cast<std::int16_t>(get(&f.data[0]));
  d.counts[5] = static_cast<std::int16_t>(get(&f.data[2]));
  d.status = get(&f.data[4]);
  d.sample = get(&f.data[6]);
  return true;
}

}  // namespace hil::drivers::netft_can
