#include <hil/drivers/socketcan.hpp>

#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/errqueue.h>
#include <linux/net_tstamp.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>

#include <hil/drivers/error.hpp>

namespace hil::drivers {
namespace {

std::string sys_error(const std::string& iface, const char* call) {
  return "SocketCAN " + iface + ": " + call + " failed: " + std::strerror(errno);
}

timespec to_timespec(std::chrono::nanoseconds d) {
  if (d.count() < 0) d = std::chrono::nanoseconds(0);
  return timespec{static_cast<time_t>(d.count() / 1000000000), static_cast<long>(d.count() % 1000000000)};
}

}  // namespace

bool SocketCanChannel::kernel_supports_can() noexcept {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return false;
  ::close(s);
  return true;
}

std::unique_ptr<SocketCanChannel> SocketCanChannel::open(const SocketCanOptions& o) {
  if (o.interface.empty() || o.interface.size() >= IFNAMSIZ)
    throw ConfigError("interface",
                      "'" + o.interface + "' is not a valid interface name (1.." + std::to_string(IFNAMSIZ - 1) + " characters)");
  std::unique_ptr<SocketCanChannel> c(new SocketCanChannel());
  c->iface_ = o.interface;
  c->fd_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (c->fd_ < 0) {
    const int e = errno;
    std::string msg = sys_error(o.interface, "socket(PF_CAN, SOCK_RAW, CAN_RAW)");
    if (e == EAFNOSUPPORT) msg += " (this kernel has no CAN support; load can and can-raw, or use a VM)";
    throw DeviceError(msg);
  }
  const int fd = c->fd_;
  const unsigned ifindex = if_nametoindex(o.interface.c_str());
  if (ifindex == 0) throw DeviceError(sys_error(o.interface, "if_nametoindex") + " (no such CAN interface?)");

  const CanChannelOptions& ch = o.channel;
  if (ch.fd) {
    const int on = 1;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) == 0) c->fd_frames_ = true;
  }
  if (!ch.filters.empty()) {
    std::vector<can_filter> flt(ch.filters.size());
    for (std::size_t i = 0; i < flt.size(); ++i) {
      flt[i].can_id = ch.filters[i].id | (ch.filters[i].inverted ? CAN_INV_FILTER : 0U);
      flt[i].can_mask = ch.filters[i].mask;
    }
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt.data(), static_cast<socklen_t>(flt.size() * sizeof(can_filter))) != 0)
      throw DeviceError(sys_error(o.interface, "setsockopt(CAN_RAW_FILTER)"));
  }
  const can_err_mask_t err_mask = ch.error_mask & CAN_ERR_MASK;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0)
    throw DeviceError(sys_error(o.interface, "setsockopt(CAN_RAW_ERR_FILTER)"));
  if (ch.receive_own) {
    const int on = 1;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &on, sizeof on) != 0)
      throw DeviceError(sys_error(o.interface, "setsockopt(CAN_RAW_RECV_OWN_MSGS)"));
  }
  if (o.timestamps) {
    const int flags = SOF_TIMESTAMPING_RX_HARDWARE | SOF_TIMESTAMPING_RAW_HARDWARE | SOF_TIMESTAMPING_RX_SOFTWARE |
                      SOF_TIMESTAMPING_SOFTWARE;
    if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPING, &flags, sizeof flags) != 0) {
      const int on = 1;
      ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
    }
  }
  {
    const int on = 1;
    c->have_ovfl_ = ::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) == 0;
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) throw DeviceError(sys_error(o.interface, "bind"));
  return c;
}

SocketCanChannel::~SocketCanChannel() {
  if (fd_ >= 0) ::close(fd_);
}

CanChannelStats SocketCanChannel::stats() const noexcept {
  CanChannelStats s;
  s.rx_frames = rx_.load();
  s.tx_frames = tx_.load();
  s.rx_dropped = dropped_.load();
  s.tx_failed = tx_failed_.load();
  s.error_frames = err_.load();
  return s;
}

