#pragma once
/// \file The Robotiq FT 300(-S) on its serial line, as pure functions. docs/hardware.md cites each
/// constant's sources (Robotiq's manuals and Robotiq's own driver, rq_sensor_com.cpp).
///  - Modbus RTU, 19200 baud 8N1, slave 9, FC03 holding registers: 180-185 Fx Fy Fz (N x 100),
///    Mx My Mz (N·m x 1000) as int16; 500-502 firmware, 510-513 serial number, 514 production year.
///  - Stream mode: FC16 writing 0x0200 to register 410 starts it; the sensor then sends 16-byte
///    frames at 100 Hz: 0x20 0x4E, six int16 little-endian (Fx Fy Fz in N x 100, Mx My Mz in
///    N·m x 1000), then the Modbus CRC-16 of the first 14 bytes, low byte first. It answers no
///    Modbus request while streaming; about 50 bytes 0xFF stop it.
///  - The sensor reports no status word: its faults are frames that fail their CRC, a stream that
///    stops and Modbus exception answers.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace hil::drivers::robotiq {

inline constexpr int kBaud = 19200;
inline constexpr int kSlave = 9;
inline constexpr std::uint16_t kRegWrench = 180;  ///< 6 registers: Fx Fy Fz Mx My Mz
inline constexpr double kCountsPerNewton = 100.0;
inline constexpr double kCountsPerNewtonMetre = 1000.0;
inline constexpr std::uint16_t kRegStreamSelect = 410;
inline constexpr std::uint16_t kStreamStart = 0x0200;  ///< written to 410 (FC16) to start the stream
inline constexpr std::uint16_t kRegFirmware = 500;     ///< 3 registers
inline constexpr std::uint16_t kRegSerial = 510;       ///< 4 registers
inline constexpr std::uint16_t kRegProductionYear = 514;
inline constexpr std::size_t kFrameBytes = 16;
inline constexpr std::uint8_t kFrameHeader0 = 0x20, kFrameHeader1 = 0x4E;
inline constexpr std::uint8_t kJamByte = 0xFF;
inline constexpr std::size_t kJamBytes = 50;  ///< the stop signal's length
inline constexpr double kStreamRateHz = 100.0;
/// The widest wrench the int16 registers hold: ±327.67 N, ±32.767 N·m.
inline constexpr double kMaxForceN = 32767.0 / kCountsPerNewton;
inline constexpr double kMaxMomentNm = 32767.0 / kCountsPerNewtonMetre;

/// Modbus CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF) of `bytes`.
std::uint16_t crc16(std::span<const std::uint8_t> bytes) noexcept;

/// One stream frame or one register read: counts as the sensor sends them.
struct Reading {
  std::array<std::int16_t, 6> counts{};  ///< Fx Fy Fz (N x 100), Mx My Mz (N·m x 1000)
  /// [Fx Fy Fz (N); Mx My Mz (N·m)].
  std::array<double, 6> si() const noexcept;
};

/// Writes one 16-byte stream frame (header, counts, CRC) into `out`.
void encode_frame(const Reading& r, std::uint8_t* out) noexcept;
/// Decodes one frame at `in` (16 bytes). False when the header or the CRC is wrong.
bool decode_frame(const std::uint8_t* in, Reading& out) noexcept;

/// Finds frames in a byte stream that may start mid-frame, carry noise or lose bytes: a frame is a
/// header whose 16 bytes pass the CRC. Bytes that belong to no frame are skipped and counted; a
/// run of skipped bytes is one "resync". Pure, allocation-free.
class StreamFramer {
 public:
  static constexpr std::size_t kCapacity = 512;
  /// Appends bytes. \returns how many were taken (the rest did not fit: call next() first).
  std::size_t push(std::span<const std::uint8_t> bytes) noexcept;
  /// The next whole frame in the buffer, if any.
  bool next(Reading& out) noexcept;
  /// Drops everything buffered (after a stop signal, before Modbus).
  void clear() noexcept { size_ = 0; }
  std::uint64_t skipped_bytes() const noexcept { return skipped_bytes_; }
  std::uint64_t resyncs() const noexcept { return resyncs_; }
  /// Frames whose header was found but whose CRC failed (a corrupt frame; skipped).
  std::uint64_t bad_crc() const noexcept { return bad_crc_; }
  std::size_t buffered() const noexcept { return size_; }

 private:
  void skip(std::size_t n) noexcept;
  std::array<std::uint8_t, kCapacity> buf_{};
  std::size_t size_ = 0;
  bool in_resync_ = false;
  std::uint64_t skipped_bytes_ = 0, resyncs_ = 0, bad_crc_ = 0;
};

/// "FT3-1.0.5" from registers 500-502: three ASCII characters, then major, minor, patch bytes,
/// high byte first in each register. "" when the first character is not 'F' (not the sensor).
std::string decode_firmware(std::span<const std::uint16_t, 3> regs);
/// "ABC-0123" from registers 510-513: three ASCII characters, then a 32-bit number whose low word
/// is register 512; "UNKNOWN" when the number is 0 (as Robotiq's driver prints it).
std::string decode_serial(std::span<const std::uint16_t, 4> regs);
/// The registers that decode to `prefix`-`number` and to firmware `prefix3`-a.b.c (for fakes).
std::array<std::uint16_t, 4> encode_serial(const std::string& prefix3, std::uint32_t number);
std::array<std::uint16_t, 3> encode_firmware(const std::string& prefix3, std::uint8_t major, std::uint8_t minor, std::uint8_t patch);

}  // namespace hil::drivers::robotiq
