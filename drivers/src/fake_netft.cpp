// The fake Net F/T box: one UDP socket on 127.0.0.0/8; requests in, records out on absolute
// deadlines. The first client that asks for a stream gets it (as the box streams to the last
// requester); a stop or another start from it changes the stream.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
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

struct FakeNetFtRdt::Impl {
  FakeNetFtConfig cfg;
  std::shared_ptr<const Scenario> scenario;
  int fd = -1;
  int port = 0;
  mutable std::mutex m;  // guards faults, stats
  std::unique_ptr<WrenchSource> source;
  StreamFaults faults;
  Stats stats;
  std::atomic<bool> stop{false};
  Matrix6d X_sensor_fp;
  Vector6d counts_per_si;
  ~Impl() {
    if (fd >= 0) ::close(fd);
  }
};

FakeNetFtRdt::FakeNetFtRdt(FakeNetFtConfig cfg, std::shared_ptr<const Scenario> scenario) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.cfg = std::move(cfg);
  I.scenario = std::move(scenario);
  I.faults = I.cfg.faults;
  in_addr a{};
  if (::inet_pton(AF_INET, I.cfg.host.c_str(), &a) != 1 || (ntohl(a.s_addr) >> 24) != 127)
    throw ConfigError("host", "'" + I.cfg.host + "': the fake Net F/T listens on 127.0.0.0/8 only");
  if (I.cfg.port < 0 || I.cfg.port > 65535) throw ConfigError("port", "must be 0..65535");
  if (!(I.cfg.rate_hz > 0.0) || I.cfg.rate_hz > 10000.0) throw ConfigError("rate_hz", "must be in (0, 10000]");
  if (I.cfg.records_per_datagram < 1 || I.cfg.records_per_datagram > 40) throw ConfigError("records_per_datagram", "must be 1..40");
  if (!(I.cfg.clock.speed > 0.0)) throw ConfigError("speed", "must be > 0");
  const double fc = 1.0 / I.cfg.calibration.newtons_per_count(), tc = 1.0 / I.cfg.calibration.newton_metres_per_count();
  I.counts_per_si << fc, fc, fc, tc, tc, tc;
  I.X_sensor_fp = plate_to_sensor_wrench(I.cfg.T_fp_sensor);
  I.source = std::make_unique<WrenchSource>(I.scenario, I.cfg.clock);
  I.fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (I.fd < 0) throw DeviceError(std::string("fake Net F/T: socket: ") + std::strerror(errno));
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_addr = a;
  sa.sin_port = htons(static_cast<std::uint16_t>(I.cfg.port));
  if (::bind(I.fd, reinterpret_cast<const sockaddr*>(&sa), sizeof sa) != 0)
    throw DeviceError("fake Net F/T: cannot bind " + I.cfg.host + ":" + std::to_string(I.cfg.port) + ": " + std::strerror(errno));
  socklen_t len = sizeof sa;
  ::getsockname(I.fd, reinterpret_cast<sockaddr*>(&sa), &len);
  I.port = ntohs(sa.sin_port);
}

FakeNetFtRdt::~FakeNetFtRdt() { stop(); }

int FakeNetFtRdt::port() const noexcept { return impl_->port; }

void FakeNetFtRdt::start() {
  if (thread_.joinable()) return;
  impl_->stop = false;
  thread_ = std::jthread([this] { run(); });
}

void FakeNetFtRdt::stop() noexcept {
  impl_->stop = true;
  if (thread_.joinable()) thread_.join();
}

void FakeNetFtRdt::set_wrench(const Vector6d& w_fp) { impl_->source->set(w_fp); }

void FakeNetFtRdt::set_faults(const StreamFaults& f) {
  std::lock_guard lk(impl_->m);
  impl_->faults = f;
}

FakeNetFtRdt::Stats FakeNetFtRdt::stats() const {
  std::lock_guard lk(impl_->m);
  return impl_->stats;
}

