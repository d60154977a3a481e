#include <algorithm>
#include <cmath>

#include <hil/drivers/error.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/so3/so3.hpp>

namespace hil::drivers {

Scenario::Scenario(std::vector<ScenarioPoint> points, bool loop) : points_(std::move(points)), loop_(loop) {
  if (points_.empty()) throw ConfigError("scenario", "no points");
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const auto& p = points_[i];
    const std::string f = "scenario[" + std::to_string(i) + "]";
    if (!std::isfinite(p.t_s) || (i > 0 && !(p.t_s > points_[i - 1].t_s)))
      throw ConfigError(f + ".t_s", "times must be finite and strictly increasing");
    if (p.joints_rad.size() != points_[0].joints_rad.size())
      throw ConfigError(f + ".joints_rad", "joint count differs from the first point");
    if (!p.w_fp.allFinite() || !p.p_base_tcp_m.allFinite() || !p.q_base_tcp.coeffs().allFinite()) throw ConfigError(f, "non-finite value");
  }
  for (auto& p : points_) p.q_base_tcp.normalize();
}

void Scenario::at(double t, ScenarioPoint& out) const {
  const double t0 = points_.front().t_s, t1 = points_.back().t_s;
  if (loop_ && t1 > t0) {
    t = t0 + std::fmod(t - t0, t1 - t0);
    if (t < t0) t += t1 - t0;
  }
  out.joints_rad.resize(points_[0].joints_rad.size());
  if (t <= t0 || points_.size() == 1) {
    const auto& p = points_.front();
    out.t_s = t;
    out.w_fp = p.w_fp;
    std::copy(p.joints_rad.begin(), p.joints_rad.end(), out.joints_rad.begin());
    out.p_base_tcp_m = p.p_base_tcp_m;
    out.q_base_tcp = p.q_base_tcp;
    return;
  }
  if (t >= t1) {
    const auto& p = points_.back();
    out.t_s = t;
    out.w_fp = p.w_fp;
    std::copy(p.joints_rad.begin(), p.joints_rad.end(), out.joints_rad.begin());
    out.p_base_tcp_m = p.p_base_tcp_m;
    out.q_base_tcp = p.q_base_tcp;
    return;
  }
  const auto it = std::upper_bound(points_.begin(), points_.end(), t, [](double v, const ScenarioPoint& p) { return v < p.t_s; });
  const ScenarioPoint& b = *it;
  const ScenarioPoint& a = *(it - 1);
  const double s = (t - a.t_s) / (b.t_s - a.t_s);
  out.t_s = t;
  out.w_fp = a.w_fp + s * (b.w_fp - a.w_fp);
  for (std::size_t j = 0; j < out.joints_rad.size(); ++j) out.joints_rad[j] = a.joints_rad[j] + s * (b.joints_rad[j] - a.joints_rad[j]);
  out.p_base_tcp_m = a.p_base_tcp_m + s * (b.p_base_tcp_m - a.p_base_tcp_m);
  out.q_base_tcp = a.q_base_tcp.slerp(s, b.q_base_tcp);
}

void encode_state(const RegisterMap& map, std::span<const double> joints, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
                  std::span<std::uint16_t> holding) {
  const Eigen::Vector3d r = so3::log(q);
  for (const auto& e : map.entries) {
    const Quantity qu = parse_quantity(e.quantity, "quantity");
    double v = 0.0;
    switch (qu.kind) {
      case Quantity::Kind::joint: v = qu.joint < joints.size() ? joints[qu.joint] : 0.0; break;
      case Quantity::Kind::px: v = p.x(); break;
      case Quantity::Kind::py: v = p.y(); break;
      case Quantity::Kind::pz: v = p.z(); break;
      case Quantity::Kind::rx: v = r.x(); break;
      case Quantity::Kind::ry: v = r.y(); break;
      case Quantity::Kind::rz: v = r.z(); break;
    }
    if (e.address + register_count(e.type) > holding.size()) continue;
    std::uint16_t* turns = e.turns_address >= 0 && static_cast<std::size_t>(e.turns_address) < holding.size()
                               ? &holding[static_cast<std::size_t>(e.turns_address)]
                               : nullptr;
    encode_entry(e, v, &holding[e.address], turns);
  }
}

void WrenchSource::set(const Vector6d& w_fp) {
  std::lock_guard lk(m_);
  wrench_ = w_fp;
}

Vector6d WrenchSource::at(double t_s) const {
  std::lock_guard lk(m_);
  if (!scenario_) return wrench_;
  scenario_->at(clock_.scenario_time(t_s), point_);
  return point_.w_fp;
}

}  // namespace hil::drivers
