// The independent contact truth (issue 12) against closed-form physics: every expected value below
// is worked out by hand from the law in tripod.hpp, not computed by the module.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

#include <hil/contact_truth/tripod.hpp>

namespace hil::contact_truth {
namespace {

using Eigen::Vector3d;

// A tripod standing still, its body origin at (x0, y0) in the plate plane pressed to depth d.
BodyState pressed(const Plate& plate, double x0, double y0, double d, double yaw = 0.0) {
  PlateTrajectory tr;
  tr.centre_x_m = x0;
  tr.centre_y_m = y0;
  tr.radius_m = 0.0;
  tr.depth_m = d;
  tr.depth_amplitude_m = 0.0;
  tr.yaw_rad = yaw;
  tr.yaw_amplitude_rad = 0.0;
  return tr.at(plate, 0.0);
}

// The default law with Coulomb coefficient mu, regularised below eps (m/s).
ContactLaw coulomb(double mu, double eps_m_per_s) {
  ContactLaw l;
  l.mu = mu;
  l.slip_regularisation_m_per_s = eps_m_per_s;
  return l;
}

// A stand of one foot at the body origin: the law of one contact, without lever arms.
Tripod one_foot() {
  Tripod t;
  t.feet_body_m = {Vector3d::Zero()};
  return t;
}

TEST(TripodLaw, StandingStillOnALevelPlateCarriesThreeTimesKDelta) {
  const Plate plate;
  Tripod tri;
  ContactLaw law;
  law.stiffness_n_per_m = 2e5;
  const double d = 1e-4;
  std::vector<FootContact> feet;
  const Vector6d w = plate_wrench(plate, tri, law, pressed(plate, 0.0, 0.0, d), &feet);
  // Each foot carries K d upwards; the plate feels 3 K d downwards.
  EXPECT_NEAR(w(2), -3.0 * 2e5 * d, 1e-9);
  EXPECT_NEAR(w(0), 0.0, 1e-12);
  EXPECT_NEAR(w(1), 0.0, 1e-12);
  // The default feet are symmetric about the body origin at the plate origin: no moment.
  EXPECT_NEAR(w.tail<3>().norm(), 0.0, 1e-9);
  for (const auto& f : feet) {
    EXPECT_TRUE(f.in_contact);
    EXPECT_NEAR(f.penetration_m, d, 1e-15);
    EXPECT_NEAR(f.normal_n, 2e5 * d, 1e-9);
  }
}

TEST(TripodLaw, AnOffCentreStandMakesTheLeverArmMoment) {
  const Plate plate;
  const Tripod tri;
  const ContactLaw law;
  const double x0 = 0.1, y0 = -0.04, d = 2e-4;
  const Vector6d w = plate_wrench(plate, tri, law, pressed(plate, x0, y0, d));
  const double fz = -3.0 * law.stiffness_n_per_m * d;
  EXPECT_NEAR(w(2), fz, 1e-9);
  // m = r x f with f = (0, 0, fz) at the feet's centroid (x0, y0, 0): (y0 fz, -x0 fz, 0).
  EXPECT_NEAR(w(3), y0 * fz, 1e-9);
  EXPECT_NEAR(w(4), -x0 * fz, 1e-9);
  EXPECT_NEAR(w(5), 0.0, 1e-9);
}

TEST(TripodLaw, TheWrenchInPlateFrameDoesNotDependOnHowThePlateLies) {
  Plate level;
  Plate yawed;
  yawed.yaw_rad = 0.7;
  yawed.tilt_x_rad = 0.02;
  yawed.tilt_y_rad = -0.03;
  yawed.origin_world_m = {0.3, -0.2, 0.05};
  const Tripod tri;
  const ContactLaw law;
  PlateTrajectory tr;  // moving: friction, a yaw rate and a changing depth
  for (double t : {0.3, 1.7, 4.2}) {
    const Vector6d a = plate_wrench(level, tri, law, tr.at(level, t));
    const Vector6d b = plate_wrench(yawed, tri, law, tr.at(yawed, t));
    EXPECT_LT((a - b).norm(), 1e-9 * (1.0 + a.norm())) << "t = " << t;
  }
}

TEST(TripodLaw, FastSlidingFrictionIsMuTimesTheNormalForceAgainstTheMotion) {
  const Plate plate;
  const Tripod tri = one_foot();
  const ContactLaw law = coulomb(0.4, 1e-6);
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);
  s.v_world_m_per_s = {0.03, -0.04, 0.0};  // 5 cm/s, far above ε
  const Vector6d w = plate_wrench(plate, tri, law, s);
  const double N = law.stiffness_n_per_m * 1e-4;
  // The foot is pushed against its motion; the plate is dragged along it.
  EXPECT_NEAR(w(0), 0.4 * N * 0.6, 1e-6 * N);
  EXPECT_NEAR(w(1), 0.4 * N * -0.8, 1e-6 * N);
  EXPECT_NEAR(w(2), -N, 1e-9);
}

TEST(TripodLaw, SlowSlidingFrictionIsRegularisedLinearInSpeed) {
  const Plate plate;
  const Tripod tri = one_foot();
  const ContactLaw law = coulomb(0.5, 1e-3);
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);
  const double N = law.stiffness_n_per_m * 1e-4;
  for (double v : {1e-6, 2e-6}) {
    s.v_world_m_per_s = {v, 0.0, 0.0};
    // μ N v / sqrt(v² + ε²) ≈ μ N v / ε for v << ε.
    EXPECT_NEAR(plate_wrench(plate, tri, law, s)(0), 0.5 * N * v / 1e-3, 1e-5 * 0.5 * N * v / 1e-3);
  }
}

