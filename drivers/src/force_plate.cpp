#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/netft_driver.hpp>

namespace hil::drivers {

const char* to_string(PollStatus s) noexcept {
  switch (s) {
    case PollStatus::ok: return "ok";
    case PollStatus::timeout: return "timeout";
    case PollStatus::bad_frame: return "bad frame";
    case PollStatus::bus_error: return "bus error";
    case PollStatus::exception: return "exception response";
    case PollStatus::disconnected: return "disconnected";
    case PollStatus::closed: return "closed";
  }
  return "?";
}

WrenchComponent parse_wrench_component(const std::string& s, const std::string& field) {
  static const char* names[] = {"fx", "fy", "fz", "mx", "my", "mz", "status"};
  for (unsigned i = 0; i < 7; ++i)
    if (s == names[i]) return static_cast<WrenchComponent>(i);
  throw ConfigError(field, "'" + s + "' is not a wrench component (fx fy fz mx my mz status)");
}

const char* to_string(WrenchComponent c) noexcept {
  static const char* names[] = {"fx", "fy", "fz", "mx", "my", "mz", "status"};
  const auto i = static_cast<unsigned>(c);
  return i < 7 ? names[i] : "?";
}

// ---- declarative signal bits -------------------------------------------------------------------

std::int64_t extract_raw(const CanSignal& s, const std::uint8_t* data) noexcept {
  std::uint64_t v = 0;
  const unsigned len = s.length_bits;
  if (!s.big_endian) {
    unsigned pos = s.start_bit;
    if ((pos & 7) == 0 && (len & 7) == 0) {  // byte aligned: whole bytes, least significant first
      for (unsigned b = len / 8; b-- > 0;) v = (v << 8) | data[pos / 8 + b];
    } else {
      for (unsigned i = 0; i < len; ++i, ++pos) v |= static_cast<std::uint64_t>((data[pos >> 3] >> (pos & 7)) & 1U) << i;
    }
  } else {
    unsigned pos = s.start_bit;
    if ((pos & 7) == 7 && (len & 7) == 0) {  // byte aligned Motorola: most significant byte first
      for (unsigned b = 0; b < len / 8; ++b) v = (v << 8) | data[pos / 8 + b];
    } else {
      for (unsigned i = 0; i < len; ++i) {
        v = (v << 1) | ((data[pos >> 3] >> (pos & 7)) & 1U);
        pos = (pos & 7) == 0 ? pos + 15 : pos - 1;
      }
    }
  }
  if (s.is_signed && len < 64 && ((v >> (len - 1)) & 1U) != 0) v |= ~((std::uint64_t{1} << len) - 1);
  return static_cast<std::int64_t>(v);
}

void insert_raw(const CanSignal& s, std::int64_t raw, std::uint8_t* data) noexcept {
  const auto v = static_cast<std::uint64_t>(raw);
  const unsigned len = s.length_bits;
  unsigned pos = s.start_bit;
  for (unsigned i = 0; i < len; ++i) {
    const unsigned bit_index = s.big_endian ? len - 1 - i : i;
    const auto bit = static_cast<std::uint8_t>((v >> bit_index) & 1U);
    data[pos >> 3] = static_cast<std::uint8_t>((data[pos >> 3] & ~(1U << (pos & 7))) | (bit << (pos & 7)));
    if (s.big_endian) pos = (pos & 7) == 0 ? pos + 15 : pos - 1;
    else ++pos;
  }
}

namespace {
/// Highest byte index a signal touches, or -1 if it runs outside 64 bytes (or below bit 0).
int last_byte(const CanSignal& s) noexcept {
  int maxb = -1;
  long pos = s.start_bit;
  for (unsigned i = 0; i < s.length_bits; ++i) {
    if (pos < 0 || pos >= 512) return -1;
    maxb = std::max(maxb, static_cast<int>(pos >> 3));
    if (s.big_endian) pos = (pos & 7) == 0 ? pos + 15 : pos - 1;
    else ++pos;
  }
  return maxb;
}
}  // namespace

unsigned bytes_needed(const CanSignal& s) noexcept {
  const int b = last_byte(s);
  return b < 0 ? 0U : static_cast<unsigned>(b + 1);
}

void validate_signals(const std::vector<CanSignal>& signals) {
  if (signals.empty()) throw ConfigError("signals", "the declarative protocol needs at least one signal");
  std::set<WrenchComponent> seen;
  std::set<std::pair<std::uint32_t, bool>> frames;
  for (std::size_t i = 0; i < signals.size(); ++i) {
    const auto& s = signals[i];
    const std::string f = "signals[" + std::to_string(i) + "].";
    if (static_cast<unsigned>(s.component) > static_cast<unsigned>(WrenchComponent::status))
      throw ConfigError(f + "component", "unknown component");
    if (!seen.insert(s.component).second)
      throw ConfigError(f + "component", std::string("'") + to_string(s.component) + "' is decoded twice");
    if (s.extended_id ? s.frame_id > kCanEffMask : s.frame_id > kCanSffMask)
      throw ConfigError(f + "frame_id", s.extended_id ? "exceeds 29 bits" : "exceeds 11 bits (0x7FF); set extended_id");
    if (s.length_bits < 1 || s.length_bits > 64) throw ConfigError(f + "length_bits", "must be 1..64");
    if (s.start_bit > 511) throw ConfigError(f + "start_bit", "must be 0..511");
    if (last_byte(s) < 0)
      throw ConfigError(f + "start_bit", "the signal runs outside the frame (" + std::string(s.big_endian ? "big" : "little") +
                                             " endian, start " + std::to_string(s.start_bit) + ", length " + std::to_string(s.length_bits) +
                                             ")");
    if (!std::isfinite(s.scale) || s.scale == 0.0) throw ConfigError(f + "scale", "must be finite and non-zero");
    if (!std::isfinite(s.offset)) throw ConfigError(f + "offset", "must be finite");
    if (s.component == WrenchComponent::status && s.length_bits > 16)
      throw ConfigError(f + "length_bits", "a status signal has at most 16 bits");
    frames.insert({s.frame_id, s.extended_id});
  }
  if (frames.size() > 64) throw ConfigError("signals", "at most 64 distinct frames");
}

// ---- configuration -----------------------------------------------------------------------------

void ForcePlateConfig::validate() const {
  if (!(rate_hz > 0.0) || rate_hz > 20000.0) throw ConfigError("rate_hz", "must be in (0, 20000]");
  if (protocol == ForcePlateProtocol::ati_netcanoem && base_id > ati::kMaxBase)
    throw ConfigError("base_id", "ATI base id must be 0..0x7F (11-bit id = base << 4 | opcode)");
  const Eigen::Matrix3d R = T_fp_sensor.linear();
  if (!R.allFinite() || !T_fp_sensor.translation().allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      R.determinant() < 0.0)
    throw ConfigError("sensor_pose", "T_fp_sensor is not a rigid transform");
  if (!saturation_limits.empty()) {
    if (saturation_limits.size() != 6)
      throw ConfigError("saturation_limits", "needs 6 values (fx fy fz mx my mz), got " + std::to_string(saturation_limits.size()));
    for (std::size_t i = 0; i < 6; ++i)
      if (!(saturation_limits[i] > 0.0)) throw ConfigError("saturation_limits[" + std::to_string(i) + "]", "must be > 0");
  }
  if (!(response_timeout_s >= 0.0) || response_timeout_s > 10.0) throw ConfigError("response_timeout_s", "must be in [0, 10]");
  if (!(startup_timeout_s > 0.0) || startup_timeout_s > 10.0) throw ConfigError("startup_timeout_s", "must be in (0, 10]");
  if (startup_tries < 1) throw ConfigError("startup_tries", "must be ≥ 1");
  if (tare_samples < 1) throw ConfigError("tare_samples", "must be ≥ 1");
  if (protocol == ForcePlateProtocol::declarative) validate_signals(signals);
  if (protocol == ForcePlateProtocol::ati_netft_can) {
    if (base_id > netft_can::kMaxBase)
      throw ConfigError("base_id", "the Net F/T's CAN base address must be 0..0x7F9 (answers on base+5, base+6)");
    (void)netft_calibration.newtons_per_count();
    (void)netft_calibration.newton_metres_per_count();
  }
  if (protocol == ForcePlateProtocol::ati_netft_rdt) {
    if (host.empty()) throw ConfigError("host", "the Net F/T box's address is needed (its web page shows it; factory 192.168.1.1)");
    if (port < 1 || port > 65535) throw ConfigError("port", "must be 1..65535, got " + std::to_string(port));
    (void)netft_calibration.newtons_per_count();  // names counts_per_force / force_unit
    (void)netft_calibration.newton_metres_per_count();
  }
  if (protocol == ForcePlateProtocol::robotiq_ft300) {
    if (serial_device.empty()) throw ConfigError("device", "the FT 300's serial port is needed (e.g. /dev/ttyUSB0)");
    if (serial_baud != robotiq::kBaud)
      throw ConfigError("baud", "the FT 300 speaks at 19200 baud only, got " + std::to_string(serial_baud));
    if (modbus_slave < 1 || modbus_slave > 247)
      throw ConfigError("slave", "must be 1..247 (the FT 300's is 9), got " + std::to_string(modbus_slave));
    // 19200 baud carries one 6-register read (25 bytes each way, with the gaps) about every 15 ms.
    if (!robotiq_stream && rate_hz > 50.0)
      throw ConfigError("rate_hz",
                        "polling the FT 300 over Modbus reaches 50 Hz at most; allow the stream-start write for its 100 Hz stream");
  }
}

const char* to_string(ForcePlateProtocol p) noexcept {
  switch (p) {
    case ForcePlateProtocol::ati_netcanoem: return "ati_netcanoem";
    case ForcePlateProtocol::declarative: return "declarative";
    case ForcePlateProtocol::ati_netft_rdt: return "ati_netft_rdt";
    case ForcePlateProtocol::robotiq_ft300: return "robotiq_ft300";
    case ForcePlateProtocol::ati_netft_can: return "ati_netft_can";
  }
  return "?";
}

double ForcePlateConfig::response_timeout() const noexcept {
  if (response_timeout_s > 0.0) return response_timeout_s;
  if (protocol == ForcePlateProtocol::robotiq_ft300 && !robotiq_stream) return 0.1;  // a Modbus RTU answer at 19200 baud
  // Request and answer within the period on CAN; a pushed stream may be a few periods late.
  const bool request_answer = protocol == ForcePlateProtocol::ati_netcanoem || protocol == ForcePlateProtocol::ati_netft_can;
  return request_answer ? 0.9 / rate_hz : 3.0 / rate_hz;
}

// ---- common part -------------------------------------------------------------------------------

ForcePlate::ForcePlate(const ForcePlateConfig& cfg) : cfg_(cfg) {
  cfg_.validate();
  const Eigen::Matrix3d R = cfg_.T_fp_sensor.linear();
  const Eigen::Vector3d p = cfg_.T_fp_sensor.translation();
  Eigen::Matrix3d P;
  P << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  X_fp_sensor_.setZero();
  X_fp_sensor_.topLeftCorner<3, 3>() = R;
  X_fp_sensor_.bottomLeftCorner<3, 3>().noalias() = P * R;
  X_fp_sensor_.bottomRightCorner<3, 3>() = R;
  if (cfg_.saturation_limits.size() == 6) {
    have_limits_ = true;
    for (std::size_t i = 0; i < 6; ++i) limits_[i] = cfg_.saturation_limits[i];
  }
  last_problem_.reserve(256);
}

void ForcePlate::tare(unsigned samples) noexcept { tare_request_.store(samples == 0 ? cfg_.tare_samples : samples); }
void ForcePlate::clear_tare() noexcept { clear_request_.store(true); }
Vector6d ForcePlate::tare_bias() const { return bias_; }

void ForcePlate::finish(WrenchSample& s) noexcept {
  if (clear_request_.exchange(false)) {
    bias_.setZero();
    tare_target_ = 0;
  }
  if (const unsigned n = tare_request_.exchange(0); n != 0) {
    tare_target_ = n;
    tare_count_ = 0;
    tare_sum_.setZero();
  }
  s.taring = false;
  if (tare_target_ != 0) {
    s.taring = true;
    tare_sum_ += s.w_sensor;
    if (++tare_count_ >= tare_target_) {
      bias_ = tare_sum_ / static_cast<double>(tare_count_);
      tare_target_ = 0;
    }
  }
  s.w_fp.noalias() = X_fp_sensor_ * (s.w_sensor - bias_);
  s.saturated_axes = 0;
  if (have_limits_)
    for (unsigned i = 0; i < 6; ++i)
      if (std::abs(s.w_fp[i]) >= limits_[i]) s.saturated_axes |= static_cast<std::uint8_t>(1U << i);
  s.sequence = ++sequence_;
  ++counters_.samples;
  counters_.consecutive_failures = 0;
  counters_.connected = true;
  counters_.bus_off = false;
}

CanForcePlate::CanForcePlate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel)
    : ForcePlate(cfg), channel_(std::move(channel)) {
  if (!channel_) throw ConfigError("channel", "no CAN channel given");
}

