#include <hil/contact_id/model.hpp>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace hil::contact_id {

Eigen::VectorXd Scene::design() const {
  Eigen::VectorXd x(static_cast<Eigen::Index>(uncertainties.size()));
  for (std::size_t j = 0; j < uncertainties.size(); ++j) x[static_cast<Eigen::Index>(j)] = uncertainties[j].design_value;
  return x;
}

Eigen::VectorXd Scene::prior_std() const {
  Eigen::VectorXd x(static_cast<Eigen::Index>(uncertainties.size()));
  for (std::size_t j = 0; j < uncertainties.size(); ++j) x[static_cast<Eigen::Index>(j)] = uncertainties[j].prior_std;
  return x;
}

std::vector<std::pair<int, int>> Scene::polyhedron_index(int body) const {
  std::vector<std::pair<int, int>> out;
  const auto& b = bodies[static_cast<std::size_t>(body)];
  for (std::size_t f = 0; f < b.features.size(); ++f)
    for (std::size_t p = 0; p < b.features[f].polyhedra.size(); ++p) out.emplace_back(static_cast<int>(f), static_cast<int>(p));
  return out;
}

void ContactModel::check() const {
  if (!(std::isfinite(K) && K > 0.0)) throw std::invalid_argument("contact stiffness K must be > 0, got " + std::to_string(K));
  if (!(std::isfinite(mu) && mu >= 0.0)) throw std::invalid_argument("friction coefficient mu must be >= 0, got " + std::to_string(mu));
  if (!(std::isfinite(v_tm) && v_tm >= 0.0))
    throw std::invalid_argument("sticking threshold v_t,m must be >= 0, got " + std::to_string(v_tm));
}

Eigen::Isometry3d body_pose(const Body& b, const Eigen::Isometry3d& T_world_ee) {
  return b.on_end_effector ? Eigen::Isometry3d(T_world_ee * b.T_attach) : b.T_attach;
}

void pose_scene(const Scene& s, const Eigen::VectorXd& x, const Eigen::Isometry3d& T_world_ee, PosedScene& out) {
  for (int b = 0; b < 2; ++b) {
    const auto& body = s.bodies[static_cast<std::size_t>(b)];
    const Eigen::Isometry3d T = body_pose(body, T_world_ee);
    out.T_world_body[static_cast<std::size_t>(b)] = T;
    auto& polys = out.polys[static_cast<std::size_t>(b)];
    std::size_t n = 0;
    for (const auto& f : body.features) n += f.polyhedra.size();
    polys.resize(n);
    std::size_t i = 0;
    for (std::size_t f = 0; f < body.features.size(); ++f) {
      const Eigen::Isometry3d Tf = T * feature_transform(s.uncertainties, x, b, static_cast<int>(f));
      for (const auto& p : body.features[f].polyhedra) polys[i++].pose(p, Tf);
    }
  }
}

static Vec3 point_velocity(const Body& b, const Kinematics& k, const Vec3& p) {
  if (!b.on_end_effector) return Vec3::Zero();
  return k.v_world_ee + k.w_world_ee.cross(p - k.T_world_ee.translation());
}

Vec3 relative_velocity(const Scene& s, const Kinematics& k, const Vec3& p) {
  return point_velocity(s.bodies[0], k, p) - point_velocity(s.bodies[1], k, p);
}

void tangent(const Scene& s, const Kinematics& k, double v_tm, ContactPoint& c) {
  const Vec3 v = relative_velocity(s, k, c.point);
  const Vec3 vt = v - v.dot(c.normal) * c.normal;
  c.slip_speed = vt.norm();
  c.slip_direction = c.slip_speed > 0.0 ? Vec3(-vt / c.slip_speed) : Vec3::Zero();
  c.tangent = c.slip_speed > v_tm ? c.slip_direction : Vec3::Zero();
}

void mindist(const Scene& s, const Kinematics& k, const Eigen::VectorXd& x, double v_tm, std::vector<ContactPoint>& out,
             MindistWorkspace& ws) {
  out.clear();
  pose_scene(s, x, k.T_world_ee, ws.posed);
  const auto& A = ws.posed.polys[0];
  const auto& B = ws.posed.polys[1];
  for (std::size_t i = 0; i < A.size(); ++i)
    for (std::size_t j = 0; j < B.size(); ++j) {
      if (!near(A[i], B[j])) continue;
      PairContact pc;
      if (!penetration(A[i], B[j], pc, ws.clip)) continue;
      ContactPoint c;
      c.delta = pc.delta;
      c.point = pc.point;
      c.normal = pc.normal;
      c.poly1 = static_cast<int>(i);
      c.poly2 = static_cast<int>(j);
      tangent(s, k, v_tm, c);
      out.push_back(c);
    }
}