TEST(TripodLaw, StribeckFrictionFallsFromItsRestValueWithTheSlidingSpeed) {
  const Plate plate;
  const Tripod tri = one_foot();
  ContactLaw law = coulomb(0.25, 1e-7);
  law.mu_rest = 0.40;
  law.stribeck_speed_m_per_s = 2e-3;
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);
  const double N = law.stiffness_n_per_m * 1e-4;
  // μ(v) = 0.25 + 0.15 exp(-(v / 2 mm/s)²), worked out by hand at v = 0.1, 2 and 10 mm/s.
  const std::vector<std::pair<double, double>> mu_at{{1e-4, 0.25 + 0.15 * std::exp(-0.0025)},
                                                     {2e-3, 0.25 + 0.15 * std::exp(-1.0)},
                                                     {1e-2, 0.25 + 0.15 * std::exp(-25.0)}};
  for (const auto& [v, mu] : mu_at) {
    s.v_world_m_per_s = {0.0, v, 0.0};
    EXPECT_NEAR(plate_wrench(plate, tri, law, s)(1), mu * N, 1e-6 * N) << "v = " << v;
  }
  // Without a speed the rest value is not used.
  law.stribeck_speed_m_per_s = 0.0;
  s.v_world_m_per_s = {0.0, 1e-4, 0.0};
  EXPECT_NEAR(plate_wrench(plate, tri, law, s)(1), 0.25 * N, 1e-6 * N);
}

TEST(TripodLaw, DampingAddsToTheNormalForceAndFrictionFollowsTheChosenBound) {
  const Plate plate;
  const Tripod tri = one_foot();
  ContactLaw law = coulomb(0.3, 1e-7);
  law.damping_n_s_per_m = 3000.0;
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);
  s.v_world_m_per_s = {0.01, 0.0, -2e-3};  // sliding along x and pressing in at 2 mm/s
  const double elastic = law.stiffness_n_per_m * 1e-4;
  const double total = elastic + 3000.0 * 2e-3;
  std::vector<FootContact> feet;
  Vector6d w = plate_wrench(plate, tri, law, s, &feet);
  EXPECT_NEAR(feet[0].penetration_rate_m_per_s, 2e-3, 1e-15);
  EXPECT_NEAR(w(2), -total, 1e-9);
  EXPECT_NEAR(w(0), 0.3 * total, 1e-6 * total);
  law.friction_on_total_normal = false;
  w = plate_wrench(plate, tri, law, s);
  EXPECT_NEAR(w(2), -total, 1e-9);
  EXPECT_NEAR(w(0), 0.3 * elastic, 1e-6 * total);
  // Pulling out faster than the spring pushes: no tension, no contact.
  s.v_world_m_per_s = {0.0, 0.0, 1.0};
  w = plate_wrench(plate, tri, law, s, &feet);
  EXPECT_FALSE(feet[0].in_contact);
  EXPECT_EQ(w.norm(), 0.0);
}

TEST(TripodLaw, HuntCrossleyDampingGrowsWithThePenetration) {
  const Plate plate;
  const Tripod tri = one_foot();
  ContactLaw law = coulomb(0.3, 1e-7);
  law.damping_n_s_per_m = 3000.0;
  law.damping_exponent = 1.0;
  law.delta_ref_m = 2e-4;
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);  // half of δ_ref
  s.v_world_m_per_s = {0.0, 0.0, -2e-3};
  const double elastic = law.stiffness_n_per_m * 1e-4;
  EXPECT_NEAR(plate_wrench(plate, tri, law, s)(2), -(elastic + 0.5 * 3000.0 * 2e-3), 1e-9);
  // Deeper, the same rate: twice the dashpot's force per unit rate at twice the depth.
  s = pressed(plate, 0.0, 0.0, 4e-4);
  s.v_world_m_per_s = {0.0, 0.0, -2e-3};
  EXPECT_NEAR(plate_wrench(plate, tri, law, s)(2), -(law.stiffness_n_per_m * 4e-4 + 2.0 * 3000.0 * 2e-3), 1e-9);
  // q = 1.5: (δ/δ_ref)^1.5.
  law.damping_exponent = 1.5;
  EXPECT_NEAR(plate_wrench(plate, tri, law, s)(2), -(law.stiffness_n_per_m * 4e-4 + std::pow(2.0, 1.5) * 3000.0 * 2e-3), 1e-9);
}

