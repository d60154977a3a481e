#include <cmath>
#include <cstdio>
#include <spdlog/spdlog.h>

#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>

namespace hil::drivers {
namespace {

using Clock = std::chrono::steady_clock;

std::chrono::nanoseconds seconds(double s) { return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9)); }

const char* op_name(std::uint8_t op) {
  switch (op) {
    case ati::kOpSerial: return "serial number (opcode 0x5)";
    case ati::kOpFirmware: return "firmware version (opcode 0xF)";
    case ati::kOpUnits: return "units (opcode 0x8)";
    case ati::kOpCounts: return "counts per unit (opcode 0x7)";
    case ati::kOpReadMatrix: return "calibration matrix row (opcode 0x2)";
    default: return "request";
  }
}

bool is_plain(const CanFrame& f) noexcept { return !f.error && !f.extended && !f.rtr && !f.fd; }

}  // namespace

AtiNetCanOemDriver::AtiNetCanOemDriver(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel)
    : CanForcePlate(cfg, std::move(channel)) {
  if (cfg_.protocol != ForcePlateProtocol::ati_netcanoem) throw ConfigError("protocol", "AtiNetCanOemDriver needs protocol ati_netcanoem");
}

void AtiNetCanOemDriver::drain() noexcept {
  CanFrame f;
  const std::uint32_t a = ati::frame_id(cfg_.base_id, ati::kOpReadGauges);
  const std::uint32_t b = ati::frame_id(cfg_.base_id, ati::kOpGaugesSecond);
  while (channel_->receive(f, std::chrono::nanoseconds(0)) == IoStatus::ok) {
    if (f.error) {
      book_error_frame(f);
    } else if (is_plain(f) && ((f.id == a && f.len != 0) || f.id == b)) {
      ++counters_.late_frames;
    }
  }
}

bool AtiNetCanOemDriver::transaction(std::uint8_t opcode, int arg, unsigned frames, std::array<CanFrame, 3>& out) {
  for (int attempt = 0; attempt < cfg_.startup_tries; ++attempt) {
    if (attempt > 0) ++counters_.retries;
    drain();
    const auto st = channel_->send(ati::request(cfg_.base_id, opcode, arg), seconds(cfg_.startup_timeout_s));
    if (st == IoStatus::closed) return false;
    if (st != IoStatus::ok) continue;
    unsigned got = 0;
    const auto deadline = Clock::now() + seconds(cfg_.startup_timeout_s);
    CanFrame f;
    while (got != (1U << frames) - 1U) {
      const auto now = Clock::now();
      if (now >= deadline) break;
      const auto r = channel_->receive(f, deadline - now);
      if (r == IoStatus::closed) return false;
      if (r != IoStatus::ok) continue;
      if (f.error) {
        book_error_frame(f);
        continue;
      }
      if (!is_plain(f) || ati::base_of(f.id) != cfg_.base_id) continue;
      const unsigned k = static_cast<unsigned>(ati::opcode_of(f.id)) - opcode;
      if (ati::opcode_of(f.id) < opcode || k >= frames || f.len == 0) continue;
      out[k] = f;
      got |= 1U << k;
    }
    if (got == (1U << frames) - 1U) return true;
  }
  return false;
}

ForcePlateInfo AtiNetCanOemDriver::start() {
  char where[96];
  std::snprintf(where, sizeof where, "ATI NETCANOEM (base 0x%02X) on %s", cfg_.base_id, channel_->name().c_str());
  auto fail = [&](std::uint8_t op, const std::string& what) -> DeviceError {
    counters_.connected = false;
    return DeviceError(std::string(where) + ": " + op_name(op) + ": " + what);
  };
  auto no_answer = [&](std::uint8_t op) {
    return fail(op, "no answer after " + std::to_string(cfg_.startup_tries) + " tries of " +
                        std::to_string(static_cast<int>(cfg_.startup_timeout_s * 1000)) + " ms");
  };
  ForcePlateInfo info;
  info.protocol = "ati_netcanoem";
  std::array<CanFrame, 3> r;

  if (!transaction(ati::kOpSerial, -1, 1, r)) throw no_answer(ati::kOpSerial);
  info.serial = ati::decode_serial(r[0]);

  if (!transaction(ati::kOpFirmware, -1, 1, r)) throw no_answer(ati::kOpFirmware);
  ati::Firmware fw;
  if (!ati::decode_firmware(r[0], fw)) throw fail(ati::kOpFirmware, "answer of length " + std::to_string(r[0].len) + ", expected 4");
  info.firmware = std::to_string(fw.major) + "." + std::to_string(fw.minor) + "." + std::to_string(fw.build);

  if (!transaction(ati::kOpUnits, -1, 1, r)) throw no_answer(ati::kOpUnits);
  std::uint8_t fu = 0, tu = 0;
  if (!ati::decode_units(r[0], fu, tu)) throw fail(ati::kOpUnits, "answer of length " + std::to_string(r[0].len) + ", expected 2");
  const double f_si = ati::force_unit_to_si(fu), t_si = ati::torque_unit_to_si(tu);
  if (f_si == 0.0) throw fail(ati::kOpUnits, "unknown force unit code " + std::to_string(fu));
  if (t_si == 0.0) throw fail(ati::kOpUnits, "unknown torque unit code " + std::to_string(tu));
  info.units = std::string(ati::force_unit_name(fu)) + ", " + ati::torque_unit_name(tu);

  if (!transaction(ati::kOpCounts, -1, 1, r)) throw no_answer(ati::kOpCounts);
  if (!ati::decode_counts(r[0], info.counts_per_force, info.counts_per_torque))
    throw fail(ati::kOpCounts, "answer of length " + std::to_string(r[0].len) + ", expected 8");
  if (info.counts_per_force <= 0 || info.counts_per_torque <= 0)
    throw fail(ati::kOpCounts, "counts per force " + std::to_string(info.counts_per_force) + " and per torque " +
                                   std::to_string(info.counts_per_torque) + " must be > 0");

  for (int row = 0; row < 6; ++row) {
    if (!transaction(ati::kOpReadMatrix, row, 3, r))
      throw fail(ati::kOpReadMatrix,
                 "row " + std::to_string(row) + ": no complete answer (3 frames) after " + std::to_string(cfg_.startup_tries) + " tries");
    ati::MatrixRow m{};
    for (unsigned k = 0; k < 3; ++k)
      if (!ati::decode_matrix_part(r[k], k, m))
        throw fail(ati::kOpReadMatrix, "row " + std::to_string(row) + " frame " + std::to_string(k) + " has length " +
                                           std::to_string(r[k].len) + ", expected 8");
    for (int c = 0; c < 6; ++c) {
      if (!std::isfinite(m[static_cast<std::size_t>(c)]))
        throw fail(ati::kOpReadMatrix, "row " + std::to_string(row) + " column " + std::to_string(c) + " is not finite");
      info.calibration(row, c) = m[static_cast<std::size_t>(c)];
    }
  }
  if (info.calibration.cwiseAbs().maxCoeff() == 0.0) throw fail(ati::kOpReadMatrix, "the calibration matrix is all zeros");

  Vector6d k;
  k << f_si / info.counts_per_force, f_si / info.counts_per_force, f_si / info.counts_per_force, t_si / info.counts_per_torque,
      t_si / info.counts_per_torque, t_si / info.counts_per_torque;
  G_ = k.asDiagonal() * info.calibration;
  started_ = true;
  counters_.connected = true;
  spdlog::info("{}: serial {}, firmware {}, units {}, counts {}/{}", where, info.serial, info.firmware, info.units, info.counts_per_force,
               info.counts_per_torque);
  return info;
}

