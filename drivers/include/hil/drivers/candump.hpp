#pragma once
/// \file The text formats of can-utils (lib.c): `123#DEADBEEF` frames as cansend takes them and
/// candump prints them, and `candump -L` log lines `(1700000000.123456) can0 123#DEADBEEF`.
/// Output is byte-for-byte what can-utils writes (uppercase hex, 3-digit standard ids, 8-digit
/// extended and error ids, `R[dlc]` for RTR, `##<flags nibble>` for CAN FD). Pure functions.
#include <cstddef>
#include <string>
#include <string_view>

#include <hil/drivers/can_frame.hpp>

namespace hil::drivers {

/// Longest formatted frame: 8-digit id, '#', '#', flags nibble, 128 hex digits, NUL.
inline constexpr std::size_t kMaxFrameText = 8 + 3 + 128 + 1;

/// Formats a frame like can-utils' sprint_canframe (no separators). Writes a NUL-terminated text
/// into `buf` (at least kMaxFrameText bytes) and returns its length.
std::size_t format_frame_text(const CanFrame& f, char* buf) noexcept;
std::string format_frame_text(const CanFrame& f);

/// Parses `<id>#<data>`, `<id>#R[dlc]`, `<id>##<flags><data>` (data bytes may be separated by '.').
/// \returns an empty string on success, else what is wrong and at which character.
std::string parse_frame_text(std::string_view text, CanFrame& out);

/// One `candump -L` line: `(%010lu.%06lu) <interface> <frame>`, without the newline.
/// The timestamp is f.t_ns truncated to microseconds.
std::string format_candump_line(const CanFrame& f, std::string_view interface);

/// Parses one `candump -L` line (trailing "\n"/"\r\n" and a trailing ` T`/` R` direction flag of newer
/// can-utils accepted). Sets out.t_ns (stamp = software) and `interface`.
/// \returns an empty string on success, else a message naming the field and column.
std::string parse_candump_line(std::string_view line, CanFrame& out, std::string& interface);

}  // namespace hil::drivers