TEST(TripodLaw, ViscousFrictionAndThePowerLaw) {
  const Plate plate;
  const Tripod tri = one_foot();
  ContactLaw law = coulomb(0.0, 1e-4);
  law.viscous_n_s_per_m = 5000.0;
  law.exponent = 1.5;
  law.delta_ref_m = 1e-4;
  BodyState s = pressed(plate, 0.0, 0.0, 4e-4);
  s.v_world_m_per_s = {0.0, 0.002, 0.0};
  const Vector6d w = plate_wrench(plate, tri, law, s);
  EXPECT_NEAR(w(1), 5000.0 * 0.002, 1e-9);
  EXPECT_NEAR(w(2), -law.stiffness_n_per_m * 1e-4 * 8.0, 1e-6);  // (4e-4 / 1e-4)^1.5 = 8
}

TEST(TripodLaw, FeetAboveThePlateCarryNothing) {
  const Plate plate;
  const Tripod tri;
  const ContactLaw law;
  std::vector<FootContact> feet;
  const Vector6d w = plate_wrench(plate, tri, law, pressed(plate, 0.0, 0.0, -1e-3), &feet);
  EXPECT_EQ(w.norm(), 0.0);
  for (const auto& f : feet) EXPECT_FALSE(f.in_contact);
}

TEST(TripodLaw, AYawRateMakesATwistingFrictionMoment) {
  const Plate plate;
  const Tripod tri;  // three feet at 5 cm from the origin
  ContactLaw law;
  law.slip_regularisation_m_per_s = 1e-8;
  BodyState s = pressed(plate, 0.0, 0.0, 1e-4);
  s.w_world_rad_per_s = {0.0, 0.0, 0.2};  // each foot slides at 1 cm/s tangentially
  const Vector6d w = plate_wrench(plate, tri, law, s);
  const double N = law.stiffness_n_per_m * 1e-4;
  // Each foot drags the plate along its motion with μ N at 5 cm: mz = 3 μ N r (counter-clockwise).
  EXPECT_NEAR(w(5), 3.0 * law.mu * N * 0.05, 1e-6);
  EXPECT_NEAR(w.head<2>().norm(), 0.0, 1e-6);
}

TEST(Trajectory, VelocitiesAreTheDerivativesOfThePoses) {
  Plate plate;
  plate.yaw_rad = 0.4;
  plate.tilt_x_rad = 0.01;
  const PlateTrajectory tr;
  const double h = 1e-6;
  for (double t : {0.0, 1.1, 7.3}) {
    const BodyState a = tr.at(plate, t - h), b = tr.at(plate, t + h), s = tr.at(plate, t);
    const Vector3d v = (b.T_world_body.translation() - a.T_world_body.translation()) / (2 * h);
    EXPECT_LT((v - s.v_world_m_per_s).norm(), 1e-8);
    const Eigen::AngleAxisd d(b.T_world_body.linear() * a.T_world_body.linear().transpose());
    EXPECT_LT((d.angle() * d.axis() / (2 * h) - s.w_world_rad_per_s).norm(), 1e-6);
  }
}

