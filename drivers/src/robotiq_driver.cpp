// The Robotiq FT 300 client. libmodbus speaks Modbus RTU on the port; once the stream is started
// the same descriptor is read raw, as the sensor then sends frames and answers nothing else.
#include <hil/drivers/robotiq_driver.hpp>

#include <modbus.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <thread>

#include <hil/drivers/error.hpp>

namespace hil::drivers {
namespace {

// Robotiq's driver waits this long after the stop signal before its first Modbus request.
constexpr auto kSwitchToModbus = std::chrono::milliseconds(100);
// A stream silent this long (and at least 20 periods) is asked for again, at most this often.
constexpr std::int64_t kSilenceBeforeRestartNs = 250'000'000;
// Between reconnection attempts of a port that went away.
constexpr std::int64_t kReopenEveryNs = 500'000'000;

}  // namespace

struct RobotiqFt300Driver::Modbus {
  modbus_t* ctx = nullptr;
  std::int64_t last_open_try_ns = 0;
  ~Modbus() { close(); }
  void close() noexcept {
    if (ctx != nullptr) {
      modbus_close(ctx);
      modbus_free(ctx);
      ctx = nullptr;
    }
  }
  int fd() const noexcept { return ctx != nullptr ? modbus_get_socket(ctx) : -1; }
};

RobotiqFt300Driver::RobotiqFt300Driver(const ForcePlateConfig& cfg) : ForcePlate(cfg), mb_(std::make_unique<Modbus>()) {
  if (cfg_.protocol != ForcePlateProtocol::robotiq_ft300) throw ConfigError("protocol", "RobotiqFt300Driver needs protocol robotiq_ft300");
}

RobotiqFt300Driver::~RobotiqFt300Driver() {
  if (started_ && cfg_.robotiq_stream) jam();
}

void RobotiqFt300Driver::jam() noexcept {
  const int fd = mb_->fd();
  if (fd < 0) return;
  std::uint8_t bytes[robotiq::kJamBytes];
  std::memset(bytes, robotiq::kJamByte, sizeof bytes);
  if (::write(fd, bytes, sizeof bytes) != static_cast<ssize_t>(sizeof bytes)) return;
  ::tcdrain(fd);
  std::this_thread::sleep_for(kSwitchToModbus);
  ::tcflush(fd, TCIFLUSH);
  framer_.clear();
}

namespace {
/// Whether bytes arrive on `fd` within `ms` (a stream is running).
bool bytes_arrive(int fd, int ms) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, ms) <= 0) return false;
  std::uint8_t sink[256];
  return ::read(fd, sink, sizeof sink) > 0;
}
}  // namespace

