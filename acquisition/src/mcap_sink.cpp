#include <hil/acquisition/mcap_sink.hpp>

#include <cmath>

#include <hil/messages/sample_msg.hpp>

namespace hil::acquisition {

McapSink::McapSink(const std::string& path, const format::RigSpec& rig, std::size_t joint_count, std::int64_t start_ns,
                   mcap::Compression compression, bool tf)
    : writer_(path, &rig, joint_count, start_ns, mcap::RecordingOptions{compression, 1 << 20, 0, tf}), start_ns_(start_ns),
      joints_(joint_count), joints_buf_(joint_count, 0.0) {}

void McapSink::sample(const acquisition::SyncedSample& s) {
  // The same row the CSV recorder writes: t from the run's start, joints zero-filled before the
  // first pose, a pose age that is not finite written as -1.
  const auto row = acquisition::to_row(s, static_cast<double>(s.t_ns - start_ns_) * 1e-9);
  std::lock_guard<std::mutex> lock(mutex_);
  for (std::size_t j = 0; j < joints_; ++j)
    joints_buf_[j] = j < static_cast<std::size_t>(s.joints_rad.size()) ? s.joints_rad[static_cast<Eigen::Index>(j)] : 0.0;
  mcap::SampleExtras x;
  x.wrench_seq = s.wrench_seq;
  x.pose_seq = s.pose_seq;
  x.wrench_age_s = s.wrench_age_s;
  x.pose_age_s = std::isfinite(s.pose_age_s) ? s.pose_age_s : -1.0;
  x.quality = s.quality;
  writer_.write_sample(row, rows_++, joints_ ? joints_buf_.data() : nullptr, x);
}

void McapSink::health(const std::vector<acquisition::DeviceHealth>& devices, std::int64_t now_ns, bool force) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool periodic = force || now_ns - last_periodic_ns_ >= static_cast<std::int64_t>(period_s_ * 1e9);
  if (periodic) last_periodic_ns_ = now_ns;
  for (const auto& h : devices) {
    const auto it = last_state_.find(h.device);
    if (!periodic && it != last_state_.end() && it->second == h.state) continue;
    last_state_[h.device] = h.state;
    hil_msgs::msg::DeviceStatus m;
    m.stamp(mcap::to_ros_time(now_ns));
    m.device(h.device);
    m.state(static_cast<std::uint8_t>(h.state));
    m.connected(h.connected);
    m.rate_hz(h.rate_hz);
    m.last_sample_age_s(h.last_sample_age_s);
    m.samples(h.samples);
    m.frames_dropped(h.frames_dropped);
    m.device_faults(h.device_faults);
    m.errors(h.errors);
    m.last_error(h.last_error);
    writer_.write_status(m);
  }
}

void McapSink::flush() {
  std::lock_guard<std::mutex> lock(mutex_);
  writer_.flush();
}

void McapSink::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  writer_.close();
}

std::uint64_t McapSink::messages() {
  std::lock_guard<std::mutex> lock(mutex_);
  return writer_.messages();
}

}  // namespace hil::acquisition
