#pragma once
/// \file An independent ground truth for the contact diagnosis (issue 12): a rigid tripod whose
/// three point feet press on and slide over a plate, and the sensor chain of a 6-axis force plate.
///
/// Written from the equations below and from nothing in hil::contact_id or hil::diagnose (no
/// polyhedra, no mindist, no candidate code), so that a test that hides an effect with it does not
/// generate the effect with the code that then has to find it. Eigen only.
///
/// Frames: W world; P plate (origin on the top surface, z along the outward normal); B the tripod's
/// body (its feet at fixed points of B). Per foot i at p_i (W), with n the plate normal (W):
///   penetration   δ_i  = max(0, -n·(p_i - o_P))                        (m)
///   its rate      δ̇_i  = -n·v_i, v_i = v_B + ω_B × (p_i - o_B)          (m/s)
///   normal force  N_i  = max(0, K δ_ref (δ_i/δ_ref)^p + D (δ_i/δ_ref)^q δ̇_i)  while δ_i > 0   (N)
///                 (q = 0: Kelvin-Voigt, a linear dashpot; q = p: Hunt-Crossley's damping, which
///                 grows from nothing at first touch)
///   friction      F_i  = -μ(|u_i|) N'_i u_i / sqrt(|u_i|² + ε²) - c_v u_i,  u_i the tangential velocity,
///                 μ(s) = μ + (μ_rest - μ) exp(-(s / v_s)²) (Stribeck; μ alone without a speed v_s)
///                 N'_i = N_i (friction on the total normal force, Kelvin-Voigt / Hunt-Crossley)
///                      or max(0, K δ_ref (δ_i/δ_ref)^p) (friction on the elastic force only)
/// The plate feels -(N_i n + F_i) at p_i; the reported wrench is that sum's force and moment about
/// o_P, in P (fx fy fz in N, mx my mz in N m).
///
/// Sensor chain per output sample k at t_k = k / rate: an optional first-order low-pass filter
/// (an amplifier's anti-aliasing stage, y' = (x - y) / τ_f) on the true wrench, then the ADC
/// averages it at `adc_subsamples` instants evenly spread over the period (t_k - τ - T, t_k - τ]
/// (τ a delay of the wrench stream), then w = (1 + γ) ∘ w̄ + b + ḃ t_k + e (gain, bias, drifting
/// offset, white Gaussian noise e), then quantisation to multiples of the resolution. The pose the robot reports
/// is the commanded one; a slip event moves the true tripod against it from its time on.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace hil::contact_truth {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// The plate: its top surface's origin and orientation in W.
struct Plate {
  Eigen::Vector3d origin_world_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;     ///< about W z, applied last
  double tilt_x_rad = 0.0;  ///< about the plate's x, then
  double tilt_y_rad = 0.0;  ///< about its y
  Eigen::Isometry3d T_world_plate() const;
};

/// A rigid tripod: the feet's tips in its body frame B (m). Any number of feet >= 1 works; three
/// make the usual statically determinate stand.
struct Tripod {
  /// Default: three feet 120° apart on a 5 cm circle about the body origin, in its z = 0 plane.
  std::vector<Eigen::Vector3d> feet_body_m{{0.05, 0.0, 0.0}, {-0.025, 0.04330127018922193, 0.0}, {-0.025, -0.04330127018922193, 0.0}};
};

/// The point-contact law (see the file comment).
struct ContactLaw {
  double stiffness_n_per_m = 2e5;             ///< K
  double exponent = 1.0;                      ///< p (1: linear)
  double delta_ref_m = 1e-4;                  ///< δ_ref of the power law
  double damping_n_s_per_m = 0.0;             ///< D (at δ = δ_ref when q != 0)
  double damping_exponent = 0.0;              ///< q: 0 Kelvin-Voigt, p Hunt-Crossley
  bool friction_on_total_normal = true;       ///< N' = N (true) or the elastic part only (false)
  double mu = 0.3;                            ///< Coulomb coefficient
  double slip_regularisation_m_per_s = 1e-4;  ///< ε: below it friction grows linearly with speed
  double viscous_n_s_per_m = 0.0;             ///< c_v
  /// Friction that falls with the sliding speed (Stribeck): μ_rest at rest, μ well above
  /// stribeck_speed_m_per_s. Off when that speed is 0.
  double mu_rest = 0.0;
  double stribeck_speed_m_per_s = 0.0;  ///< v_s
};

