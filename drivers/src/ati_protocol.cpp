#include <hil/drivers/ati_protocol.hpp>

#include <cstdio>
#include <utility>

#include <bit>
#include <cstring>

namespace hil::drivers::ati {
namespace {

inline void put16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}
inline std::uint16_t get16(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>((static_cast<unsigned>(p[0]) << 8) | p[1]); }
inline void put32(std::uint8_t* p, std::uint32_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}
inline std::uint32_t get32(const std::uint8_t* p) noexcept {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) | (static_cast<std::uint32_t>(p[2]) << 8) |
         p[3];
}

CanFrame frame(std::uint32_t base, std::uint8_t op, std::uint8_t len) noexcept {
  CanFrame f;
  f.id = frame_id(base, op);
  f.len = len;
  return f;
}

}  // namespace

CanFrame request(std::uint32_t base, std::uint8_t opcode, int arg) noexcept {
  CanFrame f = frame(base, opcode, arg < 0 ? 0 : 1);
  if (arg >= 0) f.data[0] = static_cast<std::uint8_t>(arg);
  return f;
}

std::array<CanFrame, 2> encode_gauges(std::uint32_t base, std::uint16_t status, const Gauges& g) noexcept {
  std::array<CanFrame, 2> out{frame(base, kOpReadGauges, 8), frame(base, kOpGaugesSecond, 6)};
  put16(&out[0].data[0], status);
  put16(&out[0].data[2], static_cast<std::uint16_t>(g[0]));
  put16(&out[0].data[4], static_cast<std::uint16_t>(g[2]));
  put16(&out[0].data[6], static_cast<std::uint16_t>(g[4]));
  put16(&out[1].data[0], static_cast<std::uint16_t>(g[1]));
  put16(&out[1].data[2], static_cast<std::uint16_t>(g[3]));
  put16(&out[1].data[4], static_cast<std::uint16_t>(g[5]));
  return out;
}

bool decode_gauges_first(const CanFrame& f, std::uint16_t& status, Gauges& g) noexcept {
  if (f.len != 8) return false;
  const std::uint8_t* d = f.data.data();
  status = get16(d);
  g[0] = static_cast<std::int16_t>(get16(d + 2));
  g[2] = static_cast<std::int16_t>(get16(d + 4));
  g[4] = static_cast<std::int16_t>(get16(d + 6));
  return true;
}

bool decode_gauges_second(const CanFrame& f, Gauges& g) noexcept {
  if (f.len != 6) return false;
  const std::uint8_t* d = f.data.data();
  g[1] = static_cast<std::int16_t>(get16(d));
  g[3] = static_cast<std::int16_t>(get16(d + 2));
  g[5] = static_cast<std::int16_t>(get16(d + 4));
  return true;
}

std::array<CanFrame, 3> encode_matrix_row(std::uint32_t base, const MatrixRow& row) noexcept {
  std::array<CanFrame, 3> out;
  for (unsigned k = 0; k < 3; ++k) {
    out[k] = frame(base, static_cast<std::uint8_t>(kOpReadMatrix + k), 8);
    put32(&out[k].data[0], std::bit_cast<std::uint32_t>(row[2 * k]));
    put32(&out[k].data[4], std::bit_cast<std::uint32_t>(row[2 * k + 1]));
  }
  return out;
}

bool decode_matrix_part(const CanFrame& f, unsigned part, MatrixRow& row) noexcept {
  if (f.len != 8 || part > 2) return false;
  row[2 * part] = std::bit_cast<float>(get32(&f.data[0]));
  row[2 * part + 1] = std::bit_cast<float>(get32(&f.data[4]));
  return true;
}

CanFrame encode_serial(std::uint32_t base, std::string_view serial) noexcept {
  CanFrame f = frame(base, kOpSerial, 8);
  for (std::size_t i = 0; i < 8; ++i) f.data[i] = i < serial.size() ? static_cast<std::uint8_t>(serial[i]) : 0;
  return f;
}

std::string decode_serial(const CanFrame& f) {
  std::string s;
  for (std::size_t i = 0; i < f.len && i < 8 && f.data[i] != 0; ++i) s.push_back(static_cast<char>(f.data[i]));
  return s;
}