ForcePlateInfo RobotiqFt300Driver::start() {
  const std::string where = "Robotiq FT 300 on " + cfg_.serial_device;
  if (mb_->ctx == nullptr) {
    mb_->ctx = modbus_new_rtu(cfg_.serial_device.c_str(), cfg_.serial_baud, 'N', 8, 1);
    if (mb_->ctx == nullptr) throw DeviceError(where + ": " + modbus_strerror(errno));
    modbus_set_slave(mb_->ctx, cfg_.modbus_slave);
    const double t = cfg_.startup_timeout_s;
    modbus_set_response_timeout(mb_->ctx, static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(std::fmod(t, 1.0) * 1e6));
    if (modbus_connect(mb_->ctx) != 0) {
      const std::string e = modbus_strerror(errno);
      mb_->close();
      throw DeviceError(where + ": cannot open the port: " + e);
    }
  }
  // A stream left running (a crashed client, a sensor that was never stopped) hides every Modbus
  // answer: stop it first, as Robotiq's driver does.
  for (int k = 0; k < 3 && bytes_arrive(mb_->fd(), 50); ++k) {
    spdlog::info("{}: a stream is running; sending the stop signal", where);
    jam();
  }
  std::uint16_t fw[3] = {}, sn[4] = {}, year = 0;
  int rc = -1;
  for (int attempt = 0; attempt < cfg_.startup_tries && rc != 3; ++attempt) {
    if (attempt > 0) ++counters_.retries;
    rc = modbus_read_registers(mb_->ctx, robotiq::kRegFirmware, 3, fw);
  }
  if (rc != 3)
    throw DeviceError(where + ": no answer to a read of registers 500-502 from slave " + std::to_string(cfg_.modbus_slave) + " (" +
                      modbus_strerror(errno) + "; the FT 300 speaks 19200 baud 8N1 as slave 9: is it powered, and the port right?)");
  ForcePlateInfo info;
  info.protocol = "robotiq_ft300";
  info.firmware = robotiq::decode_firmware(std::span<const std::uint16_t, 3>(fw, 3));
  if (info.firmware.empty()) {
    char buf[96];
    std::snprintf(buf, sizeof buf, ": registers 500-502 read 0x%04x 0x%04x 0x%04x, not a firmware version starting 'F'", fw[0], fw[1],
                  fw[2]);
    throw DeviceError(where + buf + " (not an FT 300?)");
  }
  if (modbus_read_registers(mb_->ctx, robotiq::kRegSerial, 4, sn) == 4)
    info.serial = robotiq::decode_serial(std::span<const std::uint16_t, 4>(sn, 4));
  if (modbus_read_registers(mb_->ctx, robotiq::kRegProductionYear, 1, &year) == 1 && year != 0)
    info.serial += " (" + std::to_string(year) + ")";
  info.units = "N, N·m";
  info.counts_per_force = static_cast<std::int32_t>(robotiq::kCountsPerNewton);
  info.counts_per_torque = static_cast<std::int32_t>(robotiq::kCountsPerNewtonMetre);
  info.calibration = Matrix6d::Identity();  // the sensor sends calibrated values
  const double t = cfg_.response_timeout();
  modbus_set_response_timeout(mb_->ctx, static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(std::fmod(t, 1.0) * 1e6));
  if (cfg_.robotiq_stream) {
    bool streaming = false;
    for (int attempt = 0; attempt < cfg_.startup_tries && !streaming; ++attempt) {
      if (attempt > 0) ++counters_.retries;
      streaming = start_stream();
    }
    if (!streaming)
      throw DeviceError(where + ": no stream frame within " + std::to_string(static_cast<int>(cfg_.startup_timeout_s * 1000)) +
                        " ms of writing 0x0200 to register 410, " + std::to_string(cfg_.startup_tries) + " times" +
                        (last_problem_.empty() ? "" : "; last: " + last_problem_));
  }
  started_ = true;
  counters_.connected = true;
  last_restart_ns_ = steady_ns();
  last_frame_ns_ = 0;
  spdlog::info("{}: firmware {}, serial {}, {}", where, info.firmware, info.serial,
               cfg_.robotiq_stream ? "streaming at 100 Hz" : "polling registers 180-185 (read-only)");
  return info;
}

bool RobotiqFt300Driver::start_stream() noexcept {
  // The one write hil makes to the sensor, allowed by the rig file (robotiq_stream). FC16, as
  // Robotiq's driver and manual do; the sensor echoes it, then streams.
  const std::uint16_t value = robotiq::kStreamStart;
  ::tcflush(mb_->fd(), TCIFLUSH);
  framer_.clear();
  if (modbus_write_registers(mb_->ctx, robotiq::kRegStreamSelect, 1, &value) != 1) {
    // Robotiq's driver, too, listens for the stream when the echo is lost.
    char buf[96];
    std::snprintf(buf, sizeof buf, "stream-start write: %s", modbus_strerror(errno));
    problem(buf);
  }
  const std::int64_t deadline = steady_ns() + static_cast<std::int64_t>(cfg_.startup_timeout_s * 1e9);
  have_first_ = false;
  while (steady_ns() < deadline) {
    const int fd = mb_->fd();
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(1, (deadline - steady_ns()) / 1'000'000))) <= 0) continue;
    std::uint8_t bytes[256];
    const ssize_t n = ::read(fd, bytes, sizeof bytes);
    if (n <= 0) break;
    framer_.push({bytes, static_cast<std::size_t>(n)});
    read_t_ns_ = realtime_ns();
    read_steady_ns_ = steady_ns();
    if (framer_.next(first_)) {
      // The stream runs; poll() hands this frame out first. Noise before it is the switch-over.
      counted_bad_crc_ = framer_.bad_crc();
      have_first_ = true;
      return true;
    }
  }
  return false;
}