/// The tripod's true motion at one instant (all in W).
struct BodyState {
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_world_m_per_s = Eigen::Vector3d::Zero();    ///< velocity of B's origin
  Eigen::Vector3d w_world_rad_per_s = Eigen::Vector3d::Zero();  ///< angular velocity
};

/// Per foot, what the law computed (for tests and plots).
struct FootContact {
  double penetration_m = 0.0, penetration_rate_m_per_s = 0.0;
  double normal_n = 0.0;                                       ///< N_i
  Eigen::Vector3d friction_world_n = Eigen::Vector3d::Zero();  ///< F_i
  Eigen::Vector3d point_world_m = Eigen::Vector3d::Zero();
  bool in_contact = false;
};

/// The wrench the plate feels (P frame, about o_P), and the feet's contacts if `feet` is given.
/// \throws std::invalid_argument on a law that is not physical (names the field).
Vector6d plate_wrench(const Plate& plate, const Tripod& tripod, const ContactLaw& law, const BodyState& s,
                      std::vector<FootContact>* feet = nullptr);

/// A closed-form trajectory relative to the plate, of one of three motion families. In P:
///  * sinusoidal: the body origin circles, x = cx + r cos(ω t), y = cy + r sin(ω t); the depth
///    z = -(d0 + d1 sin(ω_d t) + d2 sin(ω_d2 t)) (d > 0: the feet penetrate); the yaw
///    ψ = ψ0 + ψ1 sin(ω_ψ t);
///  * piecewise_linear (what a robot's point-to-point moves give): the body origin goes round the
///    square of half-side r about (cx, cy) at the speed r ω along each side, and stops `dwell_s` at
///    each corner; the depth and the yaw are the same sums with each sine replaced by the triangle
///    wave of the same period and amplitude, tri(θ) = (2/π) asin(sin θ), so the normal motion
///    has kinks and constant rates;
///  * trapezoidal (what a robot's trajectory generator gives for the same moves): the same square
///    with stops and the same periodic depth and yaw, but every move's speed is a trapezoid: a
///    constant acceleration for the share `ramp_fraction` of the move, cruise, and the mirrored
///    deceleration. The cruise speed is raised so that each move keeps its duration (the square's
///    side 2/|ω|, a tone's half period π/ω_d): v = distance / ((1 - ramp_fraction) duration).
///    The rates are continuous (no kinks), the accelerations step; ramp_fraction → 0 is the
///    piecewise-linear family, 0.5 a triangular speed profile.
/// The body's z stays along the plate normal.
struct PlateTrajectory {
  enum class Motion { sinusoidal, piecewise_linear, trapezoidal };
  Motion motion = Motion::sinusoidal;
  double centre_x_m = 0.0, centre_y_m = 0.0;
  double radius_m = 5e-3;
  double angular_rate_rad_per_s = 0.5;  ///< ω
  double depth_m = 1e-4;                ///< d0
  double depth_amplitude_m = 5e-5;      ///< d1
  double depth_rate_rad_per_s = 1.3;    ///< ω_d
  double depth_amplitude2_m = 0.0;      ///< d2 (a second tone of the normal motion)
  double depth_rate2_rad_per_s = 0.0;   ///< ω_d2
  double yaw_rad = 0.0;                 ///< ψ0
  double yaw_amplitude_rad = 0.05;      ///< ψ1
  double yaw_rate_rad_per_s = 0.7;      ///< ω_ψ
  double dwell_s = 0.5;                 ///< piecewise_linear, trapezoidal: the stop at each corner
  double ramp_fraction = 0.25;          ///< trapezoidal: each move's share accelerating, in (0, 0.5]
  /// The body state at time t (W), with its analytic velocities (one-sided at a kink).
  BodyState at(const Plate& plate, double t_s) const;
};