Regressor regressor_row(const ContactPoint& c, const Eigen::Isometry3d& T_world_o1) {
  const auto Rt = T_world_o1.linear().transpose();
  const Vec3 p = Rt * (c.point - T_world_o1.translation());
  const Vec3 n = Rt * c.normal;
  const Vec3 t = Rt * c.tangent;
  Regressor r;
  r.block<3, 1>(0, 0) = c.delta * n;
  r.block<3, 1>(0, 1) = c.delta * t;
  r.block<3, 1>(3, 0) = c.delta * p.cross(n);
  r.block<3, 1>(3, 1) = c.delta * p.cross(t);
  return r;
}

Regressor regressor(const std::vector<ContactPoint>& contacts, const Eigen::Isometry3d& T_world_o1) {
  Regressor r = Regressor::Zero();
  for (const auto& c : contacts) r += regressor_row(c, T_world_o1);
  return r;
}

Vector6d plate_to_object1(const Vector6d& w_fp, const Eigen::Isometry3d& T_world_fp, const Eigen::Isometry3d& T_world_o1) {
  // Plate wrench in world, about the world origin.
  const Vec3 f_w = T_world_fp.linear() * w_fp.head<3>();
  const Vec3 m_w = T_world_fp.linear() * w_fp.tail<3>() + T_world_fp.translation().cross(f_w);
  // Object 1 feels the opposite; move to o1's origin and frame.
  const Vec3 f1 = -f_w;
  const Vec3 m1 = -m_w - T_world_o1.translation().cross(f1);
  Vector6d out;
  out.head<3>() = T_world_o1.linear().transpose() * f1;
  out.tail<3>() = T_world_o1.linear().transpose() * m1;
  return out;
}

Vector6d object1_to_plate(const Vector6d& w_o1, const Eigen::Isometry3d& T_world_fp, const Eigen::Isometry3d& T_world_o1) {
  const Vec3 f1 = T_world_o1.linear() * w_o1.head<3>();
  const Vec3 m1 = T_world_o1.linear() * w_o1.tail<3>() + T_world_o1.translation().cross(f1);
  const Vec3 f_w = -f1;
  const Vec3 m_w = -m1 - T_world_fp.translation().cross(f_w);
  Vector6d out;
  out.head<3>() = T_world_fp.linear().transpose() * f_w;
  out.tail<3>() = T_world_fp.linear().transpose() * m_w;
  return out;
}

Vector6d plate_wrench(const Scene& s, const ContactModel& m, const Eigen::VectorXd& x, const Kinematics& k, MindistWorkspace& ws,
                      std::vector<ContactPoint>& contacts) {
  mindist(s, k, x, m.v_tm, contacts, ws);
  const Eigen::Isometry3d T_world_o1 = body_pose(s.bodies[0], k.T_world_ee);
  const Vector6d w_o1 = regressor(contacts, T_world_o1) * m.theta();
  return object1_to_plate(w_o1, s.T_world_fp, T_world_o1);
}

static double quantise(double v, double step) { return step > 0.0 ? std::round(v / step) * step : v; }

std::vector<SimulatedSample> simulate(const Scene& s, const ContactModel& m, const Eigen::VectorXd& x_true,
                                      const std::vector<Kinematics>& truth, const SensorModel& sensor) {
  m.check();
  std::mt19937_64 rng(sensor.seed);
  std::normal_distribution<double> g(0.0, 1.0);
  MindistWorkspace ws;
  std::vector<ContactPoint> contacts;
  std::vector<SimulatedSample> out;
  out.reserve(truth.size());
  for (const auto& k : truth) {
    SimulatedSample smp;
    smp.w_fp_true = plate_wrench(s, m, x_true, k, ws, contacts);
    smp.contacts = static_cast<int>(contacts.size());
    smp.kin = k;
    for (int i = 0; i < 3; ++i) {
      smp.kin.T_world_ee.translation()[i] = quantise(k.T_world_ee.translation()[i], sensor.position_resolution_m);
      smp.kin.v_world_ee[i] = quantise(k.v_world_ee[i], sensor.velocity_resolution_m_per_s);
    }
    for (int i = 0; i < 6; ++i) {
      const bool force = i < 3;
      const double noise = force ? sensor.force_noise_n : sensor.moment_noise_nm;
      const double step = force ? sensor.force_resolution_n : sensor.moment_resolution_nm;
      smp.w_fp[i] = quantise(smp.w_fp_true[i] + noise * g(rng), step);
    }
    out.push_back(smp);
  }
  return out;
}

}  // namespace hil::contact_id