TEST(Trajectory, PiecewiseLinearMotionHasConstantRatesBetweenKinksAndStopsAtTheCorners) {
  Plate plate;
  plate.yaw_rad = 0.4;
  plate.tilt_x_rad = 0.01;
  PlateTrajectory tr;
  tr.motion = PlateTrajectory::Motion::piecewise_linear;
  tr.centre_x_m = 0.001;
  tr.radius_m = 4e-3;
  tr.angular_rate_rad_per_s = 2.0;  // 8 mm/s along a side of 8 mm: 1 s per side
  tr.dwell_s = 0.25;
  tr.depth_m = 1e-4;
  tr.depth_amplitude_m = 4e-5;
  tr.depth_rate_rad_per_s = M_PI;  // a triangle of period 2 s: 4e-5 m per 0.5 s = 8e-5 m/s
  tr.depth_amplitude2_m = 1e-5;
  tr.depth_rate2_rad_per_s = 2 * M_PI;  // period 1 s: 1e-5 m per 0.25 s = 4e-5 m/s
  tr.yaw_amplitude_rad = 0.02;
  tr.yaw_rate_rad_per_s = M_PI / 2;  // period 4 s: 0.02 rad per s
  const Eigen::Matrix3d R = plate.T_world_plate().linear();
  auto in_plate = [&](const Vector3d& v_world) -> Vector3d { return R.transpose() * v_world; };
  // t = 0.1: first side, from (r, r) towards (-r, r) at 8 mm/s; both tones rising.
  Vector3d v = in_plate(tr.at(plate, 0.1).v_world_m_per_s);
  EXPECT_NEAR(v.x(), -8e-3, 1e-12);
  EXPECT_NEAR(v.y(), 0.0, 1e-12);
  EXPECT_NEAR(v.z(), -(8e-5 + 4e-5), 1e-12);
  EXPECT_NEAR((R.transpose() * tr.at(plate, 0.1).w_world_rad_per_s).z(), 0.02, 1e-12);
  // t = 1.1: stopped at (-r, r) in the plane; the slow tone falling (0.5-1.5 s), the fast one
  // rising (0.75-1.25 s): the depth falls at 4e-5 m/s, the body rises.
  const BodyState stop = tr.at(plate, 1.1);
  v = in_plate(stop.v_world_m_per_s);
  EXPECT_NEAR(v.head<2>().norm(), 0.0, 1e-15);
  EXPECT_NEAR(v.z(), -(-8e-5 + 4e-5), 1e-12);
  const Vector3d p = R.transpose() * (stop.T_world_body.translation() - plate.origin_world_m);
  EXPECT_NEAR(p.x(), 0.001 - 4e-3, 1e-12);
  EXPECT_NEAR(p.y(), 4e-3, 1e-12);
  // t = 1.3: second side, towards (-r, -r).
  v = in_plate(tr.at(plate, 1.3).v_world_m_per_s);
  EXPECT_NEAR(v.y(), -8e-3, 1e-12);
  // Between kinks the velocities are the derivatives of the poses.
  const double h = 1e-6;
  for (double t : {0.3, 1.6, 3.7, 6.05}) {
    const BodyState a = tr.at(plate, t - h), b = tr.at(plate, t + h), s = tr.at(plate, t);
    EXPECT_LT(((b.T_world_body.translation() - a.T_world_body.translation()) / (2 * h) - s.v_world_m_per_s).norm(), 1e-8) << t;
    const Eigen::AngleAxisd d(b.T_world_body.linear() * a.T_world_body.linear().transpose());
    EXPECT_LT((d.angle() * d.axis() / (2 * h) - s.w_world_rad_per_s).norm(), 1e-6) << t;
  }
  // The depth's extremes: d1 tri(πt) + d2 tri(2πt) peaks at t = 0.5 + 2j (4e-5 + 0) and is
  // lowest at t = 1.5 + 2j (-4e-5 + 0); at the fast tone's peaks the slow one is at ±1/2 (3e-5).
  double lo = 1.0, hi = -1.0;
  for (double t = 0.0; t < 8.0; t += 0.01) {
    const double z = (R.transpose() * (tr.at(plate, t).T_world_body.translation() - plate.origin_world_m)).z();
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  EXPECT_NEAR(lo, -1.4e-4, 1e-12);
  EXPECT_NEAR(hi, -0.6e-4, 1e-12);
}

// The trapezoidal family: the same moves in the same time as the piecewise-linear family, with a
// speed that ramps instead of stepping. Expected values from the profile's own arithmetic.
TEST(Trajectory, TrapezoidalMotionRampsItsSpeedAndKeepsEachMovesDuration) {
  Plate plate;
  plate.yaw_rad = -0.3;
  plate.tilt_y_rad = 0.02;
  PlateTrajectory tr;
  tr.motion = PlateTrajectory::Motion::trapezoidal;
  tr.ramp_fraction = 0.2;
  tr.radius_m = 4e-3;
  tr.angular_rate_rad_per_s = 2.0;  // a side of 8 mm in 1 s: cruise 8 / 0.8 = 10 mm/s, 0.2 s ramps
  tr.dwell_s = 0.25;
  tr.depth_m = 1e-4;
  tr.depth_amplitude_m = 4e-5;
  tr.depth_rate_rad_per_s = M_PI;  // half period 1 s from -4e-5 to 4e-5: cruise 1e-4 m/s
  tr.depth_amplitude2_m = 0.0;
  tr.yaw_amplitude_rad = 0.02;
  tr.yaw_rate_rad_per_s = -M_PI / 2;  // a negative rate: the yaw falls first
  const Eigen::Matrix3d R = plate.T_world_plate().linear();
  auto p_plate = [&](double t) -> Vector3d { return R.transpose() * (tr.at(plate, t).T_world_body.translation() - plate.origin_world_m); };
  auto v_plate = [&](double t) -> Vector3d { return R.transpose() * tr.at(plate, t).v_world_m_per_s; };
  auto yaw_rate = [&](double t) { return (R.transpose() * tr.at(plate, t).w_world_rad_per_s).z(); };
  // Mid-side and mid-ramp speeds; the corner reached at the end of the side and held at the stop.
  EXPECT_NEAR(v_plate(0.5).x(), -1e-2, 1e-12);
  EXPECT_NEAR(v_plate(0.1).x(), -0.5e-2, 1e-12);                   // half the ramp: half the cruise speed
  EXPECT_NEAR(p_plate(0.1).x(), 4e-3 - 0.5 * 0.05 * 0.01, 1e-12);  // ½ a t², a = 0.01 / 0.2 = 0.05 m/s²
  EXPECT_NEAR(p_plate(1.0).x(), -4e-3, 1e-12);
  EXPECT_NEAR(v_plate(1.1).head<2>().norm(), 0.0, 1e-15);
  EXPECT_NEAR(p_plate(1.1).y(), 4e-3, 1e-12);
  EXPECT_NEAR(v_plate(1.75).y(), -1e-2, 1e-12);  // second side: starts at 1.25 s
  // The depth: rising through its mean at t = 0 at the cruise speed (the body sinks: z falls),
  // at its extremes at t = ±0.5 s with zero rate, as the triangle wave of the same period.
  EXPECT_NEAR(p_plate(0.0).z(), -1e-4, 1e-15);
  EXPECT_NEAR(v_plate(0.0).z(), -1e-4, 1e-12);
  EXPECT_NEAR(p_plate(0.5).z(), -1.4e-4, 1e-15);
  EXPECT_NEAR(v_plate(0.5).z(), 0.0, 1e-15);
  EXPECT_NEAR(p_plate(1.5).z(), -0.6e-4, 1e-15);
  // The yaw (ω_ψ < 0): falls first, at 0.02 / (0.8 · 2 s) · 2 = 0.025 rad/s cruising.
  EXPECT_NEAR(yaw_rate(0.0), -0.025, 1e-12);
  // No kinks: the rates are continuous everywhere (one 10 µs step apart, at most the largest
  // acceleration, 0.05 m/s² in the plane, times the step), and they are the poses' derivatives.
  const double h = 1e-6;
  for (double t = -3.0; t < 9.0; t += 0.01037) {
    EXPECT_LT((v_plate(t + 1e-5) - v_plate(t)).norm(), 0.06 * 1e-5) << t;
    EXPECT_LT(std::abs(yaw_rate(t + 1e-5) - yaw_rate(t)), 0.2 * 1e-5) << t;
    const BodyState a = tr.at(plate, t - h), b = tr.at(plate, t + h), s = tr.at(plate, t);
    EXPECT_LT(((b.T_world_body.translation() - a.T_world_body.translation()) / (2 * h) - s.v_world_m_per_s).norm(), 1e-8) << t;
    const Eigen::AngleAxisd d(b.T_world_body.linear() * a.T_world_body.linear().transpose());
    EXPECT_LT((d.angle() * d.axis() / (2 * h) - s.w_world_rad_per_s).norm(), 1e-6) << t;
  }
  // The same trajectory as piecewise-linear reaches the same corners and extremes at the same times.
  PlateTrajectory pl = tr;
  pl.motion = PlateTrajectory::Motion::piecewise_linear;
  auto p_linear = [&](double t) -> Vector3d { return R.transpose() * (pl.at(plate, t).T_world_body.translation() - plate.origin_world_m); };
  for (double t : {1.0, 1.1, 2.25, 3.5, 4.75}) EXPECT_LT((p_plate(t) - p_linear(t)).head<2>().norm(), 1e-12) << t;  // corners
  for (double t : {0.5, 1.5, 2.5, -0.5}) EXPECT_NEAR(p_plate(t).z(), p_linear(t).z(), 1e-15) << t;                  // extremes
}

Scenario quiet_scenario() {
  Scenario sc;
  sc.duration_s = 5.0;
  sc.sensor.rate_hz = 100.0;
  sc.sensor.adc_subsamples = 1;
  return sc;
}

TEST(SensorChain, WithoutErrorsItReportsTheTrueWrench) {
  const Scenario sc = quiet_scenario();
  const auto samples = simulate(sc);
  ASSERT_EQ(samples.size(), 500u);
  for (const auto& s : samples) {
    EXPECT_EQ(s.wrench_measured, s.wrench_true);
    EXPECT_EQ(s.feet_in_contact, 3);
  }
  EXPECT_DOUBLE_EQ(samples[123].t_s, 1.23);
}

TEST(SensorChain, TheAdcAveragesOverThePeriodThatEndsAtTheSample) {
  Scenario sc = quiet_scenario();
  sc.sensor.adc_subsamples = 4;
  const auto samples = simulate(sc);
  const double T = 1.0 / sc.sensor.rate_hz;
  for (std::size_t k : {std::size_t{10}, std::size_t{250}}) {
    Vector6d mean = Vector6d::Zero();
    for (int j = 0; j < 4; ++j) mean += plate_wrench(sc.plate, sc.tripod, sc.law, true_state(sc, samples[k].t_s - T * j / 4.0));
    EXPECT_LT((samples[k].wrench_measured - mean / 4.0).norm(), 1e-9);
  }
}

TEST(SensorChain, ADelayShowsTheWrenchOfAnEarlierInstant) {
  Scenario sc = quiet_scenario();
  sc.sensor.delay_s = 0.03;  // three samples
  const auto late = simulate(sc);
  sc.sensor.delay_s = 0.0;
  const auto now = simulate(sc);
  for (std::size_t k = 3; k < now.size(); ++k) EXPECT_LT((late[k].wrench_measured - now[k - 3].wrench_measured).norm(), 1e-9);
  // The poses are not delayed.
  EXPECT_TRUE(late[100].reported.T_world_body.isApprox(now[100].reported.T_world_body));
}

// The filter against its closed forms: a ramp's response lags it by exactly τ_f once settled,
// a sinusoid's has the gain 1 / sqrt(1 + (ω τ_f)²) and the phase lag atan(ω τ_f).
TEST(SensorChain, AFirstOrderLagFollowsItsClosedForms) {
  const double tau = 0.012;
  FirstOrderLag ramp(tau);
  Vector6d y = Vector6d::Zero();
  for (int i = 0; i <= 20000; ++i) {  // 2 s at 0.1 ms; x = 3 t on every component
    const double t = 1e-4 * i;
    y = ramp.at(t, Vector6d::Constant(3.0 * t));
  }
  EXPECT_NEAR(y(0), 3.0 * (2.0 - tau), 1e-9);  // exact for a linear input: e^(-2/τ) of transient left
  // Coarse steps are exact for a linear input too (first-order hold).
  FirstOrderLag coarse(tau);
  for (int i = 0; i <= 40; ++i) y = coarse.at(0.05 * i, Vector6d::Constant(3.0 * 0.05 * i));
  EXPECT_NEAR(y(5), 3.0 * (2.0 - tau), 1e-9);

  const double w = 2.0 * M_PI * 2.3;
  FirstOrderLag sine(tau);
  double peak = 0.0, t_peak = 0.0;
  for (int i = 0; i <= 40000; ++i) {  // 4 s at 0.1 ms, the peak searched in the last period
    const double t = 1e-4 * i;
    const double out = sine.at(t, Vector6d::Constant(std::sin(w * t)))(2);
    if (t > 4.0 - 2.0 * M_PI / w && out > peak) {
      peak = out;
      t_peak = t;
    }
  }
  EXPECT_NEAR(peak, 1.0 / std::sqrt(1.0 + w * w * tau * tau), 1e-6);
  // sin(w t - φ) peaks where w t - φ = π/2 (mod 2π): φ from the peak's time, on a 0.1 ms grid.
  const double phase = std::remainder(w * t_peak - M_PI / 2.0, 2.0 * M_PI);
  EXPECT_NEAR(phase, std::atan(w * tau), w * 1e-4);
  EXPECT_THROW(FirstOrderLag(0.0), std::invalid_argument);
  FirstOrderLag back(tau);
  back.at(1.0, Vector6d::Zero());
  EXPECT_THROW(back.at(0.5, Vector6d::Zero()), std::invalid_argument);
}

// In the sensor chain: the filtered stream is the filter of the true wrench, sample by sample
// (fed here at 0.05 ms, a tenth of the chain's own step), before the delay and the ADC.
TEST(SensorChain, AFilterActsOnTheTrueWrenchBeforeTheAdc) {
  Scenario sc = quiet_scenario();
  sc.sensor.filter_time_constant_s = 0.008;
  sc.sensor.delay_s = 0.004;
  const auto samples = simulate(sc);
  FirstOrderLag lag(0.008);
  double t = -0.004 - 0.08;
  lag.at(t, plate_wrench(sc.plate, sc.tripod, sc.law, true_state(sc, t)));
  double worst = 0.0, scale = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double until = samples[k].t_s - 0.004;
    Vector6d y = Vector6d::Zero();
    for (; t < until - 1e-12;) {
      t = std::min(until, t + 5e-5);
      y = lag.at(t, plate_wrench(sc.plate, sc.tripod, sc.law, true_state(sc, t)));
    }
    worst = std::max(worst, (samples[k].wrench_measured - y).norm());
    scale = std::max(scale, (samples[k].wrench_measured - samples[k].wrench_true).norm());
  }
  EXPECT_LT(worst, 1e-3 * scale) << "the chain's filter against one fed ten times finer; the filter's effect " << scale;
  EXPECT_GT(scale, 0.0);
}

