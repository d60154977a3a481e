// The fake FT 300: a pseudo-terminal's master side. Its own Modbus RTU slave (not libmodbus, which
// the driver uses), so the two sides of a test are separate implementations of the framing.
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <random>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>

namespace hil::drivers {

struct FakeRobotiqFt300::Impl {
  FakeFt300Config cfg;
  std::shared_ptr<const Scenario> scenario;
  int master = -1;
  int slave = -1;  // kept open: the line keeps its raw settings and the master never sees a hang-up
  std::string path;
  mutable std::mutex m;  // guards faults, stats
  std::unique_ptr<WrenchSource> source;
  StreamFaults stream;
  ModbusFaults modbus;
  Stats stats;
  std::atomic<bool> stop{false};
  std::atomic<bool> streaming{false};
  Matrix6d X_sensor_fp;
  ~Impl() {
    if (slave >= 0) ::close(slave);
    if (master >= 0) ::close(master);
  }
};

namespace {
void check_faults(const StreamFaults& f) {
  if (f.duplicate_fraction > 0.0) throw ConfigError("duplicate", "a serial line does not duplicate frames");
  if (!f.status.empty() || f.status_now != 0) throw ConfigError("status", "the FT 300 sends no status word");
}
}  // namespace

FakeRobotiqFt300::FakeRobotiqFt300(FakeFt300Config cfg, std::shared_ptr<const Scenario> scenario) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.cfg = std::move(cfg);
  I.scenario = std::move(scenario);
  check_faults(I.cfg.stream);
  I.stream = I.cfg.stream;
  I.modbus = I.cfg.modbus;
  if (I.cfg.slave < 1 || I.cfg.slave > 247) throw ConfigError("slave", "must be 1..247");
  if (!(I.cfg.stream_rate_hz > 0.0) || I.cfg.stream_rate_hz > 1000.0) throw ConfigError("stream_rate_hz", "must be in (0, 1000]");
  if (!(I.cfg.clock.speed > 0.0)) throw ConfigError("speed", "must be > 0");
  I.X_sensor_fp = plate_to_sensor_wrench(I.cfg.T_fp_sensor);
  I.source = std::make_unique<WrenchSource>(I.scenario, I.cfg.clock);
  I.master = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (I.master < 0 || ::grantpt(I.master) != 0 || ::unlockpt(I.master) != 0)
    throw DeviceError(std::string("fake FT 300: pseudo-terminal: ") + std::strerror(errno));
  char name[128];
  if (::ptsname_r(I.master, name, sizeof name) != 0) throw DeviceError(std::string("fake FT 300: ptsname: ") + std::strerror(errno));
  I.path = name;
  I.slave = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (I.slave < 0) throw DeviceError("fake FT 300: cannot open " + I.path + ": " + std::strerror(errno));
  termios t{};
  ::tcgetattr(I.slave, &t);
  ::cfmakeraw(&t);  // no echo, no line editing: bytes pass as on a serial line
  ::cfsetspeed(&t, B19200);
  ::tcsetattr(I.slave, TCSANOW, &t);
  ::fcntl(I.master, F_SETFL, ::fcntl(I.master, F_GETFL) | O_NONBLOCK);
  I.streaming = I.cfg.streaming_at_start;
}

FakeRobotiqFt300::~FakeRobotiqFt300() { stop(); }

const std::string& FakeRobotiqFt300::device_path() const noexcept { return impl_->path; }
bool FakeRobotiqFt300::streaming() const noexcept { return impl_->streaming.load(); }

void FakeRobotiqFt300::start() {
  if (thread_.joinable()) return;
  impl_->stop = false;
  thread_ = std::jthread([this] { run(); });
}

void FakeRobotiqFt300::stop() noexcept {
  impl_->stop = true;
  if (thread_.joinable()) thread_.join();
}

void FakeRobotiqFt300::set_wrench(const Vector6d& w_fp) { impl_->source->set(w_fp); }

void FakeRobotiqFt300::set_faults(const StreamFaults& stream, const ModbusFaults& modbus) {
  check_faults(stream);
  std::lock_guard lk(impl_->m);
  impl_->stream = stream;
  impl_->modbus = modbus;
}

FakeRobotiqFt300::Stats FakeRobotiqFt300::stats() const {
  std::lock_guard lk(impl_->m);
  return impl_->stats;
}

