#include "tripod_scene.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hil::diagnose::test {

namespace {

using Vec3 = Eigen::Vector3d;

double quantise(double v, double step) { return step > 0.0 ? step * std::round(v / step) : v; }

}  // namespace

ct::Scenario pressing_and_sliding(double duration_s) {
  ct::Scenario s;
  s.plate.origin_world_m = {0.45, 0.1, 0.05};
  s.plate.yaw_rad = 0.4;
  s.plate.tilt_x_rad = 0.05;
  s.plate.tilt_y_rad = -0.03;
  s.law.stiffness_n_per_m = 2e5;
  s.law.mu = 0.3;
  auto& tr = s.trajectory;
  tr.centre_x_m = 0.002;
  tr.centre_y_m = -0.001;
  tr.radius_m = 5e-3;
  tr.angular_rate_rad_per_s = 1.0;  // 5 mm/s
  tr.depth_m = 6e-5;
  tr.depth_amplitude_m = 8e-5;
  tr.depth_rate_rad_per_s = 2.1;
  tr.yaw_rad = 0.1;
  tr.yaw_amplitude_rad = 0.03;
  tr.yaw_rate_rad_per_s = 0.7;  // at most 1 mm/s at the feet
  s.sensor.rate_hz = 100.0;
  s.sensor.adc_subsamples = 1;
  s.sensor.noise_std << 0.1, 0.1, 0.1, 0.005, 0.005, 0.005;
  s.sensor.resolution << 0.1, 0.1, 0.1, 0.005, 0.005, 0.005;
  s.duration_s = duration_s;
  return s;
}

cid::Scene tripod_scene(const ct::Plate& plate, const ct::Tripod& tripod, const TripodRigOptions& o) {
  if (!(o.foot_height_m > 0.0 && o.foot_base_radius_m > 0.0 && o.plate_half_size_m > 0.0 && o.plate_thickness_m > 0.0))
    throw std::invalid_argument("tripod_scene: foot and plate sizes must be > 0");
  if (tripod.feet_body_m.empty()) throw std::invalid_argument("tripod_scene: the tripod has no feet");
  cid::Scene s;
  auto& feet = s.bodies[0];
  feet.name = "tripod";
  feet.on_end_effector = true;  // the truth's robot moves B; the rig reports B as the ee
  for (std::size_t i = 0; i < tripod.feet_body_m.size(); ++i) {
    const Vec3& tip = tripod.feet_body_m[i];
    // The truth's body z is the plate normal at every instant (PlateTrajectory): the apex points down.
    const double r = o.foot_base_radius_m, h = o.foot_height_m;
    std::vector<Vec3> v{tip, tip + Vec3(r, 0.0, h), tip + Vec3(-0.5 * r, 0.8660254037844386 * r, h),
                        tip + Vec3(-0.5 * r, -0.8660254037844386 * r, h)};
    feet.features.push_back({"foot" + std::to_string(i), {cid::Polyhedron::from_vertices(v)}});
  }
  auto& p = s.bodies[1];
  p.name = "plate";
  p.on_end_effector = false;
  p.T_attach = plate.T_world_plate();  // body frame = the truth's P
  const double a = o.plate_half_size_m;
  std::vector<Vec3> box;
  for (int i = 0; i < 8; ++i) box.emplace_back(i & 1 ? a : -a, i & 2 ? a : -a, i & 4 ? 0.0 : -o.plate_thickness_m);
  p.features.push_back({"top", {cid::Polyhedron::from_vertices(box)}});

  using K = cid::Uncertainty::Kind;
  s.uncertainties.push_back({kPlateHeight, 1, 0, K::translation, Vec3::UnitZ(), Vec3::Zero(), o.declared_plate_height_m,
                             o.height_prior_std_m});
  s.uncertainties.push_back({kPlateTiltX, 1, 0, K::rotation, Vec3::UnitX(), Vec3::Zero(), 0.0, o.tilt_prior_std_rad});
  s.uncertainties.push_back({kPlateTiltY, 1, 0, K::rotation, Vec3::UnitY(), Vec3::Zero(), 0.0, o.tilt_prior_std_rad});
  s.T_world_fp = plate.T_world_plate();  // the truth's wrench frame: P, about o_P
  return s;
}

std::vector<cid::Measurement> to_measurements(const std::vector<ct::Sample>& samples, const ReportedResolution& r) {
  if (r.position_m < 0.0 || r.velocity_m_per_s < 0.0 || !std::isfinite(r.position_m) || !std::isfinite(r.velocity_m_per_s))
    throw std::invalid_argument("to_measurements: resolutions must be finite and >= 0");
  std::vector<cid::Measurement> m;
  m.reserve(samples.size());
  for (const auto& s : samples) {
    cid::Measurement x;
    x.t_s = s.t_s;
    x.kin.T_world_ee = s.reported.T_world_body;
    x.kin.v_world_ee = s.reported.v_world_m_per_s;  // of B's origin = the ee origin
    x.kin.w_world_ee = s.reported.w_world_rad_per_s;
    for (int i = 0; i < 3; ++i) {
      x.kin.T_world_ee.translation()[i] = quantise(x.kin.T_world_ee.translation()[i], r.position_m);
      x.kin.v_world_ee[i] = quantise(x.kin.v_world_ee[i], r.velocity_m_per_s);
    }
    x.w_fp = s.wrench_measured;
    m.push_back(x);
  }
  return m;
}

}  // namespace hil::diagnose::test
