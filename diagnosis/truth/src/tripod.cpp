#include <hil/contact_truth/tripod.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <tuple>
#include <utility>
#include <sstream>
#include <stdexcept>

namespace hil::contact_truth {
namespace {

using Eigen::Vector3d;

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }
bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

std::string law_problems(const ContactLaw& l) {
  std::ostringstream o;
  if (!finite_positive(l.stiffness_n_per_m)) o << "law.stiffness_n_per_m must be > 0 (got " << l.stiffness_n_per_m << "); ";
  if (!finite_positive(l.exponent)) o << "law.exponent must be > 0 (got " << l.exponent << "); ";
  if (!finite_positive(l.delta_ref_m)) o << "law.delta_ref_m must be > 0 (got " << l.delta_ref_m << "); ";
  if (!finite_non_negative(l.damping_n_s_per_m)) o << "law.damping_n_s_per_m must be >= 0 (got " << l.damping_n_s_per_m << "); ";
  if (!finite_non_negative(l.damping_exponent)) o << "law.damping_exponent must be >= 0 (got " << l.damping_exponent << "); ";
  if (!finite_non_negative(l.mu)) o << "law.mu must be >= 0 (got " << l.mu << "); ";
  if (!finite_positive(l.slip_regularisation_m_per_s))
    o << "law.slip_regularisation_m_per_s must be > 0 (got " << l.slip_regularisation_m_per_s << "); ";
  if (!finite_non_negative(l.viscous_n_s_per_m)) o << "law.viscous_n_s_per_m must be >= 0 (got " << l.viscous_n_s_per_m << "); ";
  if (!finite_non_negative(l.mu_rest)) o << "law.mu_rest must be >= 0 (got " << l.mu_rest << "); ";
  if (!finite_non_negative(l.stribeck_speed_m_per_s))
    o << "law.stribeck_speed_m_per_s must be >= 0 (got " << l.stribeck_speed_m_per_s << "); ";
  return o.str();
}

void throw_if(const std::string& problems) {
  if (problems.empty()) return;
  throw std::invalid_argument("contact_truth: " + problems.substr(0, problems.size() - 2));
}

Eigen::Matrix3d rot_z(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

// The body state relative to the plate (P): position, yaw and their rates.
struct PlanarState {
  Vector3d p_plate_m, v_plate_m_per_s;
  double yaw_rad = 0.0, yaw_rate_rad_per_s = 0.0;
};

// A move of `distance` in `duration` from rest to rest: the distance covered and the speed at
// tau in [0, duration], with a trapezoidal speed profile (ramp: the share of the duration spent
// accelerating, and as much decelerating), or a constant speed (ramp = 0).
std::pair<double, double> move(double distance, double duration, double ramp, double tau) {
  if (ramp == 0.0) return {distance * tau / duration, distance / duration};
  const double t_ramp = ramp * duration, v = distance / ((1.0 - ramp) * duration), a = v / t_ramp;
  if (tau < t_ramp) return {0.5 * a * tau * tau, a * tau};
  const double left = duration - tau;
  if (left < t_ramp) return {distance - 0.5 * a * left * left, a * left};
  return {0.5 * v * t_ramp + v * (tau - t_ramp), v};
}

// A tone of amplitude a and angular rate w (value and rate at t): a sine; or, for the moving
// families, a back-and-forth between -a and a of the same period and phase, each half period one
// move (piecewise-linear: the triangle wave (2/π) a asin(sin wt), its rate one-sided at the kinks).
std::pair<double, double> tone(const PlateTrajectory& tr, double a, double w, double t) {
  if (a == 0.0 || w == 0.0) return {0.0, 0.0};
  if (tr.motion == PlateTrajectory::Motion::sinusoidal) return {a * std::sin(w * t), a * w * std::cos(w * t)};
  const double half = M_PI / std::abs(w), period = 2.0 * half;
  double m = std::fmod(t + 0.5 * half, period);  // the rising half spans t in [-half/2, half/2]
  if (m < 0.0) m += period;
  const double ramp = tr.motion == PlateTrajectory::Motion::trapezoidal ? tr.ramp_fraction : 0.0;
  const double sign = w > 0.0 ? 1.0 : -1.0;
  if (m < half) {
    const auto [s, v] = move(2.0 * a, half, ramp, m);
    return {sign * (s - a), sign * v};
  }
  const auto [s, v] = move(2.0 * a, half, ramp, m - half);
  return {sign * (a - s), -sign * v};
}

// The square path with stops: position and velocity in the plate plane, relative to the centre.
std::pair<Eigen::Vector2d, Eigen::Vector2d> square_path(double r, double w, double dwell, double ramp, double t) {
  const Eigen::Vector2d corner[4] = {{r, r}, {-r, r}, {-r, -r}, {r, -r}};
  const double side_s = 2.0 / std::abs(w);  // a side of 2r at the speed r|w| (piecewise-linear)
  const double leg = side_s + dwell, cycle = 4.0 * leg;
  double m = std::fmod(t, cycle);
  if (m < 0.0) m += cycle;
  const int i = std::min(3, static_cast<int>(m / leg));
  const double tau = m - i * leg;
  const Eigen::Vector2d a = corner[i], b = corner[(i + 1) % 4];
  if (tau >= side_s) return {b, Eigen::Vector2d::Zero()};
  const Eigen::Vector2d u = (b - a) / (2.0 * r);
  const auto [s, v] = move(2.0 * r, side_s, ramp, tau);
  return {a + u * s, u * v};
}

PlanarState planar(const PlateTrajectory& tr, double t) {
  PlanarState s;
  const auto m = tr.motion;
  const auto d1 = tone(tr, tr.depth_amplitude_m, tr.depth_rate_rad_per_s, t);
  const auto d2 = tone(tr, tr.depth_amplitude2_m, tr.depth_rate2_rad_per_s, t);
  const auto yaw = tone(tr, tr.yaw_amplitude_rad, tr.yaw_rate_rad_per_s, t);
  Eigen::Vector2d p, v;
  if (m == PlateTrajectory::Motion::sinusoidal) {
    const double w = tr.angular_rate_rad_per_s;
    p = {tr.radius_m * std::cos(w * t), tr.radius_m * std::sin(w * t)};
    v = {-tr.radius_m * w * std::sin(w * t), tr.radius_m * w * std::cos(w * t)};
  } else {
    const double ramp = m == PlateTrajectory::Motion::trapezoidal ? tr.ramp_fraction : 0.0;
    std::tie(p, v) = square_path(tr.radius_m, tr.angular_rate_rad_per_s, tr.dwell_s, ramp, t);
  }
  s.p_plate_m = {tr.centre_x_m + p.x(), tr.centre_y_m + p.y(), -(tr.depth_m + d1.first + d2.first)};
  s.v_plate_m_per_s = {v.x(), v.y(), -(d1.second + d2.second)};
  s.yaw_rad = tr.yaw_rad + yaw.first;
  s.yaw_rate_rad_per_s = yaw.second;
  return s;
}

BodyState to_world(const Plate& plate, const PlanarState& s) {
  const Eigen::Isometry3d T_wp = plate.T_world_plate();
  const Eigen::Matrix3d R_wp = T_wp.linear();
  BodyState b;
  b.T_world_body.linear() = R_wp * rot_z(s.yaw_rad);
  b.T_world_body.translation() = T_wp * s.p_plate_m;
  b.v_world_m_per_s = R_wp * s.v_plate_m_per_s;
  b.w_world_rad_per_s = R_wp * Vector3d(0.0, 0.0, s.yaw_rate_rad_per_s);
  return b;
}

// A zero-mean Gaussian from the engine by Box-Muller: std::normal_distribution's algorithm is
// implementation-defined, this is the same sequence on every standard library.
double gaussian(std::mt19937_64& rng) {
  constexpr double two_pi = 6.283185307179586;
  const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(two_pi * u2);
}

}  // namespace

Eigen::Isometry3d Plate::T_world_plate() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rot_z(yaw_rad) * Eigen::AngleAxisd(tilt_x_rad, Vector3d::UnitX()).toRotationMatrix() *
               Eigen::AngleAxisd(tilt_y_rad, Vector3d::UnitY()).toRotationMatrix();
  T.translation() = origin_world_m;
  return T;
}

