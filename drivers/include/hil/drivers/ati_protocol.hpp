#pragma once
/// \file The ATI NETCANOEM protocol as pure functions (ATI "Net F/T CAN OEM" interface).
/// 11-bit id = base << 4 | opcode; all multi-byte values big-endian.
///  - 0x0 read gauges: request empty; answered by two frames: id base|0x0 = status word, SG0, SG2,
///    SG4 (8 bytes) and id base|0x1 = SG1, SG3, SG5 (6 bytes), int16 each.
///  - 0x2 read calibration-matrix row r (request 1 byte = r, 0..5 = Fx..Tz): three frames with ids
///    base|0x2, base|0x3, base|0x4, two float32 each (the row's coefficients for SG0..SG5).
///  - 0x5 serial number (8 ASCII bytes), 0x7 counts per force and per torque (2 × int32),
///    0x8 units (force code, torque code), 0xF firmware (major, minor, build uint16).
///  - status word: bit 15 = any error, with the cause in bits 0-14 (kStatus*). Every bit set
///    marks the reading as a device fault: the independent drivers stop on any non-zero status.
/// Conversion: F/T in the device's units = (M · SG) ./ [cpf cpf cpf cpt cpt cpt].
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include <hil/drivers/can_frame.hpp>

namespace hil::drivers::ati {

inline constexpr std::uint8_t kOpReadGauges = 0x0;
inline constexpr std::uint8_t kOpGaugesSecond = 0x1;
inline constexpr std::uint8_t kOpReadMatrix = 0x2;
inline constexpr std::uint8_t kOpSerial = 0x5;
inline constexpr std::uint8_t kOpCounts = 0x7;
inline constexpr std::uint8_t kOpUnits = 0x8;
inline constexpr std::uint8_t kOpFirmware = 0xF;
// Status word bits (first gauge frame), as docs/hardware.md cites them.
inline constexpr std::uint16_t kStatusWatchdogReset = 0x0001;
inline constexpr std::uint16_t kStatusDacAdcTooHigh = 0x0002;
inline constexpr std::uint16_t kStatusDacAdcTooLow = 0x0004;
inline constexpr std::uint16_t kStatusAnalogGround = 0x0008;
inline constexpr std::uint16_t kStatusSupplyTooHigh = 0x0010;
inline constexpr std::uint16_t kStatusSupplyTooLow = 0x0020;
inline constexpr std::uint16_t kStatusBadCalibration = 0x0040;
inline constexpr std::uint16_t kStatusEepromFailure = 0x0080;
inline constexpr std::uint16_t kStatusConfigInvalid = 0x0100;
inline constexpr std::uint16_t kStatusTemperatureTooHigh = 0x0800;
inline constexpr std::uint16_t kStatusTemperatureTooLow = 0x1000;
inline constexpr std::uint16_t kStatusCanBusError = 0x4000;
inline constexpr std::uint16_t kStatusAnyError = 0x8000;
/// The factory base id of a NETCANOEM board (frame ids 0x200-0x20F).
inline constexpr std::uint32_t kFactoryBase = 0x20;
inline constexpr std::uint32_t kMaxBase = 0x7F;

using Gauges = std::array<std::int16_t, 6>;
using MatrixRow = std::array<float, 6>;

constexpr std::uint32_t frame_id(std::uint32_t base, std::uint8_t opcode) noexcept { return (base << 4) | opcode; }
/// The base id and opcode of an 11-bit frame id.
constexpr std::uint32_t base_of(std::uint32_t id) noexcept { return id >> 4; }
constexpr std::uint8_t opcode_of(std::uint32_t id) noexcept { return static_cast<std::uint8_t>(id & 0xF); }

/// A request frame; `arg` < 0: no data byte (gauges, serial, counts, units, firmware), else one byte.
CanFrame request(std::uint32_t base, std::uint8_t opcode, int arg = -1) noexcept;

std::array<CanFrame, 2> encode_gauges(std::uint32_t base, std::uint16_t status, const Gauges& g) noexcept;
/// First gauge frame (8 bytes): status, SG0, SG2, SG4. False if the length is not 8.
bool decode_gauges_first(const CanFrame& f, std::uint16_t& status, Gauges& g) noexcept;
/// Second gauge frame (6 bytes): SG1, SG3, SG5. False if the length is not 6.
bool decode_gauges_second(const CanFrame& f, Gauges& g) noexcept;

std::array<CanFrame, 3> encode_matrix_row(std::uint32_t base, const MatrixRow& row) noexcept;
/// One of the three matrix frames (part = opcode - 2); fills row[2*part], row[2*part+1].
bool decode_matrix_part(const CanFrame& f, unsigned part, MatrixRow& row) noexcept;

CanFrame encode_serial(std::uint32_t base, std::string_view serial) noexcept;
std::string decode_serial(const CanFrame& f);
CanFrame encode_counts(std::uint32_t base, std::int32_t counts_per_force, std::int32_t counts_per_torque) noexcept;
bool decode_counts(const CanFrame& f, std::int32_t& counts_per_force, std::int32_t& counts_per_torque) noexcept;
CanFrame encode_units(std::uint32_t base, std::uint8_t force_code, std::uint8_t torque_code) noexcept;
bool decode_units(const CanFrame& f, std::uint8_t& force_code, std::uint8_t& torque_code) noexcept;
struct Firmware {
  std::uint8_t major = 0, minor = 0;
  std::uint16_t build = 0;
};
CanFrame encode_firmware(std::uint32_t base, const Firmware& fw) noexcept;
bool decode_firmware(const CanFrame& f, Firmware& fw) noexcept;

/// "0x8020 (supply too low, any error)"; "0x0000 (ok)". Reserved bits are named by number.
std::string describe_status(std::uint16_t status);

/// ATI unit codes → SI factor (0 if unknown). Force: 1 lbf, 2 N, 3 klbf, 4 kN, 5 kgf, 6 gf.
/// Torque: 1 lbf·in, 2 lbf·ft, 3 N·m, 4 N·mm, 5 kgf·cm, 6 kN·m.
double force_unit_to_si(std::uint8_t code) noexcept;
double torque_unit_to_si(std::uint8_t code) noexcept;
const char* force_unit_name(std::uint8_t code) noexcept;
const char* torque_unit_name(std::uint8_t code) noexcept;

}  // namespace hil::drivers::ati