TEST(SensorChain, GainBiasDriftThenQuantisation) {
  Scenario sc = quiet_scenario();
  sc.sensor.gain << 0.1, 0, -0.05, 0, 0, 0;
  sc.sensor.bias << 2.0, 0, 0, 0, 0.3, 0;
  sc.sensor.drift_per_s << 0, 0.5, 0, 0, 0, 0;
  sc.sensor.resolution << 0.25, 0.25, 0.25, 0.01, 0.01, 0.01;
  const auto samples = simulate(sc);
  for (std::size_t k : {std::size_t{0}, std::size_t{200}, std::size_t{499}}) {
    const auto& s = samples[k];
    Vector6d expected = s.wrench_true;
    expected(0) = 1.1 * expected(0) + 2.0;
    expected(1) = expected(1) + 0.5 * s.t_s;
    expected(2) = 0.95 * expected(2);
    expected(4) += 0.3;
    for (int c = 0; c < 6; ++c) {
      const double step = sc.sensor.resolution(c);
      EXPECT_NEAR(s.wrench_measured(c), expected(c), step / 2 + 1e-12) << "component " << c;
      EXPECT_NEAR(s.wrench_measured(c) / step, std::round(s.wrench_measured(c) / step), 1e-9);
    }
  }
}

TEST(SensorChain, CrossCouplingLeaksOneTrueComponentIntoAnotherBeforeTheGain) {
  Scenario sc = quiet_scenario();
  sc.trajectory.radius_m = 5e-3;  // sliding: fx and fy are non-zero
  sc.sensor.cross_coupling(1, 0) = 0.04;
  sc.sensor.cross_coupling(5, 2) = -0.002;
  sc.sensor.gain(1) = 0.1;
  const auto samples = simulate(sc);
  for (std::size_t k : {std::size_t{37}, std::size_t{311}}) {
    const Vector6d t = samples[k].wrench_true, m = samples[k].wrench_measured;
    ASSERT_GT(std::abs(t(0)), 1e-3);
    EXPECT_NEAR(m(1), 1.1 * (t(1) + 0.04 * t(0)), 1e-9);
    EXPECT_NEAR(m(5), t(5) - 0.002 * t(2), 1e-9);
    EXPECT_NEAR(m(0), t(0), 1e-12);
  }
}

