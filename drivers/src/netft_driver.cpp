// The Net F/T RDT client. One UDP socket connect()ed to the box: the kernel then delivers only the
// box's datagrams, and a box that is not listening shows as ECONNREFUSED instead of silence.
#include <hil/drivers/netft_driver.hpp>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>

#include <hil/drivers/error.hpp>

namespace hil::drivers {
namespace {

// The box sends one record per datagram in real-time mode and up to a few dozen buffered.
constexpr std::size_t kMaxDatagram = 64 * 1024;
// A box silent this long (and at least 20 periods) is asked to stream again, at most this often. A
// start request restarts rdt_sequence at 1, so a late record must not trigger one.
constexpr std::int64_t kSilenceBeforeRestartNs = 250'000'000;

}  // namespace

NetFtRdtDriver::NetFtRdtDriver(const ForcePlateConfig& cfg) : ForcePlate(cfg), buffer_(kMaxDatagram) {
  if (cfg_.protocol != ForcePlateProtocol::ati_netft_rdt) throw ConfigError("protocol", "NetFtRdtDriver needs protocol ati_netft_rdt");
  n_per_count_ = cfg_.netft_calibration.newtons_per_count();
  nm_per_count_ = cfg_.netft_calibration.newton_metres_per_count();
  pending_.reserve(kMaxDatagram / netft::kRecordBytes);
}

NetFtRdtDriver::~NetFtRdtDriver() {
  if (fd_ >= 0) {
    send(netft::RdtCommand::stop);
    ::close(fd_);
  }
}

std::string NetFtRdtDriver::link() const { return "udp " + cfg_.host + ":" + std::to_string(cfg_.port); }

bool NetFtRdtDriver::send(netft::RdtCommand c, std::uint32_t sample_count) noexcept {
  if (fd_ < 0) return false;
  const auto req = netft::encode_request(c, sample_count);
  return ::send(fd_, req.data(), req.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(req.size());
}

bool NetFtRdtDriver::bias_on_device() noexcept { return send(netft::RdtCommand::set_bias); }
bool NetFtRdtDriver::reset_latch() noexcept { return send(netft::RdtCommand::reset_latch); }

ForcePlateInfo NetFtRdtDriver::start() {
  const std::string where = "ATI Net F/T (RDT) at " + link();
  if (fd_ < 0) {
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* res = nullptr;
    const std::string port = std::to_string(cfg_.port);
    if (const int e = ::getaddrinfo(cfg_.host.c_str(), port.c_str(), &hints, &res); e != 0)
      throw DeviceError(where + ": cannot resolve '" + cfg_.host + "': " + ::gai_strerror(e));
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) {
      ::freeaddrinfo(res);
      throw DeviceError(where + ": socket: " + std::strerror(errno));
    }
    const int on = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);  // kernel receive time
    ::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);     // datagrams the socket dropped
    const int rcvbuf = 4 * 1024 * 1024;                             // ~100 000 records: seconds of a stalled reader
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    const int rc = ::connect(fd_, res->ai_addr, res->ai_addrlen);
    const int err = errno;
    ::freeaddrinfo(res);
    if (rc != 0) {
      ::close(fd_);
      fd_ = -1;
      throw DeviceError(where + ": connect: " + std::strerror(err));
    }
  }
  for (int attempt = 0; attempt < cfg_.startup_tries; ++attempt) {
    if (attempt > 0) ++counters_.retries;
    if (!send(netft::RdtCommand::start_realtime)) continue;
    const std::int64_t deadline = steady_ns() + static_cast<std::int64_t>(cfg_.startup_timeout_s * 1e9);
    while (steady_ns() < deadline) {
      const PollStatus st = receive(deadline);
      if (st == PollStatus::ok) break;
    }
    if (next_ < pending_.size()) break;
  }
  if (next_ >= pending_.size())
    throw DeviceError(where + ": no RDT record after " + std::to_string(cfg_.startup_tries) + " requests of " +
                      std::to_string(static_cast<int>(cfg_.startup_timeout_s * 1000)) +
                      " ms (is RDT enabled on the box's Communications page, and the address right?)" +
                      (last_problem_.empty() ? "" : "; last: " + last_problem_));
  started_ = true;
  counters_.connected = true;
  last_restart_ns_ = last_record_ns_ = steady_ns();
  ForcePlateInfo info;
  info.protocol = "ati_netft_rdt";
  info.units = cfg_.netft_calibration.force_unit + ", " + cfg_.netft_calibration.torque_unit;
  info.counts_per_force = static_cast<std::int32_t>(std::lround(cfg_.netft_calibration.counts_per_force));
  info.counts_per_torque = static_cast<std::int32_t>(std::lround(cfg_.netft_calibration.counts_per_torque));
  info.calibration = Matrix6d::Identity();  // the box applies its matrix; the records are in F/T counts
  spdlog::info("{}: streaming, units {}, counts {}/{}", where, info.units, cfg_.netft_calibration.counts_per_force,
               cfg_.netft_calibration.counts_per_torque);
  return info;
}

