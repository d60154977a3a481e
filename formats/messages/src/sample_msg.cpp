#include <hil/messages/sample_msg.hpp>

#include <cmath>

namespace hil::messages {

builtin_interfaces::msg::Time to_time(double t_s) {
  builtin_interfaces::msg::Time t;
  double sec = std::floor(t_s);
  auto ns = static_cast<std::int64_t>(std::llround((t_s - sec) * 1e9));
  if (ns >= 1000000000) {  // rounding carried into the next second
    sec += 1.0;
    ns -= 1000000000;
  }
  t.sec(static_cast<std::int32_t>(sec));
  t.nanosec(static_cast<std::uint32_t>(ns));
  return t;
}

builtin_interfaces::msg::Time to_time_ns(std::int64_t t_ns) {
  std::int64_t sec = t_ns / 1'000'000'000, ns = t_ns % 1'000'000'000;
  if (ns < 0) {
    ns += 1'000'000'000;
    --sec;
  }
  builtin_interfaces::msg::Time t;
  t.sec(static_cast<std::int32_t>(sec));
  t.nanosec(static_cast<std::uint32_t>(ns));
  return t;
}

double from_time(const builtin_interfaces::msg::Time& t) { return t.sec() + t.nanosec() * 1e-9; }

namespace {
geometry_msgs::msg::Vector3 vec(const Eigen::Vector3d& v) {
  geometry_msgs::msg::Vector3 m;
  m.x(v.x());
  m.y(v.y());
  m.z(v.z());
  return m;
}
Eigen::Vector3d vec(const geometry_msgs::msg::Vector3& m) { return {m.x(), m.y(), m.z()}; }
}  // namespace

hil_msgs::msg::PoseWrenchSample to_message(const format::Sample& s, std::uint64_t index,
                                           const Eigen::Ref<const Eigen::RowVectorXd>& joints_rad) {
  hil_msgs::msg::PoseWrenchSample m;
  m.header().stamp(to_time(s.t_s));
  m.header().frame_id("world");
  m.sample_index(index);
  m.t_s(s.t_s);
  m.pose_world_ee().position().x(s.p_world_ee_m.x());
  m.pose_world_ee().position().y(s.p_world_ee_m.y());
  m.pose_world_ee().position().z(s.p_world_ee_m.z());
  m.pose_world_ee().orientation().w(s.q_world_ee.w());
  m.pose_world_ee().orientation().x(s.q_world_ee.x());
  m.pose_world_ee().orientation().y(s.q_world_ee.y());
  m.pose_world_ee().orientation().z(s.q_world_ee.z());
  m.twist_world_ee().linear(vec(s.v_world_ee_m_per_s));
  m.twist_world_ee().angular(vec(s.w_world_ee_rad_per_s));
  m.wrench_fp().force(vec(s.f_fp_n));
  m.wrench_fp().torque(vec(s.m_fp_nm));
  m.joint_positions_rad().assign(joints_rad.data(), joints_rad.data() + joints_rad.size());
  return m;
}

format::Sample from_message(const hil_msgs::msg::PoseWrenchSample& m, Eigen::VectorXd* joints_rad) {
  format::Sample s;
  s.t_s = m.t_s();
  const auto& p = m.pose_world_ee().position();
  const auto& q = m.pose_world_ee().orientation();
  s.p_world_ee_m = {p.x(), p.y(), p.z()};
  s.q_world_ee = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
  s.v_world_ee_m_per_s = vec(m.twist_world_ee().linear());
  s.w_world_ee_rad_per_s = vec(m.twist_world_ee().angular());
  s.f_fp_n = vec(m.wrench_fp().force());
  s.m_fp_nm = vec(m.wrench_fp().torque());
  if (joints_rad)
    *joints_rad = Eigen::Map<const Eigen::VectorXd>(m.joint_positions_rad().data(),
                                                    static_cast<Eigen::Index>(m.joint_positions_rad().size()));
  return s;
}

}  // namespace hil::messages