void RobotiqFt300Driver::account_arrival(std::int64_t t_ns) noexcept {
  // No sequence numbers on the line: a gap of k periods says k-1 frames were lost, unless the
  // frames behind it arrive in a burst (the reader or the sender was late, nothing was lost).
  const double period_ns = 1e9 / cfg_.rate_hz;
  if (last_frame_ns_ != 0) {
    const double dt = static_cast<double>(t_ns - last_frame_ns_);
    if (dt > 1.5 * period_ns) {
      gap_pending_ += static_cast<std::uint64_t>(std::llround(dt / period_ns)) - 1;
    } else if (dt < 0.5 * period_ns) {
      if (gap_pending_ > 0) --gap_pending_;
    } else {
      counters_.dropped_frames += gap_pending_;
      gap_pending_ = 0;
    }
  }
  last_frame_ns_ = t_ns;
}

PollStatus RobotiqFt300Driver::poll(WrenchSample& out) noexcept {
  ++counters_.polls;
  if (!started_) {
    problem("poll() before start()");
    return PollStatus::disconnected;
  }
  out.error_frames = 0;
  out.gauges = {};
  out.status_word = 0;
  out.device_fault = false;  // the FT 300 flags nothing: a bad frame is never a sample
  if (mb_->ctx == nullptr) {
    // The port went away (a USB adapter unplugged): reopen now and then.
    const std::int64_t now = steady_ns();
    if (now - mb_->last_open_try_ns < kReopenEveryNs) return PollStatus::disconnected;
    mb_->last_open_try_ns = now;
    started_ = false;
    try {
      (void)start();
      ++counters_.reconnects;
    } catch (const std::exception& e) {
      started_ = true;  // keep polling (and retrying)
      mb_->close();
      problem(e.what());
      return PollStatus::disconnected;
    }
  }
  return cfg_.robotiq_stream ? poll_stream(out) : poll_registers(out);
}

PollStatus RobotiqFt300Driver::poll_registers(WrenchSample& out) noexcept {
  std::uint16_t regs[6] = {};
  const std::int64_t t0 = realtime_ns();
  const int rc = modbus_read_registers(mb_->ctx, robotiq::kRegWrench, 6, regs);
  const std::int64_t t1 = realtime_ns();
  if (rc != 6) {
    const int err = rc < 0 ? errno : EMBBADDATA;
    ++counters_.consecutive_failures;
    char buf[128];
    std::snprintf(buf, sizeof buf, "read of registers 180-185: %s", modbus_strerror(err));
    problem(buf);
    if (err > MODBUS_ENOBASE && err <= MODBUS_ENOBASE + MODBUS_EXCEPTION_GATEWAY_TARGET) {
      ++counters_.exceptions;
      ++counters_.device_faults;  // the sensor refused: a fault it reports
      return PollStatus::exception;
    }
    if (err == ETIMEDOUT) {
      ++counters_.timeouts;
      return PollStatus::timeout;
    }
    if (err == EIO || err == EBADF || err == ENXIO) {
      counters_.connected = false;
      mb_->close();
      return PollStatus::disconnected;
    }
    ++counters_.bad_frames;  // a bad CRC, a wrong slave or length
    modbus_flush(mb_->ctx);
    return PollStatus::bad_frame;
  }
  robotiq::Reading r;
  for (std::size_t i = 0; i < 6; ++i) r.counts[i] = static_cast<std::int16_t>(regs[i]);
  const auto w = r.si();
  for (int i = 0; i < 6; ++i) out.w_sensor[i] = w[static_cast<std::size_t>(i)];
  out.gauge_saturated = std::any_of(r.counts.begin(), r.counts.end(), [](std::int16_t c) { return c == 32767 || c == -32768; });
  out.t_ns = t0 + (t1 - t0) / 2;  // the middle of the transaction
  out.stamp = StampSource::software;
  counters_.consecutive_failures = 0;
  counters_.connected = true;
  finish(out);
  return PollStatus::ok;
}