/// A slip of the tripod against the commanded pose: from t on, the true body is displaced by
/// (dx, dy) in the plate plane and turned by dyaw about the plate normal (at its origin), while the
/// robot keeps reporting the commanded pose.
struct SlipEvent {
  double t_s = 0.0;
  double dx_m = 0.0, dy_m = 0.0, dyaw_rad = 0.0;
};

/// The force plate's sensor chain (see the file comment). Components in the order fx fy fz mx my mz.
struct SensorChain {
  double rate_hz = 100.0;
  int adc_subsamples = 10;  ///< instants the ADC averages per output sample
  double delay_s = 0.0;     ///< τ: the wrench stream lags the poses
  /// τ_f: a first-order low-pass before the ADC (0: none). Not a pure delay: its group delay is
  /// τ_f / (1 + (ω τ_f)²) and its gain 1 / sqrt(1 + (ω τ_f)²) at ω.
  double filter_time_constant_s = 0.0;
  Vector6d gain = Vector6d::Zero();         ///< γ: relative gain error per component
  Vector6d bias = Vector6d::Zero();         ///< b: constant offset (N, N m)
  Vector6d drift_per_s = Vector6d::Zero();  ///< ḃ: slowly drifting offset (N/s, N m/s)
  /// X: cross-coupling, row = measured component, column = true component (e.g. X(1, 0) = 0.04:
  /// 4 % of fx leaks into fy). Its diagonal must be zero (the gain is γ).
  Eigen::Matrix<double, 6, 6> cross_coupling = Eigen::Matrix<double, 6, 6>::Zero();
  Vector6d noise_std = Vector6d::Zero();   ///< std of e (N, N m)
  Vector6d resolution = Vector6d::Zero();  ///< quantisation step (0: none)
  unsigned seed = 1;
};

/// A first-order low-pass filter y' = (x - y) / τ_f of a wrench, integrated exactly for an input
/// linear between the instants it is given (first-order hold): feed it at steps short against
/// the input's changes. The first call settles it on its input.
class FirstOrderLag {
 public:
  /// \throws std::invalid_argument unless τ_f > 0 and finite.
  explicit FirstOrderLag(double time_constant_s);
  /// The output at t for the input x at t; t must not decrease.
  Vector6d at(double t_s, const Vector6d& x);

 private:
  double tau_s_;
  bool started_ = false;
  double t_s_ = 0.0;
  Vector6d x_ = Vector6d::Zero(), y_ = Vector6d::Zero();
};

/// One output sample: what the rig reports (commanded pose and twist, measured wrench) and the
/// truth behind it.
struct Sample {
  double t_s = 0.0;
  BodyState reported;                           ///< the commanded state the robot reports
  Vector6d wrench_measured = Vector6d::Zero();  ///< plate frame, about o_P
  Vector6d wrench_true = Vector6d::Zero();      ///< the true wrench at t_s (no sensor chain)
  int feet_in_contact = 0;                      ///< at t_s, true pose
};

/// A whole scene: plate, tripod, law, motion, sensor and events.
struct Scenario {
  Plate plate;
  Tripod tripod;
  ContactLaw law;
  PlateTrajectory trajectory;
  SensorChain sensor;
  std::vector<SlipEvent> slips;
  double duration_s = 40.0;
};

/// The true body state at t (the commanded one moved by the slips that happened by t).
BodyState true_state(const Scenario& s, double t_s);

/// Simulates `duration_s * rate_hz` samples from t = 0.
/// \throws std::invalid_argument on a scenario that is not physical or not simulable (names the field).
std::vector<Sample> simulate(const Scenario& s);

/// Checks a scenario; empty when valid, else every problem, each naming its field.
std::string validate(const Scenario& s);

}  // namespace hil::contact_truth
