#include <hil/drivers/can_frame.hpp>

#include <cstdio>
#include <cstring>

namespace hil::drivers {

bool same_frame(const CanFrame& a, const CanFrame& b) noexcept {
  if (a.id != b.id || a.len != b.len || a.extended != b.extended || a.rtr != b.rtr || a.error != b.error || a.fd != b.fd ||
      (a.fd && a.fd_flags != b.fd_flags))
    return false;
  if (a.rtr) return true;
  return std::memcmp(a.data.data(), b.data.data(), a.len) == 0;
}

std::uint32_t kernel_can_id(const CanFrame& f) noexcept {
  if (f.error) return (f.id & kCanErrMask) | kCanErrFlag;
  std::uint32_t id = f.extended ? ((f.id & kCanEffMask) | kCanEffFlag) : (f.id & kCanSffMask);
  if (f.rtr) id |= kCanRtrFlag;
  return id;
}

bool valid_fd_length(unsigned len) noexcept {
  return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 || len == 64;
}

const char* frame_problem(const CanFrame& f) noexcept {
  if (f.error) {
    if (f.fd) return "error frames are classic frames";
    if (f.id > kCanErrMask) return "error class bits exceed 29 bits";
    if (f.len > 8) return "error frame longer than 8 bytes";
    return nullptr;
  }
  if (f.extended ? f.id > kCanEffMask : f.id > kCanSffMask)
    return f.extended ? "extended id exceeds 29 bits" : "standard id exceeds 11 bits (0x7FF)";
  if (f.fd) {
    if (f.rtr) return "CAN FD frames have no RTR";
    if (!valid_fd_length(f.len)) return "CAN FD length must be 0..8, 12, 16, 20, 24, 32, 48 or 64";
    if (f.fd_flags > 0xF) return "CAN FD flags exceed one nibble";
    return nullptr;
  }
  if (f.len > 8) return "classic frame longer than 8 bytes";
  return nullptr;
}

const char* to_string(CanCodecStatus s) noexcept {
  switch (s) {
    case CanCodecStatus::ok: return "ok";
    case CanCodecStatus::bad_size: return "size is neither CAN_MTU (16) nor CANFD_MTU (72)";
    case CanCodecStatus::bad_length: return "payload length out of range";
    case CanCodecStatus::bad_id: return "invalid identifier";
  }
  return "?";
}

std::size_t encode_kernel_frame(const CanFrame& f, std::span<std::uint8_t, kCanFdMtu> out) noexcept {
  if (frame_problem(f) != nullptr) return 0;
  const std::uint32_t id = kernel_can_id(f);
  std::memcpy(out.data(), &id, 4);
  out[4] = f.len;
  out[5] = f.fd ? f.fd_flags : 0;
  out[6] = 0;
  out[7] = 0;
  const std::size_t payload = f.fd ? 64 : 8;
  if (f.rtr) {
    std::memset(out.data() + 8, 0, payload);
  } else {
    std::memcpy(out.data() + 8, f.data.data(), f.len);
    std::memset(out.data() + 8 + f.len, 0, payload - f.len);
  }
  return f.fd ? kCanFdMtu : kCanMtu;
}

CanCodecStatus decode_kernel_frame(std::span<const std::uint8_t> in, CanFrame& out) noexcept {
  const std::size_t n = in.size();
  if (n != kCanMtu && n != kCanFdMtu) [[unlikely]]
    return CanCodecStatus::bad_size;
  std::uint32_t id;
  std::memcpy(&id, in.data(), 4);
  const std::uint8_t len = in[4];
  const bool fd = n == kCanFdMtu;
  if (len > (fd ? 64 : 8)) [[unlikely]]
    return CanCodecStatus::bad_length;
  out.error = (id & kCanErrFlag) != 0;
  out.extended = !out.error && (id & kCanEffFlag) != 0;
  out.rtr = !out.error && (id & kCanRtrFlag) != 0;
  out.id = out.error ? (id & kCanErrMask) : out.extended ? (id & kCanEffMask) : (id & kCanSffMask);
  if (!out.error && !out.extended && (id & kCanSffMask) != (id & kCanEffMask)) [[unlikely]]
    return CanCodecStatus::bad_id;
  out.len = len;
  out.fd = fd;
  out.fd_flags = fd ? static_cast<std::uint8_t>(in[5] & 0x0F) : 0;
  if (fd) {
    std::memcpy(out.data.data(), in.data() + 8, 64);
  } else {
    std::memcpy(out.data.data(), in.data() + 8, 8);
  }
  return CanCodecStatus::ok;
}

CanFilter CanFilter::exact(std::uint32_t id, bool extended) noexcept {
  // Match the id and the EFF flag; RTR is not in the mask so data and remote frames both pass.
  return extended ? CanFilter{(id & kCanEffMask) | kCanEffFlag, kCanEffMask | kCanEffFlag, false}
                  : CanFilter{id & kCanSffMask, kCanSffMask | kCanEffFlag, false};
}

CanFilter CanFilter::masked(std::uint32_t base, std::uint32_t id_mask, bool extended) noexcept {
  return extended ? CanFilter{(base & kCanEffMask) | kCanEffFlag, (id_mask & kCanEffMask) | kCanEffFlag, false}
                  : CanFilter{base & kCanSffMask, (id_mask & kCanSffMask) | kCanEffFlag, false};
}

bool passes(std::span<const CanFilter> filters, const CanFrame& f) noexcept {
  if (filters.empty() || f.error) return true;
  const std::uint32_t id = kernel_can_id(f);
  for (const auto& flt : filters) {
    const bool match = (id & flt.mask) == (flt.id & flt.mask);
    if (match != flt.inverted) return true;
  }
  return false;
}

CanErrorInfo decode_error_frame(const CanFrame& f) noexcept {
  CanErrorInfo e;
  if (!f.error) return e;
  const auto& d = f.data;
  e.classes = f.id;
  e.tx_timeout = (f.id & kErrTxTimeout) != 0;
  e.lost_arbitration = (f.id & kErrLostArb) != 0;
  if (e.lost_arbitration && d[0] != 0) e.lost_arbitration_bit = d[0];
  e.controller = (f.id & kErrCrtl) != 0;
  if (e.controller) {
    e.rx_overflow = (d[1] & kErrCrtlRxOverflow) != 0;
    e.tx_overflow = (d[1] & kErrCrtlTxOverflow) != 0;
    e.warning = (d[1] & (kErrCrtlRxWarning | kErrCrtlTxWarning)) != 0;
    e.error_passive = (d[1] & (kErrCrtlRxPassive | kErrCrtlTxPassive)) != 0;
    e.back_to_active = (d[1] & kErrCrtlActive) != 0;
  }
  e.protocol = (f.id & kErrProt) != 0;
  if (e.protocol) {
    e.protocol_type = d[2];
    e.protocol_location = d[3];
  }
  e.transceiver = (f.id & kErrTrx) != 0;
  e.no_ack = (f.id & kErrAck) != 0;
  e.bus_off = (f.id & kErrBusOff) != 0;
  e.bus_error = (f.id & kErrBusError) != 0;
  e.restarted = (f.id & kErrRestarted) != 0;
  if ((f.id & kErrCnt) != 0) {
    e.tx_error_count = d[6];
    e.rx_error_count = d[7];
  }
  return e;
}

std::string describe(const CanErrorInfo& e) {
  std::string s;
  auto add = [&s](const std::string& part) {
    if (!s.empty()) s += ", ";
    s += part;
  };
  if (e.bus_off) add("bus-off");
  if (e.error_passive) add("error-passive");
  if (e.warning) add("error-warning");
  if (e.back_to_active) add("back to error-active");
  if (e.rx_overflow) add("controller rx overflow");
  if (e.tx_overflow) add("controller tx overflow");
  if (e.controller && !e.error_passive && !e.warning && !e.back_to_active && !e.rx_overflow && !e.tx_overflow) add("controller problem");
  if (e.lost_arbitration)
    add(e.lost_arbitration_bit >= 0 ? "lost arbitration at bit " + std::to_string(e.lost_arbitration_bit) : "lost arbitration");
  if (e.protocol) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "protocol violation (type 0x%02X, location 0x%02X)", e.protocol_type, e.protocol_location);
    add(buf);
  }
  if (e.transceiver) add("transceiver error");
  if (e.no_ack) add("no ACK");
  if (e.bus_error) add("bus error");
  if (e.tx_timeout) add("tx timeout");
  if (e.restarted) add("controller restarted");
  if (e.tx_error_count >= 0) add("tx errors " + std::to_string(e.tx_error_count) + ", rx errors " + std::to_string(e.rx_error_count));
  if (s.empty()) s = "error frame without class bits";
  return s;
}

CanFrame make_error_frame(std::uint32_t classes, std::array<std::uint8_t, 8> data) noexcept {
  CanFrame f;
  f.error = true;
  f.id = classes & kCanErrMask;
  f.len = 8;
  std::memcpy(f.data.data(), data.data(), 8);
  return f;
}

}  // namespace hil::drivers