IoStatus SocketCanChannel::send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept {
  alignas(8) std::uint8_t buf[kCanFdMtu];
  if (frame.fd && !fd_frames_) {
    last_error_ = iface_ + ": CAN FD frame but CAN FD is not enabled on this socket";
    ++tx_failed_;
    return IoStatus::error;
  }
  const std::size_t n = encode_kernel_frame(frame, std::span<std::uint8_t, kCanFdMtu>(buf, kCanFdMtu));
  if (n == 0) {
    const char* p = frame_problem(frame);
    last_error_ = iface_ + ": " + (p ? p : "invalid frame");
    ++tx_failed_;
    return IoStatus::error;
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const ssize_t w = ::send(fd_, buf, n, MSG_DONTWAIT);
    if (w == static_cast<ssize_t>(n)) {
      ++tx_;
      return IoStatus::ok;
    }
    if (w < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EINTR)) {
      // The device queue is full: poll() may not wait for ENOBUFS, so retry in short steps.
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) {
        ++tx_failed_;
        return IoStatus::timeout;
      }
      auto step = std::min<std::chrono::nanoseconds>(deadline - now, std::chrono::microseconds(500));
      pollfd p{fd_, POLLOUT, 0};
      const timespec ts = to_timespec(step);
      ::ppoll(&p, 1, &ts, nullptr);
      if (errno == ENOBUFS) {
        timespec sl = to_timespec(std::min<std::chrono::nanoseconds>(step, std::chrono::microseconds(100)));
        ::nanosleep(&sl, nullptr);
      }
      continue;
    }
    last_error_ = w < 0 ? sys_error(iface_, "send") : iface_ + ": short write";
    ++tx_failed_;
    return IoStatus::error;
  }
}

IoStatus SocketCanChannel::receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept {
  pollfd p{fd_, POLLIN, 0};
  const timespec ts = to_timespec(timeout);
  const int r = ::ppoll(&p, 1, &ts, nullptr);
  if (r == 0) return IoStatus::timeout;
  if (r < 0) {
    if (errno == EINTR) return IoStatus::timeout;
    last_error_ = sys_error(iface_, "ppoll");
    return IoStatus::error;
  }
  alignas(8) std::uint8_t buf[kCanFdMtu];
  alignas(cmsghdr) char
      control[CMSG_SPACE(sizeof(scm_timestamping)) + CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t)) + 64];
  iovec iov{buf, sizeof buf};
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return IoStatus::timeout;
    if (errno == ENETDOWN) {
      last_error_ = iface_ + ": interface is down";
      return IoStatus::closed;
    }
    last_error_ = sys_error(iface_, "recvmsg");
    return IoStatus::error;
  }
  const auto st = decode_kernel_frame(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(n)), frame);
  if (st != CanCodecStatus::ok) {
    last_error_ = iface_ + ": received " + std::to_string(n) + " bytes: " + to_string(st);
    return IoStatus::error;
  }
  frame.stamp = StampSource::none;
  frame.t_ns = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SO_TIMESTAMPING) {
      scm_timestamping t;
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      if (t.ts[2].tv_sec != 0 || t.ts[2].tv_nsec != 0) {
        frame.t_ns = static_cast<std::int64_t>(t.ts[2].tv_sec) * 1000000000LL + t.ts[2].tv_nsec;
        frame.stamp = StampSource::hardware;
      } else if (t.ts[0].tv_sec != 0 || t.ts[0].tv_nsec != 0) {
        frame.t_ns = static_cast<std::int64_t>(t.ts[0].tv_sec) * 1000000000LL + t.ts[0].tv_nsec;
        frame.stamp = StampSource::software;
      }
    } else if (c->cmsg_type == SO_TIMESTAMPNS) {
      timespec t;
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      frame.t_ns = static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
      frame.stamp = StampSource::software;
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      // The kernel reports the socket's total drops; count the increase.
      dropped_ += static_cast<std::uint32_t>(drops - last_ovfl_);
      last_ovfl_ = drops;
    }
  }
  if (frame.stamp == StampSource::none) frame.t_ns = realtime_ns();  // user-space time, marked as unstamped
  ++rx_;
  if (frame.error) ++err_;
  return IoStatus::ok;
}

}  // namespace hil::drivers