TEST(SensorChain, NoiseHasItsStatedStdAndTheSeedReproducesIt) {
  Scenario sc = quiet_scenario();
  sc.duration_s = 100.0;  // 10,000 samples
  sc.sensor.noise_std << 0.5, 0, 0, 0, 0, 0.02;
  const auto a = simulate(sc);
  std::vector<double> e0, e5;
  for (const auto& s : a) {
    e0.push_back(s.wrench_measured(0) - s.wrench_true(0));
    e5.push_back(s.wrench_measured(5) - s.wrench_true(5));
    EXPECT_EQ(s.wrench_measured(1), s.wrench_true(1));
  }
  auto stats = [](const std::vector<double>& v) {
    const double m = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
    double q = 0.0;
    for (double x : v) q += (x - m) * (x - m);
    return std::pair{m, std::sqrt(q / static_cast<double>(v.size() - 1))};
  };
  const auto [m0, s0] = stats(e0);
  const auto [m5, s5] = stats(e5);
  // 10,000 draws: the sample std is within 3 % of the truth and the mean within 4 std / 100.
  EXPECT_NEAR(s0, 0.5, 0.015);
  EXPECT_NEAR(s5, 0.02, 0.0006);
  EXPECT_NEAR(m0, 0.0, 4 * 0.5 / 100);
  EXPECT_NEAR(m5, 0.0, 4 * 0.02 / 100);
  const auto b = simulate(sc);
  EXPECT_EQ(a[777].wrench_measured, b[777].wrench_measured);
  sc.sensor.seed = 2;
  const auto c = simulate(sc);
  EXPECT_NE(a[777].wrench_measured(0), c[777].wrench_measured(0));
}