CanFrame encode_counts(std::uint32_t base, std::int32_t cpf, std::int32_t cpt) noexcept {
  CanFrame f = frame(base, kOpCounts, 8);
  put32(&f.data[0], static_cast<std::uint32_t>(cpf));
  put32(&f.data[4], static_cast<std::uint32_t>(cpt));
  return f;
}

bool decode_counts(const CanFrame& f, std::int32_t& cpf, std::int32_t& cpt) noexcept {
  if (f.len != 8) return false;
  cpf = static_cast<std::int32_t>(get32(&f.data[0]));
  cpt = static_cast<std::int32_t>(get32(&f.data[4]));
  return true;
}

CanFrame encode_units(std::uint32_t base, std::uint8_t force_code, std::uint8_t torque_code) noexcept {
  CanFrame f = frame(base, kOpUnits, 2);
  f.data[0] = force_code;
  f.data[1] = torque_code;
  return f;
}

bool decode_units(const CanFrame& f, std::uint8_t& force_code, std::uint8_t& torque_code) noexcept {
  if (f.len != 2) return false;
  force_code = f.data[0];
  torque_code = f.data[1];
  return true;
}

CanFrame encode_firmware(std::uint32_t base, const Firmware& fw) noexcept {
  CanFrame f = frame(base, kOpFirmware, 4);
  f.data[0] = fw.major;
  f.data[1] = fw.minor;
  put16(&f.data[2], fw.build);
  return f;
}

bool decode_firmware(const CanFrame& f, Firmware& fw) noexcept {
  if (f.len != 4) return false;
  fw.major = f.data[0];
  fw.minor = f.data[1];
  fw.build = get16(&f.data[2]);
  return true;
}

double force_unit_to_si(std::uint8_t code) noexcept {
  switch (code) {
    case 1: return 4.4482216152605;
    case 2: return 1.0;
    case 3: return 4448.2216152605;
    case 4: return 1000.0;
    case 5: return 9.80665;
    case 6: return 0.00980665;
    default: return 0.0;
  }
}

double torque_unit_to_si(std::uint8_t code) noexcept {
  switch (code) {
    case 1: return 0.1129848290276167;
    case 2: return 1.3558179483314004;
    case 3: return 1.0;
    case 4: return 0.001;
    case 5: return 0.0980665;
    case 6: return 1000.0;
    default: return 0.0;
  }
}

const char* force_unit_name(std::uint8_t code) noexcept {
  static const char* n[] = {"?", "lbf", "N", "klbf", "kN", "kgf", "gf"};
  return code <= 6 ? n[code] : "?";
}
const char* torque_unit_name(std::uint8_t code) noexcept {
  static const char* n[] = {"?", "lbf-in", "lbf-ft", "N-m", "N-mm", "kgf-cm", "kN-m"};
  return code <= 6 ? n[code] : "?";
}

std::string describe_status(std::uint16_t status) {
  static constexpr std::pair<std::uint16_t, const char*> kBits[] = {
      {kStatusWatchdogReset, "watchdog reset"},
      {kStatusDacAdcTooHigh, "DAC/ADC check too high"},
      {kStatusDacAdcTooLow, "DAC/ADC check too low"},
      {kStatusAnalogGround, "analog ground out of range"},
      {kStatusSupplyTooHigh, "supply too high"},
      {kStatusSupplyTooLow, "supply too low"},
      {kStatusBadCalibration, "bad active calibration"},
      {kStatusEepromFailure, "EEPROM failure"},
      {kStatusConfigInvalid, "configuration invalid"},
      {kStatusTemperatureTooHigh, "temperature too high"},
      {kStatusTemperatureTooLow, "temperature too low"},
      {kStatusCanBusError, "CAN bus error"},
      {kStatusAnyError, "any error"},
  };
  char head[16];
  std::snprintf(head, sizeof head, "0x%04X (", status);
  std::string out = head;
  std::uint16_t named = 0;
  for (const auto& [bit, name] : kBits) {
    named |= bit;
    if ((status & bit) == 0) continue;
    if (out.back() != '(') out += ", ";
    out += name;
  }
  for (int b = 0; b < 16; ++b) {
    const auto bit = static_cast<std::uint16_t>(1U << b);
    if ((status & bit) == 0 || (named & bit) != 0) continue;
    if (out.back() != '(') out += ", ";
    out += "reserved bit " + std::to_string(b);
  }
  if (status == 0) out += "ok";
  return out + ")";
}

}  // namespace hil::drivers::ati
