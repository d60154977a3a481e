// Read-only Modbus client. Only modbus_read_registers / modbus_read_input_registers are used here;
// tests/drivers checks that no write function appears in this file.
#include <hil/drivers/robot_controller.hpp>

#include <modbus/modbus.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/error.hpp>
#include <hil/so3/so3.hpp>

namespace hil::drivers {

void ModbusConfig::validate() const {
  if (transport == ModbusTransport::tcp) {
    if (host.empty()) throw ConfigError("host", "empty");
    if (port < 1 || port > 65535) throw ConfigError("port", "must be 1..65535, got " + std::to_string(port));
  } else {
    if (serial_device.empty()) throw ConfigError("serial_device", "an RTU link needs a serial device");
    if (baud <= 0) throw ConfigError("baud", "must be > 0");
    if (parity != 'N' && parity != 'E' && parity != 'O') throw ConfigError("parity", "must be N, E or O");
    if (data_bits < 5 || data_bits > 8) throw ConfigError("data_bits", "must be 5..8");
    if (stop_bits != 1 && stop_bits != 2) throw ConfigError("stop_bits", "must be 1 or 2");
  }
  if (unit_id < 0 || unit_id > 255) throw ConfigError("unit_id", "must be 0..255");
  if (!(rate_hz > 0.0) || rate_hz > 10000.0) throw ConfigError("rate_hz", "must be in (0, 10000]");
  if (!(timeout_s > 0.0) || timeout_s > 60.0) throw ConfigError("timeout_s", "must be in (0, 60]");
  if (retries < 0 || retries > 10) throw ConfigError("retries", "must be 0..10");
  if (!(reconnect_min_s > 0.0) || !(reconnect_max_s >= reconnect_min_s))
    throw ConfigError("reconnect_min_s", "need 0 < reconnect_min_s <= reconnect_max_s");
  map.validate();
  if (kinematics) {
    if (kinematics->joints == 0 || !kinematics->T_base_tool) throw ConfigError("kinematics", "no joints or no forward kinematics given");
    if (map.joint_count() < kinematics->joints)
      throw ConfigError("kinematics", "the robot has " + std::to_string(kinematics->joints) + " joints but the register map reads " +
                                          std::to_string(map.joint_count()));
  }
}

std::string ModbusConfig::describe() const {
  char buf[256];
  if (transport == ModbusTransport::tcp) std::snprintf(buf, sizeof buf, "Modbus TCP %s:%d unit %d", host.c_str(), port, unit_id);
  else
    std::snprintf(buf, sizeof buf, "Modbus RTU %s %d %d%c%d unit %d", serial_device.c_str(), baud, data_bits, parity, stop_bits, unit_id);
  return buf;
}

struct RobotControllerDriver::Impl {
  modbus_t* ctx = nullptr;
  bool connected = false;
  ~Impl() { reset(); }
  void reset() noexcept {
    if (ctx != nullptr) {
      if (connected) modbus_close(ctx);
      modbus_free(ctx);
    }
    ctx = nullptr;
    connected = false;
  }
};

RobotControllerDriver::RobotControllerDriver(ModbusConfig cfg) : cfg_(std::move(cfg)), impl_(std::make_unique<Impl>()) {
  cfg_.validate();
  plan_ = plan_reads(cfg_.map);
  unsigned max_h = 0, max_i = 0;
  for (const auto& b : plan_)
    (b.table == RegisterTable::holding ? max_h : max_i) = std::max(b.table == RegisterTable::holding ? max_h : max_i, b.address + b.count);
  holding_.assign(max_h, 0);
  input_.assign(max_i, 0);
  holding_again_.assign(max_h, 0);
  input_again_.assign(max_i, 0);
  for (const auto& e : cfg_.map.entries) decoded_.push_back(Decoded{parse_quantity(e.quantity, "quantity"), &e});
  const auto block_of = [&](RegisterTable table, unsigned address) {
    for (std::size_t k = 0; k < plan_.size(); ++k)
      if (plan_[k].table == table && address >= plan_[k].address && address < plan_[k].address + plan_[k].count) return k;
    return plan_.size();  // not reached: the plan covers every register of the map
  };
  const auto add_once = [](std::vector<std::size_t>& v, std::size_t k) {
    if (std::find(v.begin(), v.end(), k) == v.end()) v.push_back(k);
  };
  for (const auto& e : cfg_.map.entries) {
    if (e.turns_address < 0) continue;
    const std::size_t a = block_of(e.table, e.address), t = block_of(e.table, static_cast<unsigned>(e.turns_address));
    if (a == t) continue;  // one request reads both: consistent by construction
    add_once(angle_blocks_, a);
    add_once(turn_blocks_, t);
    split_turned_.push_back(&e);
  }
  backoff_s_ = cfg_.reconnect_min_s;
  last_problem_.reserve(256);
}

RobotControllerDriver::~RobotControllerDriver() = default;

void RobotControllerDriver::set_problem(const char* what, int err) noexcept {
  char buf[256];
  if (err != 0) std::snprintf(buf, sizeof buf, "%s: %s", what, modbus_strerror(err));
  else std::snprintf(buf, sizeof buf, "%s", what);
  try {
    last_problem_.assign(buf);
  } catch (...) {
  }
}

bool RobotControllerDriver::try_connect() noexcept {
  impl_->reset();
  if (cfg_.transport == ModbusTransport::tcp) impl_->ctx = modbus_new_tcp(cfg_.host.c_str(), cfg_.port);
  else impl_->ctx = modbus_new_rtu(cfg_.serial_device.c_str(), cfg_.baud, cfg_.parity, cfg_.data_bits, cfg_.stop_bits);
  if (impl_->ctx == nullptr) {
    set_problem("cannot create the libmodbus context", errno);
    return false;
  }
  modbus_set_slave(impl_->ctx, cfg_.unit_id);
  const double t = cfg_.timeout_s;
  modbus_set_response_timeout(impl_->ctx, static_cast<std::uint32_t>(t), static_cast<std::uint32_t>((t - std::floor(t)) * 1e6));
  modbus_set_error_recovery(impl_->ctx, MODBUS_ERROR_RECOVERY_NONE);
  if (modbus_connect(impl_->ctx) != 0) {
    set_problem("connect failed", errno);
    impl_->reset();
    return false;
  }
  impl_->connected = true;
  counters_.connected = true;
  return true;
}

void RobotControllerDriver::connect() {
  if (!try_connect()) {
    counters_.connected = false;
    throw DeviceError(cfg_.describe() + ": " + last_problem_);
  }
  ever_connected_ = true;
  backoff_s_ = cfg_.reconnect_min_s;
}

ControllerIdentity RobotControllerDriver::identify() noexcept {
  ControllerIdentity id;
  if (impl_->ctx == nullptr || !impl_->connected) {
    id.error = "not connected";
    return id;
  }
  std::uint8_t answer[MODBUS_MAX_PDU_LENGTH] = {};
  const int n = modbus_report_slave_id(impl_->ctx, static_cast<int>(sizeof answer), answer);
  if (n < 0) {
    id.error = modbus_strerror(errno);
    modbus_flush(impl_->ctx);
    return id;
  }
  id.answered = true;
  if (n >= 1) id.server_id = answer[0];
  if (n >= 2) id.running = answer[1] == 0xFF;
  for (int i = 2; i < n && i < static_cast<int>(sizeof answer); ++i) {
    const auto c = answer[i];
    if (c >= 0x20 && c < 0x7F) {
      id.text += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      id.text += hex;
    }
  }
  return id;
}

void RobotControllerDriver::disconnect() noexcept {
  impl_->reset();
  counters_.connected = false;
}

PollStatus RobotControllerDriver::read_block(const ReadBlock& b, std::uint16_t* dst) noexcept {
  using Clock = std::chrono::steady_clock;
  for (int attempt = 0;; ++attempt) {
    const int rc = b.table == RegisterTable::holding
                       ? modbus_read_registers(impl_->ctx, static_cast<int>(b.address), static_cast<int>(b.count), dst)
                       : modbus_read_input_registers(impl_->ctx, static_cast<int>(b.address), static_cast<int>(b.count), dst);
    if (rc == static_cast<int>(b.count)) return PollStatus::ok;
    const int err = rc < 0 ? errno : EMBBADDATA;
    if (err > MODBUS_ENOBASE && err <= MODBUS_ENOBASE + MODBUS_EXCEPTION_GATEWAY_TARGET) {
      ++counters_.exceptions;
      ++counters_.device_faults;  // the device refused: a fault it reports, like a status bit
      ++counters_.consecutive_failures;
      set_problem("exception response", err);
      return PollStatus::exception;
    }
    const bool link_lost = err == ECONNRESET || err == EPIPE || err == ENOTCONN || err == EBADF || err == ECONNREFUSED ||
                           err == ECONNABORTED || err == EIO;
    if (!link_lost && attempt < cfg_.retries) {
      ++counters_.retries;
      modbus_flush(impl_->ctx);
      continue;
    }
    ++counters_.consecutive_failures;
    const bool timeout = err == ETIMEDOUT;
    if (timeout) ++counters_.timeouts;
    else if (!link_lost) ++counters_.bad_frames;
    set_problem(link_lost ? "link lost" : timeout ? "no answer" : "garbled answer", err);
    // Start over on a fresh connection; the next poll reconnects right away, then backs off.
    impl_->reset();
    counters_.connected = false;
    next_attempt_ = Clock::now();
    return link_lost ? PollStatus::disconnected : timeout ? PollStatus::timeout : PollStatus::bad_frame;
  }
}

PollStatus RobotControllerDriver::read_untorn() noexcept {
  // A UR joint crossing 0 rad between the angle request and the counter request decodes a full
  // turn off (6.282 rad for -0.001). Reading the angles again brackets the counter read: if no
  // angle wrapped between the two angle reads, the counter read between them is theirs.
  constexpr int kRounds = 4;  // a joint sitting on 0 rad may flicker; more than this is a fault
  for (int round = 0; !angle_blocks_.empty(); ++round) {
    for (const std::size_t k : angle_blocks_) {
      const ReadBlock& b = plan_[k];
      std::uint16_t* dst = (b.table == RegisterTable::holding ? holding_again_.data() : input_again_.data()) + b.address;
      if (const PollStatus st = read_block(b, dst); st != PollStatus::ok) return st;
    }
    bool wrapped = false;
    for (const RegisterEntry* e : split_turned_) {
      const bool h = e->table == RegisterTable::holding;
      const double first = decode_entry(*e, (h ? holding_ : input_).data() + e->address);
      const double again = decode_entry(*e, (h ? holding_again_ : input_again_).data() + e->address);
      wrapped = wrapped || std::abs(again - first) > std::numbers::pi;
    }
    if (!wrapped) return PollStatus::ok;
    ++counters_.torn_reads;
    if (round + 1 == kRounds) {
      ++counters_.bad_frames;
      ++counters_.consecutive_failures;
      set_problem("a joint angle kept wrapping between its angle and turn-counter reads", 0);
      return PollStatus::bad_frame;
    }
    // The second angles become the first; the counters are read after them, then angles again.
    for (const std::size_t k : angle_blocks_) {
      const ReadBlock& b = plan_[k];
      const auto& src = b.table == RegisterTable::holding ? holding_again_ : input_again_;
      auto& dst = b.table == RegisterTable::holding ? holding_ : input_;
      std::copy_n(src.begin() + b.address, b.count, dst.begin() + b.address);
    }
    for (const std::size_t k : turn_blocks_) {
      const ReadBlock& b = plan_[k];
      std::uint16_t* dst = (b.table == RegisterTable::holding ? holding_.data() : input_.data()) + b.address;
      if (const PollStatus st = read_block(b, dst); st != PollStatus::ok) return st;
    }
  }
  return PollStatus::ok;
}

PollStatus RobotControllerDriver::poll(RobotSample& out) noexcept {
  ++counters_.polls;
  using Clock = std::chrono::steady_clock;
  if (!impl_->connected) {
    const auto now = Clock::now();
    if (now < next_attempt_) return PollStatus::disconnected;
    if (!try_connect()) {
      counters_.connected = false;
      ++counters_.consecutive_failures;
      next_attempt_ = now + std::chrono::nanoseconds(static_cast<std::int64_t>(backoff_s_ * 1e9));
      backoff_s_ = std::min(backoff_s_ * 2.0, cfg_.reconnect_max_s);
      return PollStatus::disconnected;
    }
    if (ever_connected_) ++counters_.reconnects;
    ever_connected_ = true;
    backoff_s_ = cfg_.reconnect_min_s;
  }
  const std::int64_t t0 = realtime_ns();
  for (const ReadBlock& b : plan_) {
    std::uint16_t* dst = (b.table == RegisterTable::holding ? holding_.data() : input_.data()) + b.address;
    if (const PollStatus st = read_block(b, dst); st != PollStatus::ok) return st;
  }
  if (const PollStatus st = read_untorn(); st != PollStatus::ok) return st;
  const std::int64_t t1 = realtime_ns();
  out.t_ns = t0 + (t1 - t0) / 2;
  out.rtt_ns = t1 - t0;
  out.joint_count = 0;
  out.has_pose = false;
  double pose[6] = {0, 0, 0, 0, 0, 0};
  int pose_parts = 0;
  for (const Decoded& d : decoded_) {
    const RegisterEntry& e = *d.e;
    const std::uint16_t* img = e.table == RegisterTable::holding ? holding_.data() : input_.data();
    const std::int16_t turns = e.turns_address >= 0 ? static_cast<std::int16_t>(img[e.turns_address]) : 0;
    const double v = decode_entry(e, img + e.address, turns);
    if (d.q.kind == Quantity::Kind::joint) {
      out.joints[d.q.joint] = v;
      out.joint_count = std::max(out.joint_count, d.q.joint + 1);
    } else {
      pose[static_cast<int>(d.q.kind) - 1] = v;
      ++pose_parts;
    }
  }
  if (pose_parts == 6) {
    out.has_pose = true;
    out.p_base_tcp_m = Eigen::Vector3d(pose[0], pose[1], pose[2]);
    out.r_base_tcp = Eigen::Vector3d(pose[3], pose[4], pose[5]);
    const double angle = out.r_base_tcp.norm();
    out.q_base_tcp = angle > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, out.r_base_tcp / angle)) : Eigen::Quaterniond::Identity();
  }
  out.pose_from_kinematics = false;
  if (!out.has_pose && cfg_.kinematics) {
    const Eigen::Isometry3d T = cfg_.kinematics->T_base_tool(out.joints.data());
    out.has_pose = true;
    out.pose_from_kinematics = true;
    out.p_base_tcp_m = T.translation();
    out.q_base_tcp = Eigen::Quaterniond(T.linear());
    out.r_base_tcp = so3::log(out.q_base_tcp);
  }
  out.sequence = ++sequence_;
  ++counters_.samples;
  counters_.consecutive_failures = 0;
  counters_.connected = true;
  return PollStatus::ok;
}

}  // namespace hil::drivers