PollStatus RobotiqFt300Driver::poll_stream(WrenchSample& out) noexcept {
  const std::int64_t deadline = steady_ns() + static_cast<std::int64_t>(cfg_.response_timeout() * 1e9);
  robotiq::Reading r;
  for (;;) {
    const bool got = have_first_ ? (r = first_, true) : framer_.next(r);
    have_first_ = false;
    if (framer_.bad_crc() > counted_bad_crc_) {
      // A corrupt frame: counted once and reported; the frames behind it come with the next poll.
      counters_.bad_frames += framer_.bad_crc() - counted_bad_crc_;
      counted_bad_crc_ = framer_.bad_crc();
      ++counters_.consecutive_failures;
      problem("a stream frame failed its CRC (skipped)");
      if (!got) return PollStatus::bad_frame;
    }
    if (got) {
      account_arrival(read_steady_ns_);
      const auto w = r.si();
      for (int i = 0; i < 6; ++i) out.w_sensor[i] = w[static_cast<std::size_t>(i)];
      out.gauge_saturated = std::any_of(r.counts.begin(), r.counts.end(), [](std::int16_t c) { return c == 32767 || c == -32768; });
      out.t_ns = read_t_ns_;
      out.stamp = StampSource::software;
      counters_.consecutive_failures = 0;
      counters_.connected = true;
      finish(out);
      return PollStatus::ok;
    }
    const int fd = mb_->fd();
    const std::int64_t left = deadline - steady_ns();
    pollfd p{fd, POLLIN, 0};
    const int ready = left > 0 ? ::poll(&p, 1, static_cast<int>((left + 999'999) / 1'000'000)) : 0;
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) {
      ++counters_.timeouts;
      ++counters_.consecutive_failures;
      problem("no stream frame");
      // A sensor that lost power comes back answering Modbus, not streaming: ask again.
      const std::int64_t now = steady_ns();
      const std::int64_t silence = std::max(kSilenceBeforeRestartNs, static_cast<std::int64_t>(20e9 / cfg_.rate_hz));
      if (now - last_frame_ns_ >= silence && now - last_restart_ns_ >= silence) {
        last_restart_ns_ = now;
        ++counters_.retries;
        if (start_stream()) {
          last_frame_ns_ = 0;  // a new stream: no gap to count across the silence
          gap_pending_ = 0;
        }
      }
      return PollStatus::timeout;
    }
    std::uint8_t bytes[256];
    const std::size_t room = std::min(sizeof bytes, robotiq::StreamFramer::kCapacity - framer_.buffered());
    const ssize_t n = ::read(fd, bytes, room);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    if (n <= 0 || (p.revents & (POLLHUP | POLLERR)) != 0) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "the port went away: %s", n < 0 ? std::strerror(errno) : "hang-up");
      problem(buf);
      counters_.connected = false;
      ++counters_.consecutive_failures;
      mb_->close();
      return PollStatus::disconnected;
    }
    read_t_ns_ = realtime_ns();
    read_steady_ns_ = steady_ns();
    framer_.push({bytes, static_cast<std::size_t>(n)});
  }
}

std::string RobotiqFt300Driver::describe_status(const WrenchSample&) const { return "the FT 300 reports no status word"; }

}  // namespace hil::drivers