void FakeRobotiqFt300::run() noexcept {
  using Clock = std::chrono::steady_clock;
  Impl& I = *impl_;
  std::mt19937_64 rng(I.cfg.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const auto t0 = Clock::now();
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / I.cfg.stream_rate_hz));
  auto next = Clock::now();
  std::vector<std::uint8_t> in;
  std::size_t ff_run = 0;
  const auto serial = robotiq::encode_serial(I.cfg.serial_prefix, I.cfg.serial_number);
  const auto firmware = robotiq::encode_firmware(I.cfg.firmware_prefix, I.cfg.firmware[0], I.cfg.firmware[1], I.cfg.firmware[2]);

  const auto now_s = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  const auto reading_at = [&](double t_s) {
    const Vector6d ws = I.X_sensor_fp * I.source->at(t_s);
    robotiq::Reading r;
    for (int i = 0; i < 6; ++i) {
      const double scale = i < 3 ? robotiq::kCountsPerNewton : robotiq::kCountsPerNewtonMetre;
      const double c = std::nearbyint(ws[i] * scale);
      r.counts[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::clamp(c, -32768.0, 32767.0));
    }
    return r;
  };
  const auto send = [&](const std::uint8_t* p, std::size_t n) { return ::write(I.master, p, n) == static_cast<ssize_t>(n); };
  const auto reply = [&](std::vector<std::uint8_t> pdu) {
    const std::uint16_t crc = robotiq::crc16(pdu);
    pdu.push_back(static_cast<std::uint8_t>(crc & 0xFF));
    pdu.push_back(static_cast<std::uint8_t>(crc >> 8));
    send(pdu.data(), pdu.size());
  };
  const auto register_value = [&](unsigned a, std::uint16_t& v) {
    if (a >= robotiq::kRegWrench && a < robotiq::kRegWrench + 6u) {
      v = static_cast<std::uint16_t>(reading_at(now_s()).counts[a - robotiq::kRegWrench]);
    } else if (a >= 190 && a <= 192) {
      v = a == 192 ? static_cast<std::uint16_t>(-1000) : 0;  // acceleration in mg: -1 g along z, at rest
    } else if (a == robotiq::kRegStreamSelect) {
      v = 0;
    } else if (a >= robotiq::kRegFirmware && a < robotiq::kRegFirmware + 3u) {
      v = firmware[a - robotiq::kRegFirmware];
    } else if (a >= robotiq::kRegSerial && a < robotiq::kRegSerial + 4u) {
      v = serial[a - robotiq::kRegSerial];
    } else if (a == robotiq::kRegProductionYear) {
      v = I.cfg.production_year;
    } else {
      return false;
    }
    return true;
  };

  // One Modbus RTU request at the front of `in`: \returns its length, 0 if incomplete.
  const auto request_length = [](const std::vector<std::uint8_t>& b) -> std::size_t {
    if (b.size() < 2) return 0;
    if (b[1] == 16) return b.size() < 7 ? 0 : 9u + b[6];
    return 8;  // FC03, FC04, FC06 and the others a master sends to a sensor
  };

  while (!I.stop.load()) {
    const bool streaming = I.streaming.load();
    const auto now = Clock::now();
    const std::int64_t wait_ns = streaming ? std::clamp<std::int64_t>((next - now).count(), 0, 20'000'000) : 20'000'000;
    const timespec ts{0, static_cast<long>(wait_ns)};
    pollfd p{I.master, POLLIN, 0};
    if (::ppoll(&p, 1, &ts, nullptr) > 0 && (p.revents & POLLIN) != 0) {
      std::uint8_t buf[512];
      const ssize_t n = ::read(I.master, buf, sizeof buf);
      if (n > 0) in.insert(in.end(), buf, buf + n);
    }
    if (I.streaming.load()) {
      // While streaming the sensor hears only the stop signal.
      for (const std::uint8_t b : in) {
        ff_run = b == robotiq::kJamByte ? ff_run + 1 : 0;
        if (ff_run >= robotiq::kJamBytes) {
          I.streaming = false;
          ff_run = 0;
          std::lock_guard lk(I.m);
          ++I.stats.stream_stops;
        }
      }
      in.clear();
    }
    // Modbus requests.
    while (!I.streaming.load()) {
      const std::size_t len = request_length(in);
      if (len == 0 || in.size() < len) break;
      const std::uint16_t crc = static_cast<std::uint16_t>(in[len - 2] | (in[len - 1] << 8));
      if (robotiq::crc16({in.data(), len - 2}) != crc) {
        // Not a request (noise, a stop signal, a request cut short): the slave waits for the
        // next frame; here the bytes are dropped one by one until one is found.
        in.erase(in.begin());
        std::lock_guard lk(I.m);
        ++I.stats.bad_requests;
        continue;
      }
      std::vector<std::uint8_t> req(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(len));
      in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(len));
      const double t = now_s();
      StreamFaults sf;
      ModbusFaults mf;
      {
        std::lock_guard lk(I.m);
        ++I.stats.requests;
        sf = I.stream;
        mf = I.modbus;
      }
      if (req[0] != I.cfg.slave) {
        std::lock_guard lk(I.m);
        ++I.stats.other_slave;
        continue;
      }
      bool silent = mf.silent_now;
      for (const auto& w : mf.silent) silent = silent || w.contains(t);
      if (silent) {
        std::lock_guard lk(I.m);
        ++I.stats.ignored_silent;
        continue;
      }
      double delay = mf.extra_delay_s;
      if (mf.slow_fraction > 0.0 && uni(rng) < mf.slow_fraction) delay += mf.slow_delay_s;
      if (delay > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(delay));
      const std::uint8_t fc = req[1];
      const unsigned addr = static_cast<unsigned>(req[2] << 8 | req[3]);
      const unsigned qty = static_cast<unsigned>(req[4] << 8 | req[5]);
      // Counters move before the bytes leave: a client that has its reply must see it counted.
      const auto exception = [&](std::uint8_t code) {
        {
          std::lock_guard lk(I.m);
          ++I.stats.exceptions;
        }
        reply({req[0], static_cast<std::uint8_t>(fc | 0x80), code});
      };
      const auto answer = [&](const std::vector<std::uint8_t>& out, bool starts_stream) {
        {
          std::lock_guard lk(I.m);
          ++I.stats.replies;
          if (starts_stream) ++I.stats.stream_starts;
        }
        if (starts_stream) {
          I.streaming = true;
          next = Clock::now();
        }
        reply(out);
      };
      bool refuse = mf.exception_fraction > 0.0 && uni(rng) < mf.exception_fraction;
      for (const auto& w : mf.exception_windows) refuse = refuse || w.contains(t);
      if (refuse) {
        exception(0x06);  // server device busy
        continue;
      }
      if (fc == 3) {
        if (qty < 1 || qty > 125) {
          exception(0x03);
          continue;
        }
        std::vector<std::uint8_t> out{req[0], 3, static_cast<std::uint8_t>(2 * qty)};
        bool ok = true;
        for (unsigned k = 0; k < qty && ok; ++k) {
          std::uint16_t v = 0;
          ok = register_value(addr + k, v);
          out.push_back(static_cast<std::uint8_t>(v >> 8));
          out.push_back(static_cast<std::uint8_t>(v & 0xFF));
        }
        if (!ok) {
          exception(0x02);
          continue;
        }
        answer(out, false);
      } else if (fc == 16) {
        const bool start_write = addr == robotiq::kRegStreamSelect && qty == 1 && req[6] == 2 && req[7] == (robotiq::kStreamStart >> 8) &&
                                 req[8] == (robotiq::kStreamStart & 0xFF);
        if (!start_write) {
          exception(addr == robotiq::kRegStreamSelect ? 0x03 : 0x02);
          continue;
        }
        bool deaf = false;
        for (const auto& w : sf.deaf) deaf = deaf || w.contains(t);
        if (deaf) {
          std::lock_guard lk(I.m);
          ++I.stats.ignored_deaf;
          continue;
        }
        answer({req[0], 16, req[2], req[3], req[4], req[5]}, true);
      } else {
        exception(0x01);  // the sensor documents FC03 and FC16 only
      }
    }
    if (!I.streaming.load() || Clock::now() < next) continue;
    // One frame at its deadline.
    const double t = std::chrono::duration<double>(next - t0).count();
    next += period;
    StreamFaults f;
    double noise = 0.0;
    {
      std::lock_guard lk(I.m);
      f = I.stream;
      noise = I.cfg.noise_fraction;
      ++I.stats.frames;
    }
    bool silent = f.silent_now;
    for (const auto& w : f.silent) silent = silent || w.contains(t);
    if (silent) {
      std::lock_guard lk(I.m);
      ++I.stats.frames_silenced;
      continue;
    }
    if (f.drop_fraction > 0.0 && uni(rng) < f.drop_fraction) {
      std::lock_guard lk(I.m);
      ++I.stats.frames_dropped;
      continue;
    }
    std::uint8_t frame[robotiq::kFrameBytes];
    robotiq::encode_frame(reading_at(t), frame);
    const bool corrupt = f.corrupt_fraction > 0.0 && uni(rng) < f.corrupt_fraction;
    if (corrupt) frame[2 + static_cast<std::size_t>(uni(rng) * 12)] ^= static_cast<std::uint8_t>(1U << static_cast<unsigned>(uni(rng) * 8));
    if (f.extra_delay_s > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(f.extra_delay_s));
    std::size_t noise_bytes = 0;
    if (noise > 0.0 && uni(rng) < noise) {
      // Stray bytes, never a header: line noise the reader must step over.
      std::uint8_t stray[5];
      noise_bytes = 1 + static_cast<std::size_t>(uni(rng) * 4);
      for (std::size_t k = 0; k < noise_bytes; ++k) stray[k] = static_cast<std::uint8_t>(0x30 + uni(rng) * 0x40);
      send(stray, noise_bytes);
    }
    const bool sent = send(frame, sizeof frame);
    std::lock_guard lk(I.m);
    I.stats.noise_bytes += noise_bytes;
    if (corrupt) ++I.stats.frames_corrupted;
    if (!sent) ++I.stats.overruns;
    if (sent && !corrupt) ++I.stats.frames_sent;
  }
}

}  // namespace hil::drivers
