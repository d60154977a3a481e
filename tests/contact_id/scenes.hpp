#pragma once
// Small analytic scenes shared by the contact_id tests and benchmarks.
#include <cmath>
#include <vector>

#include <hil/contact_id/identification.hpp>

namespace hil::contact_id::test {

inline std::vector<Vec3> box(const Vec3& lo, const Vec3& hi) {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  return v;
}

inline PosedPolyhedron posed(const Polyhedron& p, const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity()) {
  PosedPolyhedron q;
  q.pose(p, T);
  return q;
}

/// Object 1: a 3 cm cube whose frame is at the centre of its bottom face, held by the ee.
/// Object 2: a 20 cm block whose top face is the world plane z = 0.
inline Scene cube_on_block() {
  Scene s;
  s.bodies[0].name = "cube";
  s.bodies[0].on_end_effector = true;
  s.bodies[0].features.push_back({"body", {Polyhedron::from_vertices(box({-0.015, -0.015, 0.0}, {0.015, 0.015, 0.03}))}});
  s.bodies[1].name = "block";
  s.bodies[1].features.push_back({"top", {Polyhedron::from_vertices(box({-0.1, -0.1, -0.05}, {0.1, 0.1, 0.0}))}});
  s.bodies[1].features.push_back({"far", {Polyhedron::from_vertices(box({0.5, 0.5, 0.0}, {0.6, 0.6, 0.1}))}});
  return s;
}

/// Press, slide along x and y at 5 mm/s with a varying depth, and tilt slightly: a trajectory that
/// excites K and μK, with some samples out of contact. Pose z = -depth.
inline std::vector<Kinematics> press_slide(int n = 200, double dt = 0.02) {
  std::vector<Kinematics> out;
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    auto pos = [](double tt) {
      const double depth = 2e-4 + 1.5e-4 * std::sin(1.3 * tt);
      return Vec3(0.005 * std::sin(0.9 * tt), 0.004 * std::cos(0.7 * tt), tt < 0.2 ? 1e-3 : -depth);
    };
    auto ang = [](double tt) { return Vec3(0.004 * std::sin(0.5 * tt), 0.003 * std::cos(0.8 * tt), 0.0); };
    const double h = 1e-5;
    Kinematics k;
    const Vec3 a = ang(t);
    k.T_world_ee.linear() = Eigen::AngleAxisd(a.norm(), a.norm() > 0 ? Vec3(a.normalized()) : Vec3::UnitZ()).toRotationMatrix();
    k.T_world_ee.translation() = pos(t);
    k.v_world_ee = (pos(t + h) - pos(t - h)) / (2 * h);
    k.w_world_ee = (ang(t + h) - ang(t - h)) / (2 * h);  // small angles: close enough to the true ω
    out.push_back(k);
  }
  return out;
}

inline std::vector<Measurement> measure(const std::vector<SimulatedSample>& s, double dt = 0.02) {
  std::vector<Measurement> m;
  for (std::size_t i = 0; i < s.size(); ++i) m.push_back({static_cast<double>(i) * dt, s[i].kin, s[i].w_fp});
  return m;
}

}  // namespace hil::contact_id::test
