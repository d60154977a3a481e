#pragma once
/// \file The ATI Net F/T box's Raw Data Transfer (RDT) over UDP as pure functions, and its
/// calibration page. Every multi-byte value is big-endian (network order). docs/hardware.md cites
/// each constant's sources.
///  - request (8 bytes, to UDP port 49152): uint16 header 0x1234, uint16 command, uint32
///    sample_count (0 = until stopped).
///  - record (36 bytes): uint32 rdt_sequence (1, 2, ... per record sent), uint32 ft_sequence (the
///    box's internal sample counter), uint32 status, int32 Fx Fy Fz Tx Ty Tz in counts. Buffered
///    streaming packs several records into one datagram.
///  - force = counts / counts_per_force, torque = counts / counts_per_torque, in the units of the
///    box's active configuration (netftapi2.xml: cfgcpf, cfgcpt, scfgfu, scfgtu).
///  - status: bit 31 joins any error; bit 16 = a monitor (threshold) condition latched.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace hil::drivers::netft {

inline constexpr std::uint16_t kRdtPort = 49152;
inline constexpr std::uint16_t kRdtHeader = 0x1234;
inline constexpr std::size_t kRequestBytes = 8;
inline constexpr std::size_t kRecordBytes = 36;

enum class RdtCommand : std::uint16_t {
  stop = 0x0000,
  start_realtime = 0x0002,  ///< one record per datagram, as fast as the box's RDT rate
  start_buffered = 0x0003,  ///< several records per datagram
  start_multi_unit = 0x0004,
  reset_latch = 0x0041,  ///< clears the latched monitor condition (status bit 16)
  set_bias = 0x0042,     ///< the box subtracts the present load from then on
};
/// "stop", "start real-time", ..., or nullptr for a value that is none of them.
const char* to_string(RdtCommand c) noexcept;

inline constexpr std::uint32_t kStatusAnyError = 0x80000000U;
inline constexpr std::uint32_t kStatusMonitorLatched = 0x00010000U;

struct RdtRequest {
  std::uint16_t header = kRdtHeader;
  std::uint16_t command = 0;
  std::uint32_t sample_count = 0;
};
std::array<std::uint8_t, kRequestBytes> encode_request(RdtCommand command, std::uint32_t sample_count = 0) noexcept;
/// False unless exactly 8 bytes with the 0x1234 header.
bool decode_request(std::span<const std::uint8_t> bytes, RdtRequest& out) noexcept;

struct RdtRecord {
  std::uint32_t rdt_sequence = 0;
  std::uint32_t ft_sequence = 0;
  std::uint32_t status = 0;
  std::array<std::int32_t, 6> counts{};  ///< Fx Fy Fz Tx Ty Tz
};
void encode_record(const RdtRecord& r, std::uint8_t* out) noexcept;  ///< writes kRecordBytes
void decode_record(const std::uint8_t* in, RdtRecord& r) noexcept;   ///< reads kRecordBytes
/// Records in a datagram of `bytes` bytes: bytes / 36, or 0 when it is not a positive multiple.
std::size_t records_in(std::size_t bytes) noexcept;

/// "0x80010000 (any error, monitor condition latched)"; the other bits by number. The box's
/// manual's table for bits 0-30 was not available to check (docs/hardware.md), so only the two
/// bits independent sources agree on are named.
std::string describe_status(std::uint32_t status);

/// The units and scale of the box's active configuration.
struct Calibration {
  double counts_per_force = 0.0;   ///< counts per force unit
  double counts_per_torque = 0.0;  ///< counts per torque unit
  std::string force_unit = "N";    ///< as the box names it: N, lbf, kN, klbf, kgf, gf
  std::string torque_unit = "Nm";  ///< Nm, N-m, Nmm, N-mm, lbf-in, lbf-ft, kNm, kgf-cm
  /// N per force count and N·m per torque count. \throws ConfigError naming the unit field.
  double newtons_per_count() const;
  double newton_metres_per_count() const;
};
/// SI factor of a Net F/T unit name (0 if unknown).
double force_unit_to_si(std::string_view unit) noexcept;
double torque_unit_to_si(std::string_view unit) noexcept;
/// Reads the box's configuration page (http://<box>/netftapi2.xml, saved to a file): cfgcpf,
/// cfgcpt, scfgfu, scfgtu under <netft>. \throws ConfigError naming `source` and the element.
Calibration parse_calibration_xml(std::string_view xml, const std::string& source);

}  // namespace hil::drivers::netft
