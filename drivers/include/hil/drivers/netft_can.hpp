#pragma once
/// \file The ATI Net F/T box's CAN mode as pure functions (Net F/T manual §15, pp. 89-90; sources
/// and what is unverified in docs/hardware.md). Values are little-endian, unlike NETCANOEM and RDT.
///  - request: id = the box's base address, one data byte: 0x02 short data, 0x04 bias.
///  - short data: two answers, id base+5 = Fx, Tx, Fy, Ty and id base+6 = Fz, Tz, status, sample
///    number, int16 each. A new request aborts an answer under way.
/// Long data (32-bit values in four answers) is not implemented: its request byte and answer ids
/// were found in no source.
#include <array>
#include <cstdint>

#include <hil/drivers/can_frame.hpp>

namespace hil::drivers::netft_can {

inline constexpr std::uint8_t kRequestShortData = 0x02;
inline constexpr std::uint8_t kRequestBias = 0x04;
inline constexpr std::uint32_t kShortFirst = 5;   ///< answer id offset: Fx Tx Fy Ty
inline constexpr std::uint32_t kShortSecond = 6;  ///< answer id offset: Fz Tz status sample
/// The highest base address whose answers still have 11-bit ids.
inline constexpr std::uint32_t kMaxBase = 0x7FF - kShortSecond;

/// One short-data answer: counts Fx Fy Fz Tx Ty Tz, the box's status and sample number.
struct ShortData {
  std::array<std::int16_t, 6> counts{};
  std::uint16_t status = 0;
  std::uint16_t sample = 0;
};

CanFrame request(std::uint32_t base, std::uint8_t command) noexcept;
std::array<CanFrame, 2> encode_short(std::uint32_t base, const ShortData& d) noexcept;
/// The first answer (8 bytes: Fx Tx Fy Ty). False if the length is not 8.
bool decode_short_first(const CanFrame& f, ShortData& d) noexcept;
/// The second answer (8 bytes: Fz Tz status sample). False if the length is not 8.
bool decode_short_second(const CanFrame& f, ShortData& d) noexcept;

}  // namespace hil::drivers::netft_can