std::string CanForcePlate::describe_link_errors(const WrenchSample& s) const {
  if (s.error_frames == 0) return {};
  return std::to_string(s.error_frames) + " CAN error frame(s): " + describe(last_bus_error_);
}

void CanForcePlate::book_error_frame(const CanFrame& f) noexcept {
  ++counters_.error_frames;
  last_bus_error_ = decode_error_frame(f);
  if (last_bus_error_.bus_off) {
    if (!counters_.bus_off) ++counters_.bus_off_events;
    counters_.bus_off = true;
  } else if (last_bus_error_.restarted || last_bus_error_.back_to_active) {
    counters_.bus_off = false;
  }
}

PollStatus CanForcePlate::send_request(const CanFrame& request, std::chrono::nanoseconds timeout, const char* what) noexcept {
  const auto st = channel_->send(request, timeout);
  if (st == IoStatus::ok) return PollStatus::ok;
  if (st == IoStatus::closed) {
    problem("CAN channel closed");
    return PollStatus::closed;
  }
  ++counters_.consecutive_failures;
  ++counters_.timeouts;
  char msg[128];
  std::snprintf(msg, sizeof msg, "%s %s", what, st == IoStatus::timeout ? "request: transmit queue full" : "request could not be sent");
  problem(msg);
  return counters_.bus_off ? PollStatus::bus_error : PollStatus::timeout;
}

