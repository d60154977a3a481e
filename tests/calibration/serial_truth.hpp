#pragma once
// An independent "truth" for the blind tests of the point calibration: static point measurements of
// a serial robot with joint offsets, joint springs, backlash with hysteresis, flexible links (beams),
// a base on springs and a payload. Independence is the point: the kinematics and gravity come from
// Orocos KDL (the chain built by kdl_parser from the URDF file, never hil's joint rows), the effects
// are written here from the textbook equations, and nothing of hil's calibration library is used,
// so a mistake shared by the model and the fit cannot hide here.
//
// Order of the physics in one posture (each effect is small, so each is computed on the
// configuration the previous ones leave, and second-order couplings are neglected):
//   1. joints: link side = commanded q + encoder error + offset + backlash side − holding torque / stiffness,
//      solved by fixed-point iteration with KDL's gravity torques at the link side;
//   2. beams: cantilever deflections of the named links under the loads of that configuration;
//   3. base: the whole chain tilted by the weight's moment over the base springs (every chain
//      link, the payload and the base link's own inertial, which KDL keeps out of the chain).
// A posture may carry a flag (an elbow or a wrist flipped): its joints then get flag_offset_rad on
// top of joint_offset_rad, in step 1 like any offset.
// Backlash side: −sign(τ) when |τ| exceeds the friction (gravity pushes the play over), otherwise
// +1 after a positive move of that joint, −1 after a negative one, unchanged when it did not move,
// +1 at the first posture. τ is KDL's holding torque (what the motor applies to hold the arm).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace hil::test::serial {

/// A flexible link: the segment from the origin of the link's frame (its joint's origin) to the
/// origin of the next moving joint of the chain (or of the tip frame) is an Euler–Bernoulli
/// cantilever clamped at its proximal end, loaded by its own weight spread evenly along it and, at
/// its end, by the weight of everything beyond (force and moment). Its end's small motion carries
/// the rest of the chain rigidly. Axial stretch is ignored.
struct Beam {
  std::string link;     ///< URDF link name (a segment of the chain)
  double EI_Nm2 = 0.0;  ///< bending stiffness, same in both transverse directions (> 0)
  double GJ_Nm2 = 0.0;  ///< torsional stiffness; 0 = rigid in torsion
};

/// The robot and its hidden effects. Every effect is off by default (empty vector or zero). Joint
/// vectors are either empty or hold one value per moving joint of the chain, in chain order.
struct Truth {
  std::string urdf, base, tip;                 ///< URDF file and the chain base link → tip link
  Eigen::VectorXd joint_offset_rad;            ///< link side at commanded q + offset
  Eigen::VectorXd flag_offset_rad;             ///< added to joint_offset_rad in the flagged postures only
  Eigen::VectorXd joint_stiffness_Nm_per_rad;  ///< joint springs; 0 = rigid joint
  Eigen::VectorXd backlash_rad;                ///< half of the play; 0 = none
  /// A once-per-turn error of each joint's link-side encoder (an eccentric disc): the link stands
  /// at q + A sin(q + φ) + offset where the encoder reads q. Empty or 0 = none.
  Eigen::VectorXd encoder_error_rad;     ///< A
  Eigen::VectorXd encoder_phase_rad;     ///< φ
  Eigen::VectorXd backlash_friction_Nm;  ///< |τ| above which gravity decides the side; empty = 2 N·m
  std::vector<Beam> beams;
  double base_stiffness_Nm_per_rad = 0.0;  ///< tilt stiffness about world x and y; 0 = rigid base
  double payload_kg = 0.0;
  Eigen::Vector3d payload_com_tip_m = Eigen::Vector3d::Zero();       ///< in the tip frame
  std::vector<Eigen::Isometry3d> T_station_base;                     ///< point_station = T * point_base (at least one)
  Eigen::Vector3d tool_point_m = Eigen::Vector3d::Zero();            ///< in the tip frame
  double noise_m = 0.0;                                              ///< Gaussian, per coordinate
  double tilt_noise_rad = 0.0;                                       ///< Gaussian, per base inclinometer reading
  Eigen::Matrix3d measured_frame_tip = Eigen::Matrix3d::Identity();  ///< a 6-D device's measured frame in the tip frame
  double noise_rad = 0.0;  ///< Gaussian, per component of the measured orientation's small noise rotation (station frame)
};

struct Sample {
  Eigen::VectorXd q;            ///< commanded joint values
  int station = 0;              ///< k % number of stations
  Eigen::Vector3d p_station_m;  ///< measured: station frame, with noise
  Eigen::Vector3d p_base_m;     ///< noiseless, base frame (for tests)
  Eigen::VectorXd q_link;       ///< link-side joint values after offsets, springs, backlash (for tests)
  bool flag = false;            ///< the posture's flag, as given
  /// The base inclinometer's reading, with noise: the x and y components of the rotation vector
  /// (axis·angle) of the tilt the base springs give the whole chain, in the base frame. The tilt
  /// turns about the base frame's origin: a point p of the chain (base coordinates, untilted) goes
  /// to exp([rx, ry, 0]) · p. Gravity being along −z, the tilt's rotation vector has no z component.
  /// Zero (noise only) when the base is rigid.
  Eigen::Vector2d base_tilt_rad = Eigen::Vector2d::Zero();
  /// The measured frame's orientation in the station's frame (rotation vector): station · deflected
  /// tip · measured_frame_tip, turned by the noise rotation (drawn last, only when noise_rad > 0).
  Eigen::Vector3d r_station_rad = Eigen::Vector3d::Zero();
};

/// Standard gravity, m/s², along −z of the (untilted) base frame.
inline constexpr double kGravity_m_per_s2 = 9.80665;

/// `n` postures, each joint uniform in its (lower, upper) range: one range per moving joint.
std::vector<Eigen::VectorXd> draw_postures(int n, const std::vector<std::pair<double, double>>& range_rad, std::mt19937& rng);

/// The measurements of `postures` in that order: backlash has hysteresis, so the order matters
/// (the link side of a joint under small torque stays where the last move of that joint left it).
/// Posture k is measured from station k % T_station_base.size(). `flags` is empty (no posture
/// flagged) or holds one flag per posture. Noise is drawn from `rng`, posture by posture: the
/// point's three coordinates when noise_m > 0, then the inclinometer's x and y readings when
/// tilt_noise_rad > 0 (so that without tilt noise the stream is the one of the runs before it
/// existed, which the blind suite's seeds depend on). Throws std::invalid_argument on a URDF KDL
/// cannot read, a missing chain, an unknown or zero-length beam link, a vector of the wrong size, a
/// negative stiffness or noise, or a number of flags that is neither 0 nor one per posture.
std::vector<Sample> generate(const Truth& t, const std::vector<Eigen::VectorXd>& postures, const std::vector<bool>& flags,
                             std::mt19937& rng);
/// The same with no posture flagged.
std::vector<Sample> generate(const Truth& t, const std::vector<Eigen::VectorXd>& postures, std::mt19937& rng);

/// A random station frame: a rotation of up to `angle_rad` about a random axis, a translation of up
/// to `distance_m` per axis.
Eigen::Isometry3d random_station(std::mt19937& rng, double angle_rad, double distance_m);

}  // namespace hil::test::serial