PollStatus AtiNetCanOemDriver::poll(WrenchSample& out) noexcept {
  ++counters_.polls;
  if (!started_) {
    problem("poll() before start()");
    return PollStatus::disconnected;
  }
  drain();
  out.error_frames = 0;
  const std::uint32_t id_a = ati::frame_id(cfg_.base_id, ati::kOpReadGauges);
  const std::uint32_t id_b = ati::frame_id(cfg_.base_id, ati::kOpGaugesSecond);
  const auto timeout = seconds(cfg_.response_timeout());
  const auto deadline = Clock::now() + timeout;
  if (const auto sst = send_request(ati::request(cfg_.base_id, ati::kOpReadGauges), timeout, "gauge"); sst != PollStatus::ok) return sst;
  bool have_a = false, have_b = false;
  CanFrame f;
  char msg[128];
  for (;;) {
    const auto st = next_data_frame(deadline, f, out, "gauges");
    if (st == PollStatus::timeout) break;
    if (st != PollStatus::ok) return st;
    if (!is_plain(f)) continue;
    if (f.id == id_a && f.len != 0) {
      // A second first frame: the one before was an earlier answer's, late (the plate answers in
      // order, so the newest is ours).
      if (have_a) ++counters_.late_frames;
      std::uint16_t status = 0;
      const bool decoded = ati::decode_gauges_first(f, status, out.gauges);
      out.status_word = status;
      if (!decoded) {
        ++counters_.bad_frames;
        ++counters_.consecutive_failures;
        std::snprintf(msg, sizeof msg, "gauge frame 1 (id 0x%03X) has length %u, expected 8", id_a, f.len);
        problem(msg);
        return PollStatus::bad_frame;
      }
      have_a = true;
      out.t_ns = f.t_ns;
      out.stamp = f.stamp;
    } else if (f.id == id_b) {
      // A second frame before this poll's first one belongs to an earlier answer whose poll gave up
      // between its frames: late. Taking it would tear the reading across two answers.
      if (!have_a) {
        ++counters_.late_frames;
        continue;
      }
      if (!ati::decode_gauges_second(f, out.gauges)) {
        ++counters_.bad_frames;
        ++counters_.consecutive_failures;
        std::snprintf(msg, sizeof msg, "gauge frame 2 (id 0x%03X) has length %u, expected 6", id_b, f.len);
        problem(msg);
        return PollStatus::bad_frame;
      }
      have_b = true;
    }
    if (have_a && have_b) {
      Eigen::Matrix<double, 6, 1> g;
      bool sat = false;
      for (int i = 0; i < 6; ++i) {
        const std::int16_t v = out.gauges[static_cast<std::size_t>(i)];
        sat = sat || v == INT16_MAX || v == INT16_MIN;
        g[i] = v;
      }
      out.gauge_saturated = sat;
      // Any bit is a fault: bit 15 joins every error, and the others (supply, calibration,
      // EEPROM, temperature...) each make the gauges untrustworthy.
      out.device_fault = out.status_word != 0;
      if (out.device_fault) ++counters_.device_faults;
      out.w_sensor.noalias() = G_ * g;
      finish(out);
      counters_.dropped_frames = channel_->stats().rx_dropped;
      return PollStatus::ok;
    }
  }
  return answer_missing(out, have_a ? "gauge frame 2 missing" : have_b ? "gauge frame 1 missing" : "no gauge answer");
}

std::string AtiNetCanOemDriver::describe_status(const WrenchSample& s) const {
  return "ATI status " + ati::describe_status(static_cast<std::uint16_t>(s.status_word));
}

}  // namespace hil::drivers
