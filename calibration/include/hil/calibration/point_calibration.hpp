#pragma once
/// \file Calibration from measured points (docs/calibration.md, "Point calibration"): static postures
/// of a robot, a point on its tool measured from one or more stations whose frames are unknown.
/// The nuisance frames (each station's pose of the robot base, the tool point) are estimated with
/// the model's parameters on one Levenberg-Marquardt, started in closed form; what the postures
/// determine is found from the SVD of the Jacobian and named; candidate extensions of the rigid
/// model are compared by held-out error (whole stations left out, or postures when there is one).
/// Pure numerics (Eigen, hil::solver).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <hil/calibration/robot.hpp>

namespace hil::calibration {

/// One measured posture.
struct PointObservation {
  Eigen::VectorXd q;            ///< joint values (rad or m)
  int station = 0;              ///< index of the station that measured it
  Eigen::Vector3d p_station_m;  ///< the measured point in the station's frame
  double payload_kg = 0.0;      ///< carried at payload_com_ee_m (tool frame): adds to the gravity load
  Eigen::Vector3d payload_com_ee_m = Eigen::Vector3d::Zero();
  double sigma_m = 0.0;           ///< the measurement's standard deviation per coordinate when the lab states it; 0: unknown
  std::vector<bool> flags;        ///< one per PointFitOptions::flag_names (an elbow or wrist flipped, ...)
  std::vector<double> tilts_rad;  ///< one per PointFitOptions::tilts: measured tilts of named links (inclinometers)
  /// The measured frame's orientation in the station's frame (rotation vector), when the device
  /// measures a full pose; used with PointFitOptions::fit_orientation.
  std::optional<Eigen::Vector3d> r_station_rad;
  double sigma_rad = 0.0;  ///< its standard deviation per component when stated; 0: unknown
};

/// What a rigid model may miss: each a model extension with its own parameters.
enum class PointCandidate {
  rigid,             ///< no extension: the nominal robot, the nuisance frames only
  joint_offsets,     ///< θ_i added to every joint value (rad or m)
  joint_compliance,  ///< joint springs under the gravity load: Δq_i = −c_i G_i(q), c_i in rad/(N·m) (needs inertials)
  backlash,          ///< an offset b_i whose sign follows the gravity torque's: Δq_i = −b_i sign(G_i(q)) (needs inertials)
  geometric,         ///< every joint frame's origin off by a small [translation; rotation] (6 per joint)
  flag_offsets,      ///< per flag column, offsets θ_fi added to the joint values of the postures it flags (needs flags)
  link_bending,      ///< named links bend as Euler-Bernoulli cantilevers under the weight (their own, spread along
                     ///< the span, and everything beyond): the chain beyond a link's end turns and moves by the
                     ///< cantilever's end motion; parameter 1/EI in 1/(N·m²) (needs inertials)
  measured_tilt,     ///< the measured tilt columns applied to their links with gain 1, nothing fitted (needs tilts)
  base_compliance,   ///< the base turns on springs about its frame's origin, about its x and y axes, by c_x M_x and
                     ///< c_y M_y: M the weight's moment about that origin (every body and the payload), c in
                     ///< rad/(N·m) (needs inertials; not compared when tilt columns measure the base's tilt)
};
const char* to_string(PointCandidate c);
/// \throws std::invalid_argument for an unknown name.
PointCandidate point_candidate_from_string(const std::string& name);
/// Every candidate but rigid, in a fixed order.
std::vector<PointCandidate> point_candidates();
/// A model: the rigid robot with a set of extensions (empty: rigid), e.g. {joint_offsets, joint_compliance}.
using PointModel = std::vector<PointCandidate>;
/// "rigid", "joint_offsets", "joint_offsets+joint_compliance".
std::string to_string(const PointModel& m);
/// Whether the candidate needs the robot's inertials.
bool needs_inertials(PointCandidate c);
struct PointFitOptions;
/// Whether the candidate can be fitted to these postures; when not, why (no inertials, no flag or
/// tilt columns, no link long enough to bend).
bool usable(PointCandidate c, const SerialRobot& robot, const std::vector<PointObservation>& obs, const PointFitOptions& options,
            std::string* why = nullptr);
/// Whether every effect of `small` is one of `big`'s (joint offsets are a part of the geometric set).
bool contains(PointCandidate big, PointCandidate small);

struct PointParameter {
  std::string name;  ///< e.g. "offset elbow_joint", "station A rz", "tool x"
  std::string unit;  ///< rad, m, rad/(N·m)
  std::string part;  ///< station, tool or the candidate's name
  double value = 0.0;
  double std = 0.0;  ///< standard deviation from the fit's covariance; NaN when not identifiable
  bool identifiable = true;
};

/// A linear combination of parameters the postures do not determine (a null direction of the
/// Jacobian), as "0.71 offset shoulder_pan_joint − 0.71 station 1 rz".
struct Undetermined {
  std::string text;
  std::vector<std::pair<std::string, double>> terms;  ///< the combination's main terms (|coefficient| ≥ 0.1)
};

struct PointFit {
  PointModel model;
  std::vector<PointParameter> parameters;         ///< stations, tool, then the candidate's
  std::vector<Eigen::Isometry3d> T_station_base;  ///< per station: a base point b maps to T b in the station's frame
  Eigen::Vector3d tool_point_ee_m = Eigen::Vector3d::Zero();
  Eigen::VectorXd residual_m;  ///< predicted − measured, 3 per posture; then, when orientations are fitted,
                               ///< 3 weighted rotation residuals (m) per posture that has one
  double rms_m = 0.0;          ///< of the 3-D distances
  double max_m = 0.0;
  double rms_rad = 0.0, max_rad = 0.0;                             ///< of the rotation residuals' angles, when orientations are fitted
  int orientations = 0;                                            ///< postures whose orientation was fitted
  Eigen::Vector3d tool_rotation_ee_rad = Eigen::Vector3d::Zero();  ///< the measured frame on the tool, when fitted
  double sigma_m = 0.0;  ///< noise per coordinate estimated from the residual, sqrt(SSR / (3N − rank))
  int rank = 0;
  int parameters_total = 0;
  double condition = 0.0;  ///< of the identifiable part (scaled units)
  std::vector<Undetermined> undetermined;
  bool converged = false;
};

struct PointFitOptions {
  Eigen::Vector3d tool_point_start_ee_m = Eigen::Vector3d::Zero();  ///< where the tool point is believed to be
  bool fit_tool_point = true;
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.80665);  ///< gravity in the robot's base frame
  /// Singular values below this × the largest (in scaled units) count as undetermined.
  double rank_tolerance = 1e-6;
  /// The stations' names in parameter names ("station A rz"); empty: 1, 2, ...
  std::vector<std::string> station_names;
  /// Jacobians in closed form (the chain's joint axes, the frames' rotation Jacobians); false:
  /// central differences of the residual, kept as the independent check of the closed form.
  bool analytic_jacobian = true;
  /// Workers for the folds and candidate models (0: every core). The results do not depend on it.
  int threads = 0;
  /// The flag columns' names, in the order of PointObservation::flags ("elbow_flipped").
  std::vector<std::string> flag_names;
  /// A measured tilt: a rotation of body `body` (0: the base, i: the body joint i moves) about its
  /// frame's x (axis 0) or y (axis 1) axis, one per PointObservation::tilts_rad.
  struct Tilt {
    int body = 0;
    int axis = 0;
    std::string name;  ///< the column, for messages
  };
  std::vector<Tilt> tilts;
  /// Bodies (1..dof) that may bend for link_bending; empty: every body whose span (its joint's origin
  /// to the next joint's, or to the flange) is at least kMinBendingSpan_m in the first posture.
  std::vector<int> bending_bodies;
  static constexpr double kMinBendingSpan_m = 0.2;
  /// Fit the measured orientations too (postures that have one): three more residuals each,
  /// log(R_measured⁻¹ R_predicted), and the measured frame's orientation on the tool ("tool rx ry
  /// rz") as a nuisance. Weighted by sigma_m / sigma_rad where a posture states both, else by
  /// kLengthPerAngle_m_per_rad (1 mrad counts as 1 mm).
  bool fit_orientation = false;
  static constexpr double kLengthPerAngle_m_per_rad = 1.0;
};

