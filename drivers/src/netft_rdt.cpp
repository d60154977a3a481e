#include <hil/drivers/netft_rdt.hpp>

#include <tinyxml2.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <hil/drivers/error.hpp>

namespace hil::drivers::netft {
namespace {

void put16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}
void put32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int k = 0; k < 4; ++k) p[k] = static_cast<std::uint8_t>(v >> (24 - 8 * k));
}
std::uint16_t get16(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
std::uint32_t get32(const std::uint8_t* p) noexcept {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) | (static_cast<std::uint32_t>(p[2]) << 8) |
         p[3];
}

}  // namespace

const char* to_string(RdtCommand c) noexcept {
  switch (c) {
    case RdtCommand::stop: return "stop";
    case RdtCommand::start_realtime: return "start real-time";
    case RdtCommand::start_buffered: return "start buffered";
    case RdtCommand::start_multi_unit: return "start multi-unit";
    case RdtCommand::reset_latch: return "reset threshold latch";
    case RdtCommand::set_bias: return "set bias";
  }
  return nullptr;
}

std::array<std::uint8_t, kRequestBytes> encode_request(RdtCommand command, std::uint32_t sample_count) noexcept {
  std::array<std::uint8_t, kRequestBytes> out{};
  put16(&out[0], kRdtHeader);
  put16(&out[2], static_cast<std::uint16_t>(command));
  put32(&out[4], sample_count);  // all four bytes (a driver of the field wrote its low half twice)
  return out;
}

bool decode_request(std::span<const std::uint8_t> bytes, RdtRequest& out) noexcept {
  if (bytes.size() != kRequestBytes) return false;
  out.header = get16(&bytes[0]);
  out.command = get16(&bytes[2]);
  out.sample_count = get32(&bytes[4]);
  return out.header == kRdtHeader;
}

void encode_record(const RdtRecord& r, std::uint8_t* out) noexcept {
  put32(out, r.rdt_sequence);
  put32(out + 4, r.ft_sequence);
  put32(out + 8, r.status);
  for (std::size_t k = 0; k < 6; ++k) put32(out + 12 + 4 * k, static_cast<std::uint32_t>(r.counts[k]));
}

void decode_record(const std::uint8_t* in, RdtRecord& r) noexcept {
  r.rdt_sequence = get32(in);
  r.ft_sequence = get32(in + 4);
  r.status = get32(in + 8);
  for (std::size_t k = 0; k < 6; ++k) r.counts[k] = static_cast<std::int32_t>(get32(in + 12 + 4 * k));
}

std::size_t records_in(std::size_t bytes) noexcept { return bytes != 0 && bytes % kRecordBytes == 0 ? bytes / kRecordBytes : 0; }

std::string describe_status(std::uint32_t status) {
  char head[24];
  std::snprintf(head, sizeof head, "0x%08X (", status);
  std::string out = head;
  const auto add = [&](const std::string& what) {
    if (out.back() != '(') out += ", ";
    out += what;
  };
  if ((status & kStatusAnyError) != 0) add("any error");
  if ((status & kStatusMonitorLatched) != 0) add("monitor condition latched");
  for (int b = 0; b < 32; ++b) {
    const std::uint32_t bit = 1U << b;
    if ((status & bit) != 0 && bit != kStatusAnyError && bit != kStatusMonitorLatched) add("bit " + std::to_string(b));
  }
  if (status == 0) out += "ok";
  return out + ")";
}

double force_unit_to_si(std::string_view u) noexcept {
  if (u == "N") return 1.0;
  if (u == "kN") return 1e3;
  if (u == "lbf" || u == "lb") return 4.4482216152605;
  if (u == "klbf" || u == "klb") return 4448.2216152605;
  if (u == "kgf" || u == "kg") return 9.80665;
  if (u == "gf" || u == "g") return 9.80665e-3;
  return 0.0;
}

double torque_unit_to_si(std::string_view u) noexcept {
  if (u == "Nm" || u == "N-m") return 1.0;
  if (u == "Nmm" || u == "N-mm") return 1e-3;
  if (u == "kNm" || u == "kN-m") return 1e3;
  if (u == "lbf-in" || u == "lbfin" || u == "in-lb" || u == "lb-in") return 0.1129848290276167;
  if (u == "lbf-ft" || u == "lbfft" || u == "ft-lb" || u == "lb-ft") return 1.3558179483314004;
  if (u == "kgf-cm" || u == "kgfcm") return 0.0980665;
  return 0.0;
}

double Calibration::newtons_per_count() const {
  const double si = force_unit_to_si(force_unit);
  if (si == 0.0) throw ConfigError("force_unit", "'" + force_unit + "' is not a Net F/T force unit (N, kN, lbf, klbf, kgf, gf)");
  if (!(counts_per_force > 0.0) || !std::isfinite(counts_per_force)) throw ConfigError("counts_per_force", "must be > 0");
  return si / counts_per_force;
}

double Calibration::newton_metres_per_count() const {
  const double si = torque_unit_to_si(torque_unit);
  if (si == 0.0)
    throw ConfigError("torque_unit", "'" + torque_unit + "' is not a Net F/T torque unit (Nm, N-mm, kNm, lbf-in, lbf-ft, kgf-cm)");
  if (!(counts_per_torque > 0.0) || !std::isfinite(counts_per_torque)) throw ConfigError("counts_per_torque", "must be > 0");
  return si / counts_per_torque;
}

Calibration parse_calibration_xml(std::string_view xml, const std::string& source) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.data(), xml.size()) != tinyxml2::XML_SUCCESS)
    throw ConfigError("calibration_xml", source + ": not XML (line " + std::to_string(doc.ErrorLineNum()) + ": " + doc.ErrorStr() + ")");
  const tinyxml2::XMLElement* root = doc.FirstChildElement("netft");
  if (root == nullptr)
    throw ConfigError("calibration_xml", source + ": no <netft> element (expected the box's netftapi2.xml configuration page)");
  const auto text = [&](const char* name) -> std::string {
    const tinyxml2::XMLElement* e = root->FirstChildElement(name);
    if (e == nullptr || e->GetText() == nullptr)
      throw ConfigError("calibration_xml",
                        source + ": <netft> has no <" + std::string(name) + "> (line " + std::to_string(root->GetLineNum()) + ")");
    return e->GetText();
  };
  const auto number = [&](const char* name) {
    const std::string t = text(name);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end != '\0' || !std::isfinite(v) || v <= 0.0)
      throw ConfigError("calibration_xml", source + ": <" + std::string(name) + "> is '" + t + "', expected a count > 0");
    return v;
  };
  Calibration c;
  c.counts_per_force = number("cfgcpf");
  c.counts_per_torque = number("cfgcpt");
  c.force_unit = text("scfgfu");
  c.torque_unit = text("scfgtu");
  try {
    (void)c.newtons_per_count();
    (void)c.newton_metres_per_count();
  } catch (const ConfigError& e) {
    throw ConfigError("calibration_xml", source + ": " + e.what());
  }
  return c;
}

}  // namespace hil::drivers::netft