void FakeNetFtRdt::run() noexcept {
  using Clock = std::chrono::steady_clock;
  Impl& I = *impl_;
  std::mt19937_64 rng(I.cfg.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const auto t0 = Clock::now();
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / I.cfg.rate_hz));
  bool streaming = false;
  sockaddr_in client{};
  std::uint32_t remaining = 0;  // records still to send; 0 = until stopped
  unsigned per_datagram = 1;
  std::uint32_t rdt_seq = 0, ft_seq = 0;
  Vector6d bias_counts = Vector6d::Zero();
  bool latched = false;
  auto next = Clock::now();
  std::vector<std::uint8_t> datagram;
  std::vector<netft::RdtRecord> batch;

  const auto counts_now = [&](double t_s) { return Vector6d(I.counts_per_si.cwiseProduct(I.X_sensor_fp * I.source->at(t_s))); };
  const auto to_int32 = [](double v) {
    if (!(v == v)) return std::int32_t{0};
    const double r = std::nearbyint(v);
    constexpr double lo = std::numeric_limits<std::int32_t>::min(), hi = std::numeric_limits<std::int32_t>::max();
    return static_cast<std::int32_t>(r < lo ? lo : r > hi ? hi : r);
  };

  while (!I.stop.load()) {
    // Wait for a request or the next record's deadline, to the nanosecond (a millisecond poll()
    // would spin through every sub-millisecond wait at 1 kHz).
    const auto now = Clock::now();
    const std::int64_t wait_ns = streaming ? std::clamp<std::int64_t>((next - now).count(), 0, 20'000'000) : 20'000'000;
    const timespec ts{0, static_cast<long>(wait_ns)};
    pollfd p{I.fd, POLLIN, 0};
    if (::ppoll(&p, 1, &ts, nullptr) > 0) {
      std::uint8_t in[64];
      sockaddr_in from{};
      socklen_t flen = sizeof from;
      const ssize_t n = ::recvfrom(I.fd, in, sizeof in, 0, reinterpret_cast<sockaddr*>(&from), &flen);
      const double t = std::chrono::duration<double>(Clock::now() - t0).count();
      StreamFaults f;
      {
        std::lock_guard lk(I.m);
        f = I.faults;
        ++I.stats.requests;
      }
      bool deaf = false;
      for (const auto& w : f.deaf) deaf = deaf || w.contains(t);
      netft::RdtRequest req;
      if (n < 0 || !netft::decode_request(std::span<const std::uint8_t>(in, static_cast<std::size_t>(n)), req)) {
        std::lock_guard lk(I.m);
        ++I.stats.bad_requests;
      } else if (deaf) {
        std::lock_guard lk(I.m);
        ++I.stats.ignored_deaf;
      } else {
        // The bias is the load now, read before the lock (counts_now takes it for set_wrench's value).
        const bool bias = static_cast<netft::RdtCommand>(req.command) == netft::RdtCommand::set_bias;
        const Vector6d load = bias ? counts_now(t) : Vector6d::Zero();
        std::lock_guard lk(I.m);
        switch (static_cast<netft::RdtCommand>(req.command)) {
          case netft::RdtCommand::start_realtime:
          case netft::RdtCommand::start_buffered:
            streaming = true;
            client = from;
            remaining = req.sample_count;
            per_datagram = static_cast<netft::RdtCommand>(req.command) == netft::RdtCommand::start_buffered ? I.cfg.records_per_datagram
                                                                                                            : 1;
            rdt_seq = 0;  // a new stream counts from 1
            next = Clock::now();
            ++I.stats.starts;
            break;
          case netft::RdtCommand::stop:
            streaming = false;
            ++I.stats.stops;
            break;
          case netft::RdtCommand::set_bias:
            bias_counts = load;
            ++I.stats.biases;
            break;
          case netft::RdtCommand::reset_latch:
            latched = false;
            ++I.stats.latch_resets;
            break;
          default: ++I.stats.bad_requests; break;
        }
      }
    }
    if (!streaming || Clock::now() < next) continue;
    // One datagram of per_datagram records, each at its own deadline's time.
    StreamFaults f;
    {
      std::lock_guard lk(I.m);
      f = I.faults;
    }
    batch.clear();
    for (unsigned k = 0; k < per_datagram && streaming; ++k) {
      const double t = std::chrono::duration<double>(next - t0).count();
      next += period;
      ++ft_seq;
      netft::RdtRecord r;
      r.rdt_sequence = ++rdt_seq;
      r.ft_sequence = ft_seq;
      std::uint32_t bits = f.status_now;
      for (const auto& sw : f.status) bits |= sw.window.contains(t) ? sw.bits : 0U;
      if ((bits & netft::kStatusMonitorLatched) != 0) latched = true;
      if (latched) bits |= netft::kStatusMonitorLatched;
      if ((bits & ~(netft::kStatusMonitorLatched | netft::kStatusAnyError)) != 0) bits |= netft::kStatusAnyError;
      r.status = bits;
      const Vector6d c = counts_now(t) - bias_counts;
      for (std::size_t i = 0; i < 6; ++i) r.counts[i] = to_int32(c[static_cast<int>(i)]);
      bool silent = f.silent_now;
      for (const auto& w : f.silent) silent = silent || w.contains(t);
      std::lock_guard lk(I.m);
      ++I.stats.records;
      if (silent) {
        ++I.stats.records_silenced;
      } else if (f.drop_fraction > 0.0 && uni(rng) < f.drop_fraction) {
        ++I.stats.records_dropped;
      } else {
        batch.push_back(r);
      }
      if (remaining != 0 && --remaining == 0) streaming = false;
    }
    if (batch.empty()) continue;
    if (f.extra_delay_s > 0.0) std::this_thread::sleep_for(std::chrono::nanoseconds(static_cast<std::int64_t>(f.extra_delay_s * 1e9)));
    datagram.assign(batch.size() * netft::kRecordBytes, 0);
    for (std::size_t k = 0; k < batch.size(); ++k) netft::encode_record(batch[k], datagram.data() + k * netft::kRecordBytes);
    std::size_t bytes = datagram.size();
    bool corrupt = false, duplicate = false;
    {
      std::lock_guard lk(I.m);
      corrupt = f.corrupt_fraction > 0.0 && uni(rng) < f.corrupt_fraction;
      duplicate = !corrupt && f.duplicate_fraction > 0.0 && uni(rng) < f.duplicate_fraction;
    }
    if (corrupt) bytes -= 1 + static_cast<std::size_t>(uni(rng) * (netft::kRecordBytes - 2));
    const bool sent = ::sendto(I.fd, datagram.data(), bytes, MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&client), sizeof client) ==
                      static_cast<ssize_t>(bytes);
    if (duplicate) ::sendto(I.fd, datagram.data(), bytes, MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&client), sizeof client);
    std::lock_guard lk(I.m);
    if (corrupt) ++I.stats.datagrams_corrupted;
    if (duplicate) ++I.stats.datagrams_duplicated;
    if (sent && !corrupt) {
      I.stats.records_sent += batch.size();
      for (const auto& r : batch) I.stats.records_flagged += r.status != 0 ? 1 : 0;
    }
  }
}

}  // namespace hil::drivers