TEST(Slip, TheTrueTripodMovesWhileTheReportedPoseDoesNot) {
  Scenario sc = quiet_scenario();
  sc.trajectory.radius_m = 0.0;
  sc.trajectory.yaw_amplitude_rad = 0.0;
  sc.trajectory.depth_amplitude_m = 0.0;
  sc.slips.push_back({2.0, 0.01, -0.02, 0.1});
  const auto samples = simulate(sc);
  const auto& before = samples[150];
  const auto& after = samples[300];
  EXPECT_TRUE(before.reported.T_world_body.isApprox(after.reported.T_world_body));
  const BodyState t = true_state(sc, 3.0);
  EXPECT_LT((t.T_world_body.translation() - after.reported.T_world_body.translation() - Vector3d(0.01, -0.02, 0.0)).norm(), 1e-12);
  // Standing still, the moment about the plate origin follows the moved feet: m = (y fz, -x fz).
  const double fz = after.wrench_true(2);
  EXPECT_NEAR(after.wrench_true(3), -0.02 * fz, 1e-9);
  EXPECT_NEAR(after.wrench_true(4), -0.01 * fz, 1e-9);
  EXPECT_NEAR(before.wrench_true.tail<3>().norm(), 0.0, 1e-9);
}

TEST(BadInput, EveryProblemIsNamed) {
  Scenario sc;
  sc.law.stiffness_n_per_m = -1.0;
  sc.law.mu = -0.1;
  sc.sensor.adc_subsamples = 0;
  sc.sensor.rate_hz = std::nan("");
  sc.sensor.gain(3) = -1.5;
  sc.slips.push_back({std::numeric_limits<double>::infinity(), 0, 0, 0});
  const std::string v = validate(sc);
  for (const char* field : {"law.stiffness_n_per_m", "law.mu", "sensor.adc_subsamples", "sensor.rate_hz", "sensor.gain", "slips[0]"})
    EXPECT_NE(v.find(field), std::string::npos) << field << " not in: " << v;
  try {
    simulate(sc);
    FAIL() << "simulate accepted a scenario that is not physical";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("law.stiffness_n_per_m must be > 0 (got -1)"), std::string::npos) << e.what();
  }
  // Each field alone: the message names it.
  const std::vector<std::pair<std::string, std::function<void(Scenario&)>>> one_each{
      {"law.exponent", [](Scenario& x) { x.law.exponent = 0.0; }},
      {"law.delta_ref_m", [](Scenario& x) { x.law.delta_ref_m = -1e-4; }},
      {"law.damping_n_s_per_m", [](Scenario& x) { x.law.damping_n_s_per_m = -1.0; }},
      {"law.damping_exponent", [](Scenario& x) { x.law.damping_exponent = -0.5; }},
      {"law.viscous_n_s_per_m", [](Scenario& x) { x.law.viscous_n_s_per_m = std::nan(""); }},
      {"tripod.feet_body_m must list", [](Scenario& x) { x.tripod.feet_body_m.clear(); }},
      {"tripod.feet_body_m[1]", [](Scenario& x) { x.tripod.feet_body_m[1].x() = std::nan(""); }},
      {"sensor.delay_s", [](Scenario& x) { x.sensor.delay_s = std::numeric_limits<double>::infinity(); }},
      {"sensor.filter_time_constant_s", [](Scenario& x) { x.sensor.filter_time_constant_s = -0.01; }},
      {"sensor.bias", [](Scenario& x) { x.sensor.bias(0) = std::nan(""); }},
      {"sensor.drift_per_s", [](Scenario& x) { x.sensor.drift_per_s(5) = std::nan(""); }},
      {"sensor.noise_std", [](Scenario& x) { x.sensor.noise_std(2) = -0.1; }},
      {"sensor.resolution", [](Scenario& x) { x.sensor.resolution(4) = -0.01; }},
      {"duration_s must be > 0", [](Scenario& x) { x.duration_s = 0.0; }},
      {"exceeds 1e8 samples", [](Scenario& x) { x.duration_s = 1e7; }},
      {"trajectory", [](Scenario& x) { x.trajectory.radius_m = std::nan(""); }},
      {"plate", [](Scenario& x) { x.plate.tilt_y_rad = std::nan(""); }},
      {"law.mu_rest", [](Scenario& x) { x.law.mu_rest = -0.1; }},
      {"law.stribeck_speed_m_per_s", [](Scenario& x) { x.law.stribeck_speed_m_per_s = std::nan(""); }},
      {"sensor.cross_coupling", [](Scenario& x) { x.sensor.cross_coupling(2, 2) = 0.01; }},
      {"piecewise-linear motion",
       [](Scenario& x) {
         x.trajectory.motion = PlateTrajectory::Motion::piecewise_linear;
         x.trajectory.dwell_s = -1.0;
       }},
      {"ramp_fraction in (0, 0.5] (got 0.6)",
       [](Scenario& x) {
         x.trajectory.motion = PlateTrajectory::Motion::trapezoidal;
         x.trajectory.ramp_fraction = 0.6;
       }},
      {"ramp_fraction in (0, 0.5] (got 0)",
       [](Scenario& x) {
         x.trajectory.motion = PlateTrajectory::Motion::trapezoidal;
         x.trajectory.ramp_fraction = 0.0;
       }},
  };
  for (const auto& [field, spoil] : one_each) {
    Scenario x;
    spoil(x);
    const std::string msg = validate(x);
    EXPECT_NE(msg.find(field), std::string::npos) << field << " not in: " << msg;
    EXPECT_THAT([&] { simulate(x); }, ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("contact_truth: " + msg)))
        << field;
  }
  ContactLaw law;
  law.slip_regularisation_m_per_s = 0.0;
  EXPECT_THAT([&] { plate_wrench(Plate{}, Tripod{}, law, BodyState{}); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("law.slip_regularisation_m_per_s must be > 0 (got 0)")));
  EXPECT_EQ(validate(Scenario{}), "");
}

}  // namespace
}  // namespace hil::contact_truth