PollStatus NetFtRdtDriver::receive(std::int64_t deadline_ns) noexcept {
  for (;;) {
    const std::int64_t left = deadline_ns - steady_ns();
    if (left <= 0) return PollStatus::timeout;
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>((left + 999'999) / 1'000'000));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) return PollStatus::timeout;
    iovec iov{buffer_.data(), buffer_.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t)) + 64];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      char buf[128];
      std::snprintf(buf, sizeof buf, "receive: %s", std::strerror(errno));
      problem(buf);
      // ECONNREFUSED: nothing listens at the box's port (an ICMP answer); the link is down.
      return errno == ECONNREFUSED ? PollStatus::disconnected : PollStatus::bad_frame;
    }
    std::int64_t t_ns = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SO_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        t_ns = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t drops = 0;
        std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
        if (drops > socket_drops_) counters_.dropped_frames += drops - socket_drops_;
        socket_drops_ = drops;
      }
    }
    const std::size_t records = (msg.msg_flags & MSG_TRUNC) != 0 ? 0 : netft::records_in(static_cast<std::size_t>(n));
    if (records == 0) {
      ++counters_.bad_frames;
      ++counters_.consecutive_failures;
      char buf[128];
      std::snprintf(buf, sizeof buf, "datagram of %zd bytes is not a whole number of %zu-byte RDT records", n, netft::kRecordBytes);
      problem(buf);
      return PollStatus::bad_frame;
    }
    pending_.resize(records);
    for (std::size_t k = 0; k < records; ++k) netft::decode_record(buffer_.data() + k * netft::kRecordBytes, pending_[k]);
    next_ = 0;
    pending_t_ns_ = t_ns != 0 ? t_ns : realtime_ns();
    pending_stamp_ = t_ns != 0 ? StampSource::software : StampSource::none;
    return PollStatus::ok;
  }
}

PollStatus NetFtRdtDriver::poll(WrenchSample& out) noexcept {
  ++counters_.polls;
  if (!started_) {
    problem("poll() before start()");
    return PollStatus::disconnected;
  }
  out.error_frames = 0;
  const std::int64_t deadline = steady_ns() + static_cast<std::int64_t>(cfg_.response_timeout() * 1e9);
  for (;;) {
    if (next_ >= pending_.size()) {
      const PollStatus st = receive(deadline);
      if (st == PollStatus::timeout) {
        ++counters_.timeouts;
        ++counters_.consecutive_failures;
        problem("no RDT record");
        // A box that rebooted, or whose stream request was lost, stays silent: ask again.
        const std::int64_t now = steady_ns();
        const std::int64_t silence = std::max(kSilenceBeforeRestartNs, static_cast<std::int64_t>(20e9 / cfg_.rate_hz));
        if (now - last_record_ns_ >= silence && now - last_restart_ns_ >= silence) {
          last_restart_ns_ = now;
          if (send(netft::RdtCommand::start_realtime)) ++counters_.retries;
        }
        return PollStatus::timeout;
      }
      if (st != PollStatus::ok) {
        if (st == PollStatus::disconnected) {
          ++counters_.consecutive_failures;
          counters_.connected = false;
        }
        return st;
      }
    }
    const netft::RdtRecord& r = pending_[next_++];
    last_record_ns_ = steady_ns();
    // Every stream the box starts counts from 1: a 1 is a new stream (ours, restarted), not a
    // record from the past.
    if (r.rdt_sequence == 1 && !(have_seq_ && last_rdt_seq_ == 1)) have_seq_ = false;  // (a duplicated 1 is late)
    if (have_seq_) {
      const std::uint32_t step = r.rdt_sequence - last_rdt_seq_;  // modulo 2^32: wraps are steps
      if (step == 0 || step > 0x80000000U) {
        ++counters_.late_frames;  // a duplicate or an older record: the newer one was handed out
        continue;
      }
      if (step > 1) counters_.dropped_frames += step - 1;
    }
    have_seq_ = true;
    last_rdt_seq_ = r.rdt_sequence;
    out.t_ns = pending_t_ns_;
    out.stamp = pending_stamp_;
    out.status_word = r.status;
    out.gauges = {};
    out.gauge_saturated = false;
    for (int k = 0; k < 3; ++k) {
      out.w_sensor[k] = r.counts[static_cast<std::size_t>(k)] * n_per_count_;
      out.w_sensor[k + 3] = r.counts[static_cast<std::size_t>(k) + 3] * nm_per_count_;
    }
    // Any status bit marks the reading, the monitor latch too: the rule of the device layer
    // (docs/hardware.md); reset_latch() clears that one.
    out.device_fault = r.status != 0;
    if (out.device_fault) ++counters_.device_faults;
    counters_.connected = true;
    finish(out);
    return PollStatus::ok;
  }
}

std::string NetFtRdtDriver::describe_status(const WrenchSample& s) const {
  return "Net F/T status " + netft::describe_status(s.status_word);
}

}  // namespace hil::drivers
