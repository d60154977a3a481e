#pragma once
// Little-endian field encoding of MCAP records (private to hil::mcap).
#include <cstdint>
#include <cstring>
#include <map>
#include <string>

namespace hil::mcap::detail {

inline void put_u8(std::string& b, std::uint8_t v) { b.push_back(static_cast<char>(v)); }
template <class T>
void put_le(std::string& b, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) b.push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xFF));
}
inline void put_u16(std::string& b, std::uint16_t v) { put_le(b, v); }
inline void put_u32(std::string& b, std::uint32_t v) { put_le(b, v); }
inline void put_u64(std::string& b, std::uint64_t v) { put_le(b, v); }
inline void put_str(std::string& b, const std::string& s) {
  put_u32(b, static_cast<std::uint32_t>(s.size()));
  b += s;
}

/// A whole record: opcode, u64 content length, content.
inline void put_record(std::string& out, std::uint8_t opcode, const std::string& content) {
  put_u8(out, opcode);
  put_u64(out, content.size());
  out += content;
}

}  // namespace hil::mcap::detail
