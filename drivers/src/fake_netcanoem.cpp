#include <algorithm>
#include <cmath>
#include <deque>
#include <random>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>

namespace hil::drivers {

Matrix6d default_ati_calibration() {
  Matrix6d M;
  M << 60, 3, -2, 1, 2, -1,  //
      -2, 60, 1, -3, 1, 2,   //
      1, -1, 62, 2, -2, 1,   //
      4, 2, -3, 180, 5, -4,  //
      -3, 5, 2, -4, 182, 3,  //
      2, -4, 3, 5, -3, 181;
  return M;
}

Matrix6d plate_to_sensor_wrench(const Eigen::Isometry3d& T_fp_sensor) {
  // The inverse of the drivers' X_fp_sensor (force_plate.cpp), written from the transform itself.
  const Eigen::Matrix3d R = T_fp_sensor.linear();
  const Eigen::Vector3d p = T_fp_sensor.translation();
  Eigen::Matrix3d P;
  P << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  Matrix6d X_sensor_fp = Matrix6d::Zero();
  X_sensor_fp.topLeftCorner<3, 3>() = R.transpose();
  X_sensor_fp.bottomLeftCorner<3, 3>() = -R.transpose() * P;
  X_sensor_fp.bottomRightCorner<3, 3>() = R.transpose();
  return X_sensor_fp;
}

AtiGaugeModel::AtiGaugeModel(const FakeNetCanOemConfig& cfg) {
  const double f_si = ati::force_unit_to_si(cfg.force_units), t_si = ati::torque_unit_to_si(cfg.torque_units);
  if (f_si == 0.0) throw ConfigError("force_units", "unknown ATI force unit code");
  if (t_si == 0.0) throw ConfigError("torque_units", "unknown ATI torque unit code");
  if (cfg.counts_per_force <= 0 || cfg.counts_per_torque <= 0) throw ConfigError("counts", "must be > 0");
  Eigen::FullPivLU<Matrix6d> lu(cfg.calibration);
  if (lu.rank() < 6) throw ConfigError("calibration", "the calibration matrix is singular");
  const Matrix6d X_sensor_fp = plate_to_sensor_wrench(cfg.T_fp_sensor);
  Vector6d to_counts;
  to_counts << cfg.counts_per_force / f_si, cfg.counts_per_force / f_si, cfg.counts_per_force / f_si, cfg.counts_per_torque / t_si,
      cfg.counts_per_torque / t_si, cfg.counts_per_torque / t_si;
  A_ = lu.inverse() * to_counts.asDiagonal() * X_sensor_fp;
}

ati::Gauges AtiGaugeModel::gauges(const Vector6d& w_fp, bool& saturated) const noexcept {
  const Vector6d g = A_ * w_fp;
  ati::Gauges out{};
  saturated = false;
  for (int i = 0; i < 6; ++i) {
    double v = std::nearbyint(g[i]);
    if (!(v == v)) v = 0;
    if (v > 32767.0) {
      v = 32767.0;
      saturated = true;
    } else if (v < -32768.0) {
      v = -32768.0;
      saturated = true;
    }
    out[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(v);
  }
  return out;
}

struct FakeNetCanOemBoard::Impl {
  FakeNetCanOemConfig cfg;
  std::unique_ptr<CanChannel> channel;
  std::shared_ptr<const Scenario> scenario;
  AtiGaugeModel model;
  mutable std::mutex m;  // guards faults, stats
  CanFaults faults;
  WrenchSource source;
  Stats stats;
  std::atomic<bool> stop{false};
  std::chrono::steady_clock::time_point start;
  std::mt19937_64 rng;
  struct Pending {
    std::chrono::steady_clock::time_point due;
    CanFrame frame;
    bool completes_answer;  ///< the last frame of an intact gauge answer
  };
  std::deque<Pending> pending;
  Impl(FakeNetCanOemConfig c, std::unique_ptr<CanChannel> ch, std::shared_ptr<const Scenario> s)
      : cfg(std::move(c)), channel(std::move(ch)), scenario(std::move(s)), model(cfg), faults(cfg.faults), source(scenario, cfg.clock),
        rng(cfg.seed) {}
};

FakeNetCanOemBoard::FakeNetCanOemBoard(FakeNetCanOemConfig cfg, std::unique_ptr<CanChannel> channel,
                                       std::shared_ptr<const Scenario> scenario) {
  if (!channel) throw ConfigError("channel", "no CAN channel given");
  if (!cfg.netft_box && cfg.base_id > ati::kMaxBase) throw ConfigError("base_id", "ATI base id must be 0..0x7F");
  if (cfg.netft_box && cfg.base_id > netft_can::kMaxBase) throw ConfigError("base_id", "the Net F/T's CAN base address must be 0..0x7F9");
  if (cfg.netft_box) {
    (void)cfg.box_calibration.newtons_per_count();  // names a bad count or unit
    (void)cfg.box_calibration.newton_metres_per_count();
  }
  if (!(cfg.clock.speed > 0.0)) throw ConfigError("speed", "must be > 0");
  impl_ = std::make_unique<Impl>(std::move(cfg), std::move(channel), std::move(scenario));
}

FakeNetCanOemBoard::~FakeNetCanOemBoard() { stop(); }

void FakeNetCanOemBoard::start() {
  if (thread_.joinable()) return;
  impl_->stop = false;
  impl_->start = std::chrono::steady_clock::now();
  thread_ = std::jthread([this] { run(); });
}

void FakeNetCanOemBoard::stop() noexcept {
  impl_->stop = true;
  if (thread_.joinable()) thread_.join();
}

void FakeNetCanOemBoard::set_wrench(const Vector6d& w_fp) { impl_->source.set(w_fp); }

void FakeNetCanOemBoard::set_faults(const CanFaults& f) {
  std::lock_guard lk(impl_->m);
  impl_->faults = f;
}

FakeNetCanOemBoard::Stats FakeNetCanOemBoard::stats() const {
  std::lock_guard lk(impl_->m);
  return impl_->stats;
}

void FakeNetCanOemBoard::run() noexcept {
  using Clock = std::chrono::steady_clock;
  Impl& I = *impl_;
  const std::uint32_t base = I.cfg.base_id;
  bool in_bus_off = false;
  Clock::time_point next_error = Clock::now();
  // The Net F/T box's state: its bias (counts) and sample number.
  Vector6d box_bias = Vector6d::Zero();
  std::uint16_t box_sample = 0;
  const Matrix6d X_sensor_fp = plate_to_sensor_wrench(I.cfg.T_fp_sensor);
  Vector6d box_per_si = Vector6d::Zero();
  if (I.cfg.netft_box) {
    const double fc = 1.0 / I.cfg.box_calibration.newtons_per_count(), tc = 1.0 / I.cfg.box_calibration.newton_metres_per_count();
    box_per_si << fc, fc, fc, tc, tc, tc;
  }
  const auto box_counts = [&](double t_s) { return Vector6d(box_per_si.cwiseProduct(X_sensor_fp * I.source.at(t_s))); };
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  // Sends one frame; `completes_answer`: it is the last frame of an intact gauge answer, which is
  // then counted as delivered (the fault soak reconciles that count with what was recorded).
  // The lock is held across the send so that a reader that has the frame sees it counted.
  auto send_now = [&](const CanFrame& f, bool completes_answer) {
    std::lock_guard lk(I.m);
    if (I.channel->send(f, std::chrono::milliseconds(5)) == IoStatus::ok) {
      ++I.stats.frames_sent;
      if (completes_answer) ++I.stats.gauge_answers_delivered;
      return true;
    }
    return false;
  };
  while (!I.stop.load()) {
    const auto now = Clock::now();
    const double t = std::chrono::duration<double>(now - I.start).count();
    CanFaults f;
    {
      std::lock_guard lk(I.m);
      f = I.faults;
    }
    bool silent = f.silent_now;
    for (const auto& w : f.silent) silent = silent || w.contains(t);
    bool bus_off = false;
    for (const auto& w : f.bus_off) bus_off = bus_off || w.contains(t);
    if (bus_off && !in_bus_off) {
      send_now(make_error_frame(kErrBusOff), false);
      std::lock_guard lk(I.m);
      ++I.stats.error_frames_sent;
    } else if (!bus_off && in_bus_off) {
      send_now(make_error_frame(kErrRestarted), false);
      std::lock_guard lk(I.m);
      ++I.stats.error_frames_sent;
    }
    in_bus_off = bus_off;
    if (f.error_frame_rate_hz > 0.0 && now >= next_error) {
      send_now(make_error_frame(kErrCrtl | kErrCnt, {0, kErrCrtlRxPassive, 0, 0, 0, 0, 0, 130}), false);
      {
        std::lock_guard lk(I.m);
        ++I.stats.error_frames_sent;
      }
      next_error = now + std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / f.error_frame_rate_hz));
    }
    while (!I.pending.empty() && I.pending.front().due <= now) {
      const auto& p = I.pending.front();
      send_now(p.frame, p.completes_answer);
      I.pending.pop_front();
    }
    auto wait = std::chrono::nanoseconds(std::chrono::milliseconds(10));
    if (!I.pending.empty()) wait = std::min<std::chrono::nanoseconds>(wait, I.pending.front().due - now);
    if (f.error_frame_rate_hz > 0.0) wait = std::min<std::chrono::nanoseconds>(wait, next_error - now);
    if (wait.count() < 0) wait = std::chrono::nanoseconds(0);
    CanFrame req;
    const auto r = I.channel->receive(req, wait);
    if (r == IoStatus::closed) break;
    if (r != IoStatus::ok || req.error || req.extended || req.rtr || req.fd) continue;
    if (I.cfg.netft_box ? req.id != base || req.len != 1 : ati::base_of(req.id) != base) continue;
    {
      // Faults as they are now (they may have been switched while we waited).
      std::lock_guard lk(I.m);
      f = I.faults;
    }
    const double t_req = std::chrono::duration<double>(Clock::now() - I.start).count();
    silent = f.silent_now;
    for (const auto& w : f.silent) silent = silent || w.contains(t_req);
    bus_off = false;
    for (const auto& w : f.bus_off) bus_off = bus_off || w.contains(t_req);
    // The Net F/T box's commands are mapped onto the board's opcodes: short data is a reading
    // (kOpReadGauges), bias has no answer.
    const std::uint8_t op = I.cfg.netft_box ? (req.data[0] == netft_can::kRequestShortData ? ati::kOpReadGauges : std::uint8_t{0xFF})
                                            : ati::opcode_of(req.id);
    if (I.cfg.netft_box && req.data[0] == netft_can::kRequestBias) {
      box_bias = box_counts(t_req);  // the load now (reads set_wrench's value under the lock itself)
      std::lock_guard lk(I.m);
      ++I.stats.requests;
      continue;
    }
    std::array<CanFrame, 3> answer;
    std::size_t n = 0;
    if (I.cfg.netft_box && op == ati::kOpReadGauges) {
      netft_can::ShortData d;
      const Vector6d c = box_counts(t_req) - box_bias;
      for (int i = 0; i < 6; ++i)
        d.counts[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::clamp(std::nearbyint(c[i]), -32768.0, 32767.0));
      std::uint32_t bits = f.status_now;
      for (const auto& sw : f.status) bits |= sw.window.contains(t_req) ? sw.bits : 0U;
      if ((bits & 0x7FFFU) != 0) bits |= 0x8000U;  // the top bit joins any other, as bit 31 of the box's status word
      d.status = static_cast<std::uint16_t>(bits);
      d.sample = ++box_sample;
      const auto fr = netft_can::encode_short(base, d);
      answer[0] = fr[0];
      answer[1] = fr[1];
      n = 2;
    }
    switch (I.cfg.netft_box ? std::uint8_t{0xFE} : op) {
      case 0xFE:
        if (n == 0) continue;  // a box command the fake does not know
        break;
      case ati::kOpReadGauges: {
        if (req.len != 0) continue;  // another device's answer
        const Vector6d w = I.source.at(std::chrono::duration<double>(Clock::now() - I.start).count());
        bool sat = false;
        const ati::Gauges g = I.model.gauges(w, sat);
        std::uint32_t bits = f.status_now;
        for (const auto& sw : f.status) bits |= sw.window.contains(t_req) ? sw.bits : 0U;
        if (f.error_frame_rate_hz > 0.0 || bus_off) bits |= ati::kStatusCanBusError;
        if ((bits & 0x7FFFU) != 0) bits |= ati::kStatusAnyError;
        const auto status = static_cast<std::uint16_t>(bits);
        const auto fr = ati::encode_gauges(base, status, g);
        answer[0] = fr[0];
        answer[1] = fr[1];
        n = 2;
        break;
      }
      case ati::kOpReadMatrix: {
        if (req.len != 1 || req.data[0] > 5) continue;
        ati::MatrixRow row{};
        for (int c = 0; c < 6; ++c) row[static_cast<std::size_t>(c)] = static_cast<float>(I.cfg.calibration(req.data[0], c));
        const auto fr = ati::encode_matrix_row(base, row);
        for (std::size_t k = 0; k < 3; ++k) answer[k] = fr[k];
        n = 3;
        break;
      }
      case ati::kOpSerial:
        answer[0] = ati::encode_serial(base, I.cfg.serial);
        n = 1;
        break;
      case ati::kOpCounts:
        answer[0] = ati::encode_counts(base, I.cfg.counts_per_force, I.cfg.counts_per_torque);
        n = 1;
        break;
      case ati::kOpUnits:
        answer[0] = ati::encode_units(base, I.cfg.force_units, I.cfg.torque_units);
        n = 1;
        break;
      case ati::kOpFirmware:
        answer[0] = ati::encode_firmware(base, I.cfg.firmware);
        n = 1;
        break;
      default: continue;
    }
    bool intact = true;  // no frame of the answer corrupted, dropped or refused by the channel
    {
      std::lock_guard lk(I.m);
      ++I.stats.requests;
      if (silent || bus_off) {
        ++I.stats.ignored_silent;
        continue;
      }
      if (op == ati::kOpReadGauges) ++I.stats.gauge_answers;
      if (f.corrupt_fraction > 0.0 && uni(I.rng) < f.corrupt_fraction) {
        ++I.stats.answers_corrupted;
        answer[0].len = static_cast<std::uint8_t>(answer[0].len >= 4 ? answer[0].len - 3 : answer[0].len + 1);
        intact = false;
      }
    }
    const auto due = Clock::now() + std::chrono::nanoseconds(static_cast<std::int64_t>(f.extra_delay_s * 1e9));
    for (std::size_t k = 0; k < n; ++k) {
      if (f.drop_fraction > 0.0) {
        bool drop;
        {
          std::lock_guard lk(I.m);
          drop = uni(I.rng) < f.drop_fraction;
          if (drop) ++I.stats.frames_dropped;
        }
        if (drop) {
          intact = false;
          continue;
        }
      }
      const bool completes = intact && op == ati::kOpReadGauges && k + 1 == n;
      if (f.extra_delay_s > 0.0) I.pending.push_back({due, answer[k], completes});
      else intact = send_now(answer[k], completes) && intact;
    }
  }
}

}  // namespace hil::drivers