namespace {

// plate_wrench without the law's check: simulate() checks the scenario once, not at every instant.
Vector6d wrench_unchecked(const Eigen::Isometry3d& T_wp, const Tripod& tripod, const ContactLaw& law, const BodyState& s,
                          std::vector<FootContact>* feet = nullptr) {
  const Vector3d n = T_wp.linear().col(2);
  const Vector3d o = T_wp.translation();
  Vector3d force_w = Vector3d::Zero(), moment_w = Vector3d::Zero();  // on the plate, about o_P
  if (feet) feet->assign(tripod.feet_body_m.size(), FootContact{});
  for (std::size_t i = 0; i < tripod.feet_body_m.size(); ++i) {
    FootContact c;
    c.point_world_m = s.T_world_body * tripod.feet_body_m[i];
    c.penetration_m = -n.dot(c.point_world_m - o);
    const Vector3d v = s.v_world_m_per_s + s.w_world_rad_per_s.cross(c.point_world_m - s.T_world_body.translation());
    c.penetration_rate_m_per_s = -n.dot(v);
    if (c.penetration_m > 0.0) {
      const double elastic = law.stiffness_n_per_m * law.delta_ref_m * std::pow(c.penetration_m / law.delta_ref_m, law.exponent);
      const double dashpot = law.damping_exponent == 0.0 ? 1.0 : std::pow(c.penetration_m / law.delta_ref_m, law.damping_exponent);
      c.normal_n = std::max(0.0, elastic + law.damping_n_s_per_m * dashpot * c.penetration_rate_m_per_s);
      c.in_contact = c.normal_n > 0.0;
      const double bound = law.friction_on_total_normal ? c.normal_n : (c.in_contact ? elastic : 0.0);
      const Vector3d u = v - n.dot(v) * n;
      const double eps = law.slip_regularisation_m_per_s;
      double mu = law.mu;
      if (law.stribeck_speed_m_per_s > 0.0)
        mu += (law.mu_rest - law.mu) * std::exp(-u.squaredNorm() / std::pow(law.stribeck_speed_m_per_s, 2));
      if (c.in_contact) c.friction_world_n = -mu * bound * u / std::sqrt(u.squaredNorm() + eps * eps) - law.viscous_n_s_per_m * u;
      // Newton's third law: the plate feels the opposite of what the foot feels.
      const Vector3d on_plate = -(c.normal_n * n + c.friction_world_n);
      force_w += on_plate;
      moment_w += (c.point_world_m - o).cross(on_plate);
    }
    if (feet) (*feet)[i] = c;
  }
  Vector6d w;
  w.head<3>() = T_wp.linear().transpose() * force_w;
  w.tail<3>() = T_wp.linear().transpose() * moment_w;
  return w;
}

}  // namespace

