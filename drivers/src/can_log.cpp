#include <cerrno>
#include <cstring>
#include <thread>

#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/candump.hpp>
#include <hil/drivers/error.hpp>

namespace hil::drivers {

std::unique_ptr<CanLogChannel> CanLogChannel::open_read(const std::string& path, CanLogOptions options) {
  std::unique_ptr<CanLogChannel> c(new CanLogChannel());
  c->f_ = std::fopen(path.c_str(), "rb");
  if (c->f_ == nullptr) throw DeviceError("candump log " + path + ": cannot open for reading: " + std::strerror(errno));
  c->path_ = path;
  c->opt_ = std::move(options);
  if (!(c->opt_.speed > 0.0)) throw ConfigError("speed", "playback speed must be > 0");
  return c;
}

std::unique_ptr<CanLogChannel> CanLogChannel::open_write(const std::string& path, CanLogOptions options) {
  std::unique_ptr<CanLogChannel> c(new CanLogChannel());
  c->f_ = std::fopen(path.c_str(), "wb");
  if (c->f_ == nullptr) throw DeviceError("candump log " + path + ": cannot create: " + std::strerror(errno));
  c->path_ = path;
  c->write_ = true;
  c->opt_ = std::move(options);
  if (c->opt_.interface.empty()) c->opt_.interface = "can0";
  return c;
}

CanLogChannel::~CanLogChannel() {
  if (f_ != nullptr) std::fclose(f_);
}

void CanLogChannel::flush() noexcept {
  if (write_ && f_ != nullptr) std::fflush(f_);
}

IoStatus CanLogChannel::send(const CanFrame& frame, std::chrono::nanoseconds /*timeout*/) noexcept {
  if (!write_) {
    last_error_ = path_ + ": log opened for reading";
    ++stats_.tx_failed;
    return IoStatus::error;
  }
  if (const char* p = frame_problem(frame)) {
    last_error_ = path_ + ": " + p;
    ++stats_.tx_failed;
    return IoStatus::error;
  }
  try {
    CanFrame f = frame;
    if (f.t_ns == 0) f.t_ns = realtime_ns();
    std::string line = format_candump_line(f, opt_.interface);
    line.push_back('\n');
    if (std::fwrite(line.data(), 1, line.size(), f_) != line.size()) {
      last_error_ = path_ + ": write failed: " + std::strerror(errno);
      ++stats_.tx_failed;
      return IoStatus::error;
    }
  } catch (...) {
    ++stats_.tx_failed;
    return IoStatus::error;
  }
  ++stats_.tx_frames;
  return IoStatus::ok;
}

IoStatus CanLogChannel::receive(CanFrame& frame, std::chrono::nanoseconds /*timeout*/) noexcept {
  if (write_) return IoStatus::closed;
  try {
    for (;;) {
      line_.clear();
      int c;
      while ((c = std::fgetc(f_)) != EOF && c != '\n') line_.push_back(static_cast<char>(c));
      if (c == EOF && line_.empty()) return IoStatus::closed;
      ++line_no_;
      if (line_.empty() || line_ == "\r") continue;
      std::string iface;
      if (auto e = parse_candump_line(line_, frame, iface); !e.empty()) {
        last_error_ = path_ + ":" + std::to_string(line_no_) + ": " + e;
        return IoStatus::error;
      }
      if (!opt_.interface.empty() && iface != opt_.interface) continue;
      if (frame.error ? (frame.id & opt_.channel.error_mask) == 0 : !passes(opt_.channel.filters, frame)) continue;
      last_iface_ = std::move(iface);
      if (opt_.realtime) {
        if (first_log_ns_ < 0) {
          first_log_ns_ = frame.t_ns;
          first_wall_ = std::chrono::steady_clock::now();
        } else {
          const auto dt = std::chrono::nanoseconds(static_cast<std::int64_t>(static_cast<double>(frame.t_ns - first_log_ns_) / opt_.speed));
          std::this_thread::sleep_until(first_wall_ + dt);
        }
      }
      ++stats_.rx_frames;
      if (frame.error) ++stats_.error_frames;
      return IoStatus::ok;
    }
  } catch (...) {
    last_error_ = path_ + ": out of memory";
    return IoStatus::error;
  }
}

CanRecordingChannel::CanRecordingChannel(std::unique_ptr<CanChannel> inner, std::unique_ptr<CanLogChannel> log, bool record_sent)
    : inner_(std::move(inner)), log_(std::move(log)), record_sent_(record_sent) {
  if (!inner_) throw ConfigError("channel", "no CAN channel to record");
  if (!log_) throw ConfigError("log", "no log to record into");
}

IoStatus CanRecordingChannel::send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept {
  const IoStatus st = inner_->send(frame, timeout);
  if (st == IoStatus::ok && record_sent_) {
    CanFrame f = frame;
    f.t_ns = realtime_ns();
    if (log_->send(f, timeout) != IoStatus::ok) ++log_failures_;
  }
  return st;
}

IoStatus CanRecordingChannel::receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept {
  const IoStatus st = inner_->receive(frame, timeout);
  if (st == IoStatus::ok && log_->send(frame, timeout) != IoStatus::ok) ++log_failures_;
  return st;
}

}  // namespace hil::drivers
