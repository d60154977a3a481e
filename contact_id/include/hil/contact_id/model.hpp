#pragma once
/// \file Surface-compliance contact model, regressor Φ and forward simulation (contact paper eq. 2-7).
///
/// Frames: world W, end effector ee, object frames o1 (held, moves with ee) and o2 (fixed), force
/// plate fp. The contact wrench is the wrench exerted by object 2 on object 1, about the origin of
/// o1, expressed in o1 (the paper's choice, eq. 21). The force plate measures the opposite wrench
/// (object 1 pushes on object 2, which stands on the plate), about the plate origin, in fp.
///
/// Per contact i: normal force K δ_i e_n,i; while sliding (|v_t,i| > v_t,m) the friction force
/// μ K δ_i e_t,i with e_t,i = -v_t,i / |v_t,i|, v_t,i the tangential velocity of object 1's point
/// relative to object 2 at p_i; while sticking e_t,i = 0 (the friction force is then not modelled,
/// as in the paper). So w = Φ^T θ with θ = (K, μK) and Φ^T = [Σ δ e_n, Σ δ e_t; Σ δ p×e_n, Σ δ p×e_t].
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include <hil/contact_id/geometry.hpp>
#include <hil/contact_id/mindist.hpp>
#include <hil/so3/so3.hpp>

namespace hil::contact_id {

using hil::Vector6d;
using Regressor = Eigen::Matrix<double, 6, 2>;  ///< Φ^T of one sample (6 wrench rows, columns K and μK)

/// The two objects, the uncertainties on their features and the force-plate frame.
struct Scene {
  std::array<Body, 2> bodies;  ///< [0] = object 1 (held), [1] = object 2 (fixed)
  std::vector<Uncertainty> uncertainties;
  Eigen::Isometry3d T_world_fp = Eigen::Isometry3d::Identity();

  Eigen::VectorXd design() const;     ///< x_u^d
  Eigen::VectorXd prior_std() const;  ///< prior standard deviations
  /// Index of the flattened polyhedron list of a body: (feature, polyhedron) for each entry.
  std::vector<std::pair<int, int>> polyhedron_index(int body) const;
};

/// Contact parameters. \pre K > 0, μ >= 0 (checked by `check()`).
struct ContactModel {
  double K = 1.8e5;    ///< N/m
  double mu = 0.2;     ///< sliding friction coefficient
  double v_tm = 1e-3;  ///< sticking threshold on the tangential speed, m/s
  /// \throws std::invalid_argument naming the bad value.
  void check() const;
  Eigen::Vector2d theta() const { return {K, mu * K}; }
};

/// The measured kinematics of one sample: ee pose and twist (at the ee origin) in world.
struct Kinematics {
  Eigen::Isometry3d T_world_ee = Eigen::Isometry3d::Identity();
  Vec3 v_world_ee = Vec3::Zero();
  Vec3 w_world_ee = Vec3::Zero();
};

/// One contact point found by mindist, in world coordinates.
struct ContactPoint {
  double delta = 0.0;           ///< interference distance, m (> 0)
  Vec3 point = Vec3::Zero();    ///< p_i, world
  Vec3 normal = Vec3::UnitZ();  ///< e_n,i, world (direction of the normal force on object 1)
  Vec3 tangent = Vec3::Zero();  ///< e_t,i, world; zero while sticking
  double slip_speed = 0.0;      ///< |v_t,i|, m/s
  int poly1 = -1, poly2 = -1;   ///< flattened polyhedron indices in object 1 and 2
  /// -v_t,i / |v_t,i| at any slip speed, sticking or not (zero at none): where a slow slip's
  /// friction would act (the diagnosis's slow_slip candidate)
  Vec3 slip_direction = Vec3::Zero();
};

/// Posed polyhedra of both bodies for one sample and one x_u (reusable buffers).
struct PosedScene {
  std::array<std::vector<PosedPolyhedron>, 2> polys;
  std::array<Eigen::Isometry3d, 2> T_world_body;
};

Eigen::Isometry3d body_pose(const Body& b, const Eigen::Isometry3d& T_world_ee);

/// Poses every polyhedron of the scene for the ee pose and uncertainty vector x.
void pose_scene(const Scene& s, const Eigen::VectorXd& x, const Eigen::Isometry3d& T_world_ee, PosedScene& out);

/// Velocity of object 1's material point `p` (world) relative to object 2.
Vec3 relative_velocity(const Scene& s, const Kinematics& k, const Vec3& p);

/// Fills e_t and the slip speed of a pair contact (sticking below v_tm).
void tangent(const Scene& s, const Kinematics& k, double v_tm, ContactPoint& c);

/// Scratch space for mindist (reused across samples: no allocation once warm).
struct MindistWorkspace {
  PosedScene posed;
  ClipWorkspace clip;
};

/// All contact points of the scene for one sample at uncertainty x (bounding-sphere broad phase).
void mindist(const Scene& s, const Kinematics& k, const Eigen::VectorXd& x, double v_tm, std::vector<ContactPoint>& out,
             MindistWorkspace& ws);

/// Φ^T of one sample: the contact wrench per unit θ, about o1's origin, in o1.
Regressor regressor(const std::vector<ContactPoint>& contacts, const Eigen::Isometry3d& T_world_o1);
/// The contribution of one contact to Φ^T (sums to `regressor`).
Regressor regressor_row(const ContactPoint& c, const Eigen::Isometry3d& T_world_o1);

/// The plate's wrench (fp frame, about the fp origin) -> the wrench of object 2 on object 1 (o1, about o1).
Vector6d plate_to_object1(const Vector6d& w_fp, const Eigen::Isometry3d& T_world_fp, const Eigen::Isometry3d& T_world_o1);
/// The inverse of plate_to_object1.
Vector6d object1_to_plate(const Vector6d& w_o1, const Eigen::Isometry3d& T_world_fp, const Eigen::Isometry3d& T_world_o1);

/// Sensor model of a simulation: quantisation steps (0 = none) and Gaussian noise std.
struct SensorModel {
  double position_resolution_m = 0.0;
  double velocity_resolution_m_per_s = 0.0;
  double force_resolution_n = 0.0;
  double moment_resolution_nm = 0.0;
  double force_noise_n = 0.0;
  double moment_noise_nm = 0.0;
  unsigned seed = 1;
};

/// The simulated measurement of one sample.
struct SimulatedSample {
  Kinematics kin;      ///< as measured (quantised)
  Vector6d w_fp;       ///< plate wrench as measured (quantised, noisy)
  Vector6d w_fp_true;  ///< noise-free plate wrench
  int contacts = 0;
};

/// Forward simulation: the plate wrench for each true pose/twist, with the true geometry x_true.
/// Quantisation and noise of `sensor` are applied to the outputs (poses, velocities, wrenches).
std::vector<SimulatedSample> simulate(const Scene& s, const ContactModel& m, const Eigen::VectorXd& x_true,
                                      const std::vector<Kinematics>& truth, const SensorModel& sensor);

/// The noise-free plate wrench of one sample.
Vector6d plate_wrench(const Scene& s, const ContactModel& m, const Eigen::VectorXd& x, const Kinematics& k, MindistWorkspace& ws,
                      std::vector<ContactPoint>& contacts);

}  // namespace hil::contact_id