Vector6d plate_wrench(const Plate& plate, const Tripod& tripod, const ContactLaw& law, const BodyState& s, std::vector<FootContact>* feet) {
  throw_if(law_problems(law));
  return wrench_unchecked(plate.T_world_plate(), tripod, law, s, feet);
}

BodyState PlateTrajectory::at(const Plate& plate, double t_s) const { return to_world(plate, planar(*this, t_s)); }

BodyState true_state(const Scenario& sc, double t_s) {
  PlanarState s = planar(sc.trajectory, t_s);
  for (const auto& e : sc.slips)
    if (t_s >= e.t_s) {
      s.p_plate_m.x() += e.dx_m;
      s.p_plate_m.y() += e.dy_m;
      s.yaw_rad += e.dyaw_rad;
    }
  return to_world(sc.plate, s);
}

std::string validate(const Scenario& s) {
  std::ostringstream o;
  o << law_problems(s.law);
  if (s.tripod.feet_body_m.empty()) o << "tripod.feet_body_m must list at least one foot; ";
  for (std::size_t i = 0; i < s.tripod.feet_body_m.size(); ++i)
    if (!s.tripod.feet_body_m[i].allFinite()) o << "tripod.feet_body_m[" << i << "] is not finite; ";
  const auto& sen = s.sensor;
  if (!finite_positive(sen.rate_hz)) o << "sensor.rate_hz must be > 0 (got " << sen.rate_hz << "); ";
  if (sen.adc_subsamples < 1) o << "sensor.adc_subsamples must be >= 1 (got " << sen.adc_subsamples << "); ";
  if (!std::isfinite(sen.delay_s)) o << "sensor.delay_s is not finite; ";
  if (!(sen.filter_time_constant_s >= 0.0) || !std::isfinite(sen.filter_time_constant_s))
    o << "sensor.filter_time_constant_s must be finite and >= 0 (got " << sen.filter_time_constant_s << "); ";
  if (!(sen.gain.array() > -1.0).all() || !sen.gain.allFinite()) o << "sensor.gain must be finite and > -1 per component; ";
  if (!sen.bias.allFinite()) o << "sensor.bias is not finite; ";
  if (!sen.drift_per_s.allFinite()) o << "sensor.drift_per_s is not finite; ";
  if (!sen.cross_coupling.allFinite() || !sen.cross_coupling.diagonal().isZero(0.0))
    o << "sensor.cross_coupling must be finite with a zero diagonal (the gain is sensor.gain); ";
  if (!sen.noise_std.allFinite() || (sen.noise_std.array() < 0.0).any()) o << "sensor.noise_std must be finite and >= 0; ";
  if (!sen.resolution.allFinite() || (sen.resolution.array() < 0.0).any()) o << "sensor.resolution must be finite and >= 0; ";
  if (!finite_positive(s.duration_s)) o << "duration_s must be > 0 (got " << s.duration_s << "); ";
  else if (std::isfinite(sen.rate_hz) && s.duration_s * sen.rate_hz > 1e8) o << "duration_s * sensor.rate_hz exceeds 1e8 samples; ";
  const auto& tr = s.trajectory;
  for (double v : {tr.centre_x_m, tr.centre_y_m, tr.radius_m, tr.angular_rate_rad_per_s, tr.depth_m, tr.depth_amplitude_m,
                   tr.depth_rate_rad_per_s, tr.depth_amplitude2_m, tr.depth_rate2_rad_per_s, tr.yaw_rad, tr.yaw_amplitude_rad,
                   tr.yaw_rate_rad_per_s, tr.dwell_s, tr.ramp_fraction})
    if (!std::isfinite(v)) {
      o << "trajectory has a parameter that is not finite; ";
      break;
    }
  if (tr.motion == PlateTrajectory::Motion::piecewise_linear && (!(tr.angular_rate_rad_per_s != 0.0) || !(tr.dwell_s >= 0.0)))
    o << "trajectory: a piecewise-linear motion needs angular_rate_rad_per_s != 0 and dwell_s >= 0; ";
  if (tr.motion == PlateTrajectory::Motion::trapezoidal &&
      (!(tr.angular_rate_rad_per_s != 0.0) || !(tr.dwell_s >= 0.0) || !(tr.ramp_fraction > 0.0 && tr.ramp_fraction <= 0.5)))
    o << "trajectory: a trapezoidal motion needs angular_rate_rad_per_s != 0, dwell_s >= 0 and ramp_fraction in (0, 0.5] (got "
      << tr.ramp_fraction << "); ";
  if (!s.plate.origin_world_m.allFinite() || !std::isfinite(s.plate.yaw_rad) || !std::isfinite(s.plate.tilt_x_rad) ||
      !std::isfinite(s.plate.tilt_y_rad))
    o << "plate has a parameter that is not finite; ";
  for (std::size_t i = 0; i < s.slips.size(); ++i) {
    const auto& e = s.slips[i];
    if (!std::isfinite(e.t_s) || !std::isfinite(e.dx_m) || !std::isfinite(e.dy_m) || !std::isfinite(e.dyaw_rad))
      o << "slips[" << i << "] has a field that is not finite; ";
  }
  std::string r = o.str();
  return r.empty() ? r : r.substr(0, r.size() - 2);
}