PollStatus CanForcePlate::answer_missing(const WrenchSample& out, const char* missing) noexcept {
  ++counters_.timeouts;
  ++counters_.consecutive_failures;
  char msg[128];
  if (counters_.bus_off) {
    std::snprintf(msg, sizeof msg, "%s: bus-off", missing);
    problem(msg);
    return PollStatus::bus_error;
  }
  if (out.error_frames != 0) {
    std::snprintf(msg, sizeof msg, "%s: CAN error frames", missing);
    problem(msg);
    return PollStatus::bus_error;
  }
  problem(missing);
  return PollStatus::timeout;
}

PollStatus CanForcePlate::next_data_frame(std::chrono::steady_clock::time_point deadline, CanFrame& f, WrenchSample& out,
                                          const char* context) noexcept {
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return PollStatus::timeout;
    const auto r = channel_->receive(f, deadline - now);
    if (r == IoStatus::timeout) return PollStatus::timeout;
    if (r == IoStatus::closed) {
      problem("CAN channel closed");
      return PollStatus::closed;
    }
    if (r == IoStatus::error) {
      ++counters_.bad_frames;
      ++counters_.consecutive_failures;
      char msg[128];
      std::snprintf(msg, sizeof msg, "CAN channel error while waiting for %s", context);
      problem(msg);
      return PollStatus::bad_frame;
    }
    if (!f.error) return PollStatus::ok;
    book_error_frame(f);
    ++out.error_frames;
    if (last_bus_error_.bus_off) {  // the controller is off the bus: no answer will come, say so now
      ++counters_.consecutive_failures;
      problem("bus-off (error frame from the CAN controller)");
      return PollStatus::bus_error;
    }
  }
}

void ForcePlate::problem(const char* what) noexcept {
  try {
    last_problem_.assign(what);
  } catch (...) {
  }
}

std::unique_ptr<CanForcePlate> make_force_plate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel) {
  if (cfg.protocol == ForcePlateProtocol::declarative) return std::make_unique<DeclarativeForcePlate>(cfg, std::move(channel));
  if (cfg.protocol == ForcePlateProtocol::ati_netft_can) return std::make_unique<NetFtCanDriver>(cfg, std::move(channel));
  return std::make_unique<AtiNetCanOemDriver>(cfg, std::move(channel));
}

std::string ForcePlate::describe_status(const WrenchSample& s) const {
  char buf[32];
  std::snprintf(buf, sizeof buf, "status 0x%08X", s.status_word);
  return buf;
}

std::string ForcePlate::describe_link_errors(const WrenchSample&) const { return {}; }

std::string ForcePlate::describe_fault(const WrenchSample& s) const {
  std::string out = s.device_fault ? "the force plate flags its reading: " + describe_status(s) : std::string();
  const std::string link_errors = describe_link_errors(s);
  if (!link_errors.empty()) out += (out.empty() ? "" : "; ") + link_errors;
  return out;
}

}  // namespace hil::drivers