/// Fits the model `candidate` to the postures. \throws std::invalid_argument for too few postures
/// per station (3 at least, not on one line) or a candidate that needs inertials the robot lacks.
PointFit fit_points(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                    const PointFitOptions& options = {});

/// What the postures determine before anything is estimated: rank and undetermined combinations of
/// the candidate's full model (nuisance frames included) at the nominal parameters.
PointFit identifiability(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                         const PointFitOptions& options = {});

/// Held-out error of one candidate.
struct HeldOut {
  PointModel model;
  std::string scheme;       ///< "leave one station out" or "leave one posture out" / "k-fold"
  Eigen::VectorXd error_m;  ///< per posture, the 3-D distance when it was held out
  double rms_m = 0.0;
};

/// Cross-validation: with several stations each is left out in turn (its frame refitted on its own
/// postures with the model held); with one, postures are left out in `folds` interleaved folds
/// (0: one posture at a time) and predicted through the training fit's station frame.
HeldOut held_out_error(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                       int folds = 0, const PointFitOptions& options = {});

/// The rigid model against every candidate: the named cause by the rules in docs/calibration.md.
struct PointComparison {
  struct Row {
    PointModel model;
    HeldOut held_out;
    double gain = 0.0;  ///< 1 − rms / rms_rigid
    double z = 0.0;     ///< paired test of the squared held-out errors against the rigid model's
    int parameters = 0;
    int rank = 0;
  };
  HeldOut rigid;
  /// The rigid fit against the stated measurement noise (every posture's sigma_m given): χ² of its
  /// residual, Σ|r_k|²/σ_k², on 3N − rank degrees of freedom, and its 99 % quantile.
  struct Noise {
    bool stated = false;  ///< every posture has a sigma_m
    double chi2 = 0.0, dof = 0.0, bound_99 = 0.0;
    bool within = false;          ///< chi2 ≤ bound_99: the rigid model is within the noise
    double rms_over_sigma = 0.0;  ///< sqrt(chi2 / dof): how many noise standard deviations the residual is
    /// The same test of the named model (cause and second cause) fitted to every posture: whether
    /// what was named explains the run down to the noise. Set when a cause is named.
    double after_chi2 = 0.0, after_dof = 0.0, after_bound_99 = 0.0, after_rms_over_sigma = 0.0;
    bool after_within = false;
  } noise;
  std::vector<Row> rows;
  int cause = -1;         ///< index in rows (a single candidate), or -1: none
  int second_cause = -1;  ///< index in rows of the cause plus a second candidate that wins over the cause alone, or -1
  /// When a named candidate gave way to a smaller one it contains (geometric to joint_offsets):
  /// why, with the held-out figures; empty otherwise.
  std::string reduced;
  /// Single candidates (indices in rows) that pass the rules against the rigid model and that the
  /// cause does not beat by the same rules: what these postures cannot tell from it (a joint's
  /// compliance and the bending of the link it holds both deflect in proportion to the weight).
  std::vector<int> alternatives;
  /// Candidates left out of the verdict because their fit to every posture is not physical (a
  /// compliance, 1/EI or half-play below zero by more than 1.96 σ): "joint_compliance: compliance
  /// elbow_joint = −3.1e-6 ± 0.8e-6 rad/(N·m)".
  std::vector<std::string> not_physical;
  /// Links left out of link_bending before it was compared because their 1/EI, fitted to every
  /// posture, came out below zero beyond its 95 % interval (one at a time, the worst first).
  std::vector<std::string> bending_dropped;
  /// The links link_bending was compared with, by body (1..dof); empty when it was not.
  std::vector<int> bending_bodies;
  /// "cause" (a candidate is named), "none" (no candidate passes and the rigid model is within the
  /// stated noise, or no noise is stated) or "unexplained" (no candidate passes, yet the rigid
  /// model's residual is above the stated noise: something outside the library).
  std::string kind = "none";
  std::string verdict;  ///< one sentence
};
PointComparison compare_point_candidates(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations,
                                         const std::vector<PointCandidate>& candidates, int folds = 0, const PointFitOptions& options = {});

namespace detail {
/// The residual's Jacobian (scaled units) at the closed-form start moved by `dx`, in closed form
/// (first) and by central differences (second): what the tests check the closed form with.
std::pair<Eigen::MatrixXd, Eigen::MatrixXd> point_jacobians(const SerialRobot& robot, const std::vector<PointObservation>& obs,
                                                            int stations, const PointModel& model, const Eigen::VectorXd& dx,
                                                            const PointFitOptions& options = {});
}  // namespace detail

}  // namespace hil::calibration