FirstOrderLag::FirstOrderLag(double time_constant_s) : tau_s_(time_constant_s) {
  if (!(tau_s_ > 0.0) || !std::isfinite(tau_s_)) throw std::invalid_argument("FirstOrderLag: the time constant must be finite and > 0");
}

Vector6d FirstOrderLag::at(double t_s, const Vector6d& x) {
  if (!started_) {
    started_ = true;
    y_ = x;
  } else {
    const double h = t_s - t_s_;
    if (h < 0.0) throw std::invalid_argument("FirstOrderLag: time went back");
    if (h > 0.0) {
      // y(h) = e^-a y0 + ∫0^h e^-(h-s)/τ x(s) ds / τ for x linear from x0 to x1, a = h / τ.
      const double a = h / tau_s_, e = std::exp(-a);
      const double ramp = a < 1e-6 ? a / 2.0 : 1.0 - (1.0 - e) / a;  // (series: a/2 - a²/6 ...)
      y_ = e * y_ + (1.0 - e) * x_ + ramp * (x - x_);
    }
  }
  t_s_ = t_s;
  x_ = x;
  return y_;
}

std::vector<Sample> simulate(const Scenario& s) {
  if (const auto problems = validate(s); !problems.empty()) throw std::invalid_argument("contact_truth: " + problems);
  const auto& sen = s.sensor;
  const double period = 1.0 / sen.rate_hz;
  const auto n = static_cast<std::size_t>(std::floor(s.duration_s * sen.rate_hz + 1e-9));
  const Eigen::Isometry3d T_wp = s.plate.T_world_plate();
  std::mt19937_64 rng(sen.seed);
  // The filter's input at steps of at most a tenth of τ_f and 0.5 ms (the motion's kinks are
  // where a linear input between steps is wrong), from 10 τ_f before its first output, settled.
  const double tau_f = sen.filter_time_constant_s;
  const bool filter = tau_f > 0.0;
  std::optional<FirstOrderLag> lag;
  if (filter) lag.emplace(tau_f);
  double t_fed = 0.0;
  bool lag_started = false;
  auto filtered = [&](double t) {
    auto input = [&](double ti) { return wrench_unchecked(T_wp, s.tripod, s.law, true_state(s, ti)); };
    Vector6d y = Vector6d::Zero();
    if (!lag_started) {
      t_fed = t - 10.0 * tau_f;
      y = lag->at(t_fed, input(t_fed));
      lag_started = true;
    }
    const double h_max = std::min(0.1 * tau_f, 5e-4);
    const auto m = static_cast<int>(std::ceil((t - t_fed) / h_max - 1e-9));
    for (int i = 1; i <= m; ++i) {
      const double ti = i == m ? t : t_fed + (t - t_fed) * i / m;
      y = lag->at(ti, input(ti));
    }
    if (m < 1) y = lag->at(t, input(t));
    t_fed = t;
    return y;
  };
  std::vector<Sample> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    Sample& o = out[k];
    o.t_s = static_cast<double>(k) * period;
    o.reported = s.trajectory.at(s.plate, o.t_s);
    std::vector<FootContact> feet;
    o.wrench_true = wrench_unchecked(T_wp, s.tripod, s.law, true_state(s, o.t_s), &feet);
    for (const auto& f : feet) o.feet_in_contact += f.in_contact ? 1 : 0;
    // The ADC's average over the period that ends at t - τ (the wrench stream lags); through the
    // filter, its instants in time order.
    Vector6d mean = Vector6d::Zero();
    for (int i = 0; i < sen.adc_subsamples; ++i) {
      const int j = filter ? sen.adc_subsamples - 1 - i : i;
      const double t = o.t_s - sen.delay_s - period * static_cast<double>(j) / sen.adc_subsamples;
      mean += filter ? filtered(t) : wrench_unchecked(T_wp, s.tripod, s.law, true_state(s, t));
    }
    mean /= sen.adc_subsamples;
    const Vector6d coupled = mean + sen.cross_coupling * mean;
    Vector6d w = (Vector6d::Ones() + sen.gain).cwiseProduct(coupled) + sen.bias + sen.drift_per_s * o.t_s;
    for (int c = 0; c < 6; ++c) {
      if (sen.noise_std(c) > 0.0) w(c) += sen.noise_std(c) * gaussian(rng);
      if (sen.resolution(c) > 0.0) w(c) = sen.resolution(c) * std::round(w(c) / sen.resolution(c));
    }
    o.wrench_measured = w;
  }
  return out;
}

}  // namespace hil::contact_truth
