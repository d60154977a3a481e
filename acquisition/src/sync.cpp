#include <hil/acquisition/sync.hpp>
#include <hil/so3/so3.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hil::acquisition {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Windowed-sinc low-pass, Hann window, unit DC gain. fc: cut-off as a fraction of the input rate.
std::vector<double> lowpass_taps(int half, double fc) {
  std::vector<double> h(static_cast<std::size_t>(2 * half + 1));
  double sum = 0.0;
  for (int k = -half; k <= half; ++k) {
    const double sinc = k == 0 ? 2.0 * fc : std::sin(2.0 * kPi * fc * k) / (kPi * k);
    const double w = 0.5 * (1.0 + std::cos(kPi * k / (half + 1)));
    h[static_cast<std::size_t>(k + half)] = sinc * w;
    sum += sinc * w;
  }
  for (double& x : h) x /= sum;
  return h;
}

}  // namespace

Synchronizer::Synchronizer(const SyncConfig& config, Sink sink) : cfg_(config), sink_(std::move(sink)) {
  if (!(cfg_.wrench_rate_hz > 0) || !(cfg_.output_rate_hz > 0)) throw std::invalid_argument("sync: rates must be > 0");
  const double ratio = cfg_.wrench_rate_hz / cfg_.output_rate_hz;
  m_ = static_cast<int>(std::lround(ratio));
  if (m_ < 1 || std::abs(ratio - m_) > 1e-9 * ratio)
    throw std::invalid_argument("sync: the output rate must divide the force-plate rate (" + std::to_string(cfg_.wrench_rate_hz) +
                                " Hz / " + std::to_string(cfg_.output_rate_hz) + " Hz is not an integer)");
  half_ = m_ == 1 ? 0 : (cfg_.fir_half_length > 0 ? cfg_.fir_half_length : 2 * m_);
  taps_ = m_ == 1 ? std::vector<double>{1.0} : lowpass_taps(half_, 0.4 / m_);
  period_ns_ = static_cast<std::int64_t>(std::llround(1e9 / cfg_.wrench_rate_hz));
  gap_ns_ = static_cast<std::int64_t>(std::llround(cfg_.gap_periods * 1e9 / cfg_.wrench_rate_hz));
  reset_ns_ = cfg_.reset_gap_s > 0 ? static_cast<std::int64_t>(cfg_.reset_gap_s * 1e9)
                                   : std::max({gap_ns_, static_cast<std::int64_t>(half_) * period_ns_, std::int64_t{50'000'000}});
}

void Synchronizer::push_wrench(const WrenchReading& r) {
  if (have_prev_ && r.t_ns <= prev_.t_ns) return;  // duplicate or out of order: keep the first
  if (!have_prev_ || r.t_ns - prev_.t_ns > reset_ns_) {
    // First reading, or a hole too long to bridge: restart the grid and the filter here.
    if (have_prev_) {
      gap_pending_ = true;
      ++gaps_;
    }
    window_.clear();
    since_output_ = 0;
    grid_ns_ = r.t_ns;
    push_grid(r.t_ns, r.wrench_fp, r.quality, r.seq);
    grid_ns_ += period_ns_;
  } else {
    if (r.t_ns - prev_.t_ns > gap_ns_) {
      gap_pending_ = true;  // readings are missing: bridged by interpolation, and said so
      ++gaps_;
    }
    const double span = static_cast<double>(r.t_ns - prev_.t_ns);
    for (; grid_ns_ <= r.t_ns; grid_ns_ += period_ns_) {
      const double a = static_cast<double>(grid_ns_ - prev_.t_ns) / span;
      push_grid(grid_ns_, (1.0 - a) * prev_.wrench_fp + a * r.wrench_fp, prev_.quality | r.quality, r.seq);
    }
  }
  prev_ = r;
  have_prev_ = true;
  last_wrench_ns_ = r.t_ns;
  emit_ready(r.t_ns, false);
}

void Synchronizer::push_grid(std::int64_t t_ns, const Vector6d& w, std::uint32_t quality, std::uint64_t seq) {
  WrenchReading g;
  g.t_ns = t_ns;
  g.wrench_fp = w;
  g.quality = quality;
  g.seq = seq;
  window_.push_back(g);
  if (window_.size() > taps_.size()) window_.pop_front();
  ++since_output_;
  if (window_.size() < taps_.size() || since_output_ < m_) return;
  since_output_ = 0;
  SyncedSample s;
  const auto& centre = window_[static_cast<std::size_t>(half_)];
  s.t_ns = centre.t_ns;
  s.wrench_seq = centre.seq;
  s.wrench_age_s = 0.0;  // the centre value is at the sample's own time
  for (std::size_t k = 0; k < taps_.size(); ++k) {
    s.wrench_fp.noalias() += taps_[k] * window_[k].wrench_fp;
    s.quality |= window_[k].quality;
  }
  if (gap_pending_) s.quality |= kGapBefore;
  gap_pending_ = false;
  pending_.push_back(std::move(s));
}

void Synchronizer::push_pose(const PoseReading& r) {
  if (!poses_.empty() && r.t_ns <= poses_.back().t_ns) return;  // out of order or duplicate: keep the first
  poses_.push_back(r);
  if (refused_) poses_.back().quality |= kDeviceFault;
  refused_ = false;
  emit_ready(last_wrench_ns_, false);
}

void Synchronizer::pose_refused() { refused_ = true; }

void Synchronizer::flush() { emit_ready(last_wrench_ns_, true); }

bool Synchronizer::fill_pose(SyncedSample& s, bool force) const {
  const std::int64_t W = static_cast<std::int64_t>(cfg_.twist_half_window_s * 1e9);
  // Ready when a pose past the twist window exists (interpolation and twist are then final).
  const bool complete = !poses_.empty() && poses_.back().t_ns >= s.t_ns + W;
  if (!complete && !force) return false;
  if (poses_.empty()) {
    s.quality |= kPoseExtrapolated | kPoseStale;
    s.pose_age_s = INFINITY;
    return true;
  }
  // Bracket s.t_ns.
  std::size_t b = 0;
  while (b < poses_.size() && poses_[b].t_ns < s.t_ns) ++b;
  if (b == 0) {
    const auto& p = poses_.front();
    s.p_world_ee_m = p.p_world_ee_m, s.q_world_ee = p.q_world_ee, s.joints_rad = p.joints_rad, s.pose_seq = p.seq;
    s.pose_age_s = (s.t_ns - p.t_ns) * 1e-9;
    s.quality |= kPoseExtrapolated | (p.quality & kDeviceFault);
  } else if (b == poses_.size()) {
    const auto& p = poses_.back();
    s.p_world_ee_m = p.p_world_ee_m, s.q_world_ee = p.q_world_ee, s.joints_rad = p.joints_rad, s.pose_seq = p.seq;
    s.pose_age_s = (s.t_ns - p.t_ns) * 1e-9;
    s.quality |= kPoseExtrapolated | (refused_ ? kDeviceFault : 0U);
  } else {
    const auto& p0 = poses_[b - 1];
    const auto& p1 = poses_[b];
    const double a = static_cast<double>(s.t_ns - p0.t_ns) / static_cast<double>(p1.t_ns - p0.t_ns);
    s.p_world_ee_m = (1.0 - a) * p0.p_world_ee_m + a * p1.p_world_ee_m;
    s.q_world_ee = p0.q_world_ee.slerp(a, p1.q_world_ee).normalized();
    if (p0.joints_rad.size() == p1.joints_rad.size()) s.joints_rad = (1.0 - a) * p0.joints_rad + a * p1.joints_rad;
    s.pose_seq = p1.seq;
    s.pose_age_s = std::min(s.t_ns - p0.t_ns, p1.t_ns - s.t_ns) * 1e-9;
    // A pose that follows refused polls (a Modbus exception burst) marks the samples interpolated
    // across the refusal: the motion in between was not read.
    s.quality |= p1.quality & kDeviceFault;
  }
  if (s.pose_age_s > cfg_.pose_stale_s) s.quality |= kPoseStale;

  // Twist: least-squares slope over the poses within +-W of the sample time.
  double st = 0, stt = 0;
  Eigen::Vector3d sp = Eigen::Vector3d::Zero(), stp = Eigen::Vector3d::Zero(), sr = Eigen::Vector3d::Zero(), str = Eigen::Vector3d::Zero();
  int n = 0;
  const Eigen::Quaterniond q_ref_inv = s.q_world_ee.conjugate();
  for (const auto& p : poses_) {
    if (p.t_ns < s.t_ns - W || p.t_ns > s.t_ns + W) continue;
    const double tau = (p.t_ns - s.t_ns) * 1e-9;
    const Eigen::Vector3d rv = so3::log(p.q_world_ee * q_ref_inv);  // world-frame rotation vector
    st += tau, stt += tau * tau, sp += p.p_world_ee_m, stp += tau * p.p_world_ee_m, sr += rv, str += tau * rv;
    ++n;
  }
  if (n >= 2) {
    const double den = n * stt - st * st;
    if (den > 0) {
      s.v_world_ee_m_per_s = (n * stp - st * sp) / den;
      s.w_world_ee_rad_per_s = (n * str - st * sr) / den;
    }
  }
  return true;
}

void Synchronizer::emit_ready(std::int64_t now_ns, bool force) {
  const std::int64_t timeout = static_cast<std::int64_t>(cfg_.pose_timeout_s * 1e9);
  while (!pending_.empty()) {
    SyncedSample& s = pending_.front();
    const bool timed_out = now_ns - s.t_ns > timeout;
    if (!fill_pose(s, force || timed_out)) break;
    s.index = next_index_++;
    sink_(s);
    pending_.pop_front();
  }
  // Keep the poses a future output may still need: those within the twist window of the oldest
  // pending (or next) output, plus one before it for interpolation.
  const std::int64_t W = static_cast<std::int64_t>(cfg_.twist_half_window_s * 1e9);
  const std::int64_t oldest_needed =
      (pending_.empty()
           ? (window_.empty() ? now_ns : window_[std::min<std::size_t>(window_.size() - 1, static_cast<std::size_t>(half_))].t_ns)
           : pending_.front().t_ns) -
      W;
  while (poses_.size() > 2 && poses_[1].t_ns < oldest_needed) poses_.pop_front();
}

format::Sample to_row(const SyncedSample& s, double t_s) {
  format::Sample row;
  row.t_s = t_s;
  row.p_world_ee_m = s.p_world_ee_m;
  row.q_world_ee = s.q_world_ee;
  row.v_world_ee_m_per_s = s.v_world_ee_m_per_s;
  row.w_world_ee_rad_per_s = s.w_world_ee_rad_per_s;
  row.f_fp_n = s.wrench_fp.head<3>();
  row.m_fp_nm = s.wrench_fp.tail<3>();
  return row;
}

}  // namespace hil::acquisition
