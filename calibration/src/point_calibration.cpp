#include <hil/calibration/point_calibration.hpp>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include <hil/calibration/gravity.hpp>
#include <hil/parallel/run_tasks.hpp>
#include <hil/so3/so3.hpp>
#include <hil/solver/levenberg_marquardt.hpp>

namespace hil::calibration {
namespace {

// Scaled units for the solver and the rank test: what a calibration's parameters are typically
// worth (mm, mrad; joint compliance in µrad/(N·m)).
constexpr double kLengthScale_m = 1e-3;
constexpr double kAngleScale_rad = 1e-3;
constexpr double kComplianceScale = 1e-6;
constexpr double kBendingScale = 1e-6;  ///< 1/EI in 1/(N·m²): a 0.6 m link of EI 1e5 N·m² under 100 N·m turns 0.6 mrad
constexpr double kResidualScale_m = 1e-4;

/// The bodies that may bend: the options' list, or every body spanning at least
/// kMinBendingSpan_m in the first posture.
std::vector<int> bending_bodies(const SerialRobot& robot, const std::vector<PointObservation>& obs, const PointFitOptions& opt);

/// Where each block of parameters sits in x.
struct Layout {
  int stations = 0, dof = 0;
  bool tool = true;
  int flags = 0, bending = 0;                          ///< flag columns; bodies that may bend
  std::vector<std::pair<PointCandidate, int>> blocks;  ///< each extension and its first index
  int tool_at = 0, size = 0;
  int rot_at = -1;  ///< the measured frame's orientation on the tool, when orientations are fitted

  Layout(int stations_, int dof_, bool tool_, const PointModel& model, int flags_ = 0, int bending_ = 0, bool orientation = false)
      : stations(stations_), dof(dof_), tool(tool_), flags(flags_), bending(bending_) {
    tool_at = 6 * stations;
    int at = tool_at + (tool ? 3 : 0);
    if (orientation) rot_at = at, at += 3;
    for (const auto c : model) {
      if (c == PointCandidate::rigid) continue;
      blocks.emplace_back(c, at);
      at += block_size(c);
    }
    size = at;
  }
  int block_size(PointCandidate c) const {
    switch (c) {
      case PointCandidate::geometric: return 6 * dof;
      case PointCandidate::flag_offsets: return flags * dof;
      case PointCandidate::link_bending: return bending;
      case PointCandidate::measured_tilt:
      case PointCandidate::rigid: return 0;
      case PointCandidate::base_compliance: return 2;
      case PointCandidate::joint_offsets:
      case PointCandidate::joint_compliance:
      case PointCandidate::backlash: return dof;
    }
    return 0;
  }
  int block(PointCandidate c) const {
    for (const auto& [k, at] : blocks)
      if (k == c) return at;
    return -1;
  }
};

struct Problem {
  const SerialRobot& robot;
  const std::vector<PointObservation>& obs;
  std::vector<Eigen::Isometry3d> T0;  ///< closed-form station frames; x perturbs them
  Layout layout;
  Eigen::Vector3d tool_fixed;  ///< when the tool point is not fitted
  Eigen::Vector3d g_world;
  std::vector<ChainPoses> nominal;  ///< rigid poses per posture (for the gravity load)
  std::vector<Eigen::VectorXd> G;   ///< holding torques per posture, when a candidate needs them
  std::vector<std::string> station_names;
  bool analytic = true;
  std::vector<std::string> flag_names;
  std::vector<int> bend;  ///< bodies that may bend (link_bending), one parameter each
  /// Per posture and bending body: the link's end (world), and the cantilever's end motion per unit
  /// 1/EI: the chain beyond the end turns about it by exp(v / EI) and moves by d / EI.
  std::vector<std::vector<Eigen::Vector3d>> bend_end, bend_v, bend_d;
  /// Per posture, the measured tilt of each body 0..N as a rotation vector in its frame (measured_tilt).
  std::vector<std::vector<Eigen::Vector3d>> tilt;
  /// Per posture, the weight's moment about the base frame's origin in that frame, x and y (base_compliance).
  std::vector<Eigen::Vector2d> base_moment;
  /// Orientation rows: per posture the first of its 3 rotation residuals (−1: none) and its weight
  /// (m/rad); the measured rotations in order of the postures that have one.
  std::vector<int> rot_row;
  std::vector<double> rot_weight;
  std::vector<Eigen::Matrix3d> R_measured;
  int residual_rows = 0;

  Problem(const SerialRobot& r, const std::vector<PointObservation>& o, int stations, const PointModel& model, const PointFitOptions& opt)
      : robot(r), obs(o), layout(stations, r.dof(), opt.fit_tool_point, model), tool_fixed(opt.tool_point_start_ee_m), g_world(opt.g_world),
        station_names(opt.station_names), analytic(opt.analytic_jacobian), flag_names(opt.flag_names) {
    for (int s = static_cast<int>(station_names.size()); s < stations; ++s) station_names.push_back(std::to_string(s + 1));
    const auto uses = [&](PointCandidate c) { return std::find(model.begin(), model.end(), c) != model.end(); };
    std::string why;
    for (const auto c : model)
      if (c != PointCandidate::rigid && !usable(c, robot, obs, opt, &why))
        throw std::invalid_argument("model " + to_string(model) + ": " + why);
    if (uses(PointCandidate::link_bending)) bend = bending_bodies(robot, obs, opt);
    // Rows: 3 per posture for the point, then 3 per posture with an orientation when they are fitted.
    int rows = 3 * static_cast<int>(obs.size());
    rot_row.assign(obs.size(), -1);
    rot_weight.assign(obs.size(), 0.0);
    if (opt.fit_orientation)
      for (std::size_t k = 0; k < obs.size(); ++k) {
        if (!obs[k].r_station_rad) continue;
        rot_row[k] = rows, rows += 3;
        rot_weight[k] = obs[k].sigma_m > 0 && obs[k].sigma_rad > 0 ? obs[k].sigma_m / obs[k].sigma_rad
                                                                   : PointFitOptions::kLengthPerAngle_m_per_rad;
        R_measured.push_back(so3::exp(*obs[k].r_station_rad));
      }
    residual_rows = rows;
    if (opt.fit_orientation && rows == 3 * static_cast<int>(obs.size()))
      throw std::invalid_argument("orientations are to be fitted, but no posture has one (rx, ry, rz)");
    const bool orientation = opt.fit_orientation;
    layout = Layout(stations, r.dof(), opt.fit_tool_point, model, static_cast<int>(flag_names.size()), static_cast<int>(bend.size()),
                    orientation);
    bool gravity = false;
    for (const auto c : model) gravity = gravity || needs_inertials(c);
    const int n = robot.dof();
    for (const auto& p : obs) {
      nominal.push_back(forward(robot, p.q));
      if (gravity) G.push_back(gravity_torques(robot, nominal.back(), g_world, p.payload_kg, p.payload_com_ee_m));
      if (!bend.empty()) bending_loads(p, nominal.back());
      if (uses(PointCandidate::base_compliance)) base_moment.push_back(base_load(p, nominal.back()));
      if (uses(PointCandidate::measured_tilt)) {
        tilt.emplace_back(static_cast<std::size_t>(n) + 1, Eigen::Vector3d::Zero());
        for (std::size_t t = 0; t < opt.tilts.size(); ++t)
          tilt.back()[static_cast<std::size_t>(opt.tilts[t].body)][opt.tilts[t].axis] += p.tilts_rad[t];
      }
    }
  }

  /// The bending loads of one posture on the nominal chain, as a clamped Euler-Bernoulli
  /// cantilever's end motion per unit 1/EI: the link's own weight spread evenly along its span, and
  /// at its end the weight of everything beyond (a force and its moment about the end). Only the
  /// parts across the span bend it (torsion is not modelled).
  void bending_loads(const PointObservation& p, const ChainPoses& poses) {
    const int n = robot.dof();
    auto& ends = bend_end.emplace_back();
    auto& turns = bend_v.emplace_back();
    auto& moves = bend_d.emplace_back();
    for (const int b : bend) {
      const auto ub = static_cast<std::size_t>(b);
      const Eigen::Vector3d a = poses.p_world_joint_m[ub - 1];
      const Eigen::Vector3d d = b < n ? poses.p_world_joint_m[ub] : poses.T_world_body[ub].translation();
      const double L = (d - a).norm();
      ends.push_back(d);
      if (L < 1e-9) {  // a body named to bend that spans nothing: it cannot turn anything
        turns.push_back(Eigen::Vector3d::Zero());
        moves.push_back(Eigen::Vector3d::Zero());
        continue;
      }
      const Eigen::Vector3d u = (d - a) / L;
      const auto across = [&u](const Eigen::Vector3d& v) { return Eigen::Vector3d(v - u * u.dot(v)); };
      Eigen::Vector3d P = p.payload_kg * g_world;
      Eigen::Vector3d M = (poses.T_world_ee * p.payload_com_ee_m - d).cross(p.payload_kg * g_world);
      for (int j = b + 1; j <= n; ++j) {
        const auto& in = robot.inertials[static_cast<std::size_t>(j)];
        P += in.mass_kg * g_world;
        M += (poses.T_world_body[static_cast<std::size_t>(j)] * in.com_m - d).cross(in.mass_kg * g_world);
      }
      const Eigen::Vector3d w = across(robot.inertials[ub].mass_kg * g_world / L), Pt = across(P), Mb = across(M);
      const double L2 = L * L, L3 = L2 * L;
      turns.push_back(u.cross(w) * L3 / 6.0 + u.cross(Pt) * L2 / 2.0 + Mb * L);
      moves.push_back(w * L3 * L / 8.0 + Pt * L3 / 3.0 + Mb.cross(u) * L2 / 2.0);
    }
  }

  /// The moment about the base frame's origin, in that frame, of the weight of every body (the base
  /// link's too: the springs are under it) and of the payload, on the nominal chain.
  Eigen::Vector2d base_load(const PointObservation& p, const ChainPoses& poses) const {
    const Eigen::Vector3d o = robot.T_world_base.translation();
    Eigen::Vector3d M = (poses.T_world_ee * p.payload_com_ee_m - o).cross(p.payload_kg * g_world);
    for (std::size_t j = 0; j < robot.inertials.size(); ++j)
      M += (poses.T_world_body[j] * robot.inertials[j].com_m - o).cross(robot.inertials[j].mass_kg * g_world);
    return (robot.T_world_base.linear().transpose() * M).head<2>();
  }
  /// The base's turn at posture k (rotation vector in the base frame, z = 0).
  Eigen::Vector3d base_turn(const Eigen::VectorXd& x, std::size_t k) const {
    const int b = layout.block(PointCandidate::base_compliance);
    if (b < 0) return Eigen::Vector3d::Zero();
    return Eigen::Vector3d(x[b] * base_moment[k].x(), x[b + 1] * base_moment[k].y(), 0.0);
  }

  Eigen::Isometry3d station(const Eigen::VectorXd& x, int s) const {
    Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
    d.linear() = so3::exp(Eigen::Vector3d(x.segment<3>(6 * s)));
    d.translation() = x.segment<3>(6 * s + 3);
    return d * T0[static_cast<std::size_t>(s)];
  }
  Eigen::Vector3d tool(const Eigen::VectorXd& x) const { return layout.tool ? Eigen::Vector3d(x.segment<3>(layout.tool_at)) : tool_fixed; }
  Eigen::Vector3d tool_rotation(const Eigen::VectorXd& x) const {
    return layout.rot_at >= 0 ? Eigen::Vector3d(x.segment<3>(layout.rot_at)) : Eigen::Vector3d::Zero();
  }
  /// The measured frame's predicted orientation in station s's frame, from the chain's R_base_ee.
  Eigen::Matrix3d predicted_rotation(const Eigen::VectorXd& x, int s, const Eigen::Matrix3d& R_base_ee) const {
    return station(x, s).linear() * R_base_ee * so3::exp(tool_rotation(x));
  }

  /// Joint values of posture k as the model moves them (offsets, springs, backlash).
  Eigen::VectorXd effective_q(const Eigen::VectorXd& x, std::size_t k) const {
    const int n = robot.dof();
    Eigen::VectorXd q = obs[k].q;
    if (const int b = layout.block(PointCandidate::joint_offsets); b >= 0) q += x.segment(b, n);
    if (const int b = layout.block(PointCandidate::joint_compliance); b >= 0) q -= x.segment(b, n).cwiseProduct(G[k]);
    if (const int b = layout.block(PointCandidate::backlash); b >= 0)
      for (int i = 0; i < n; ++i) q[i] -= x[b + i] * sign(G[k][i]);
    if (const int b = layout.block(PointCandidate::flag_offsets); b >= 0)
      for (int f = 0; f < layout.flags; ++f)
        if (obs[k].flags[static_cast<std::size_t>(f)]) q += x.segment(b + f * n, n);
    return q;
  }
  static double sign(double v) { return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0; }

  /// What the closed-form Jacobian needs of the chain at one posture, per joint i: the frame before
  /// its geometric error E_i, the frame after it, and the joint's axis and a point on it (base
  /// frame). Scratch storage, reused between postures.
  struct Chain {
    std::vector<Eigen::Isometry3d> before_error, after_error;
    std::vector<Eigen::Vector3d> axis, on_axis;
    Eigen::Matrix3d R_base_ee;
    Eigen::Matrix3d R_base_turned;               ///< the base frame after its tilt and its turn (base_compliance)
    Eigen::Vector3d p_rigid;                     ///< the point before the links' bending
    Eigen::Matrix3d R_bend;                      ///< ∂p/∂p_rigid: the bending turns, proximal first
    std::vector<Eigen::Vector3d> w;              ///< per bending body: the point about the link's end, before its turn
    std::vector<Eigen::Matrix3d> R_before_bend;  ///< per bending body: the product of the turns proximal to it
  };

  /// The tool point in the robot's base frame (T_world_base included) at posture k; with `chain`,
  /// what the Jacobian needs of the walk.
  Eigen::Vector3d point_base(const Eigen::VectorXd& x, std::size_t k, Chain* chain = nullptr) const {
    const int n = robot.dof();
    const Eigen::VectorXd q = effective_q(x, k);
    const int geo = layout.block(PointCandidate::geometric);
    if (chain) {
      for (auto* v : {&chain->before_error, &chain->after_error}) v->resize(static_cast<std::size_t>(n));
      for (auto* v : {&chain->axis, &chain->on_axis}) v->resize(static_cast<std::size_t>(n));
    }
    const bool tilted = !tilt.empty();
    Eigen::Isometry3d T = robot.T_world_base;
    if (tilted) T.linear() = T.linear() * so3::exp(tilt[k][0]);
    if (!base_moment.empty()) T.linear() = T.linear() * so3::exp(base_turn(x, k));
    if (chain) chain->R_base_turned = T.linear();
    for (int i = 0; i < n; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      if (chain) chain->before_error[ui] = T;
      if (geo >= 0) {
        Eigen::Isometry3d E = Eigen::Isometry3d::Identity();
        E.translation() = x.segment<3>(geo + 6 * i);
        E.linear() = so3::exp(Eigen::Vector3d(x.segment<3>(geo + 6 * i + 3)));
        T = T * E;
      }
      const DhRow& row = robot.joints[ui];
      const Eigen::Isometry3d A = dh_transform(robot.convention, row, q[i]);
      if (chain) {
        // The joint's axis as forward() finds it: standard DH, z of the frame before the row;
        // modified, z of the frame after it; URDF, the row's axis in its joint frame.
        chain->after_error[ui] = T;
        if (robot.convention == DhConvention::urdf) {
          chain->axis[ui] = T.linear() * (row.T_parent_joint.linear() * row.axis);
          chain->on_axis[ui] = T * row.T_parent_joint.translation();
        } else {
          const Eigen::Isometry3d at = robot.convention == DhConvention::standard ? T : T * A;
          chain->axis[ui] = at.linear().col(2);
          chain->on_axis[ui] = at.translation();
        }
      }
      T = T * A;
      if (tilted) T.linear() = T.linear() * so3::exp(tilt[k][ui + 1]);
    }
    const Eigen::Isometry3d T_ee = T * robot.T_flange_ee;
    Eigen::Vector3d p = T_ee * tool(x);
    if (chain) chain->R_base_ee = T_ee.linear(), chain->p_rigid = p, chain->R_bend.setIdentity();
    if (bend.empty()) return p;
    // Each bending body turns the chain beyond its end and moves it; distal first, so that the
    // proximal motions carry the distal ones (ends and loads on the nominal chain: the deflections
    // are small).
    const int b0 = layout.block(PointCandidate::link_bending);
    if (chain) chain->w.resize(bend.size()), chain->R_before_bend.resize(bend.size());
    for (std::size_t l = bend.size(); l-- > 0;) {
      const Eigen::Vector3d w = p - bend_end[k][l];
      p = so3::exp(Eigen::Vector3d(x[b0 + static_cast<int>(l)] * bend_v[k][l])) * w + bend_end[k][l] +
          x[b0 + static_cast<int>(l)] * bend_d[k][l];
      if (chain) chain->w[l] = w;
    }
    if (chain) {
      for (std::size_t l = 0; l < bend.size(); ++l) {
        chain->R_before_bend[l] = chain->R_bend;
        chain->R_bend = chain->R_bend * so3::exp(Eigen::Vector3d(x[b0 + static_cast<int>(l)] * bend_v[k][l]));
      }
      chain->R_base_ee = chain->R_bend * chain->R_base_ee;
    }
    return p;
  }

  /// r = (predicted − measured) / kResidualScale_m, 3 per posture; then the weighted rotation
  /// residuals w log(R_measured⁻¹ R_predicted) of the postures with an orientation.
  void residual(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    r.resize(residual_rows);
    Chain chain;
    std::size_t m = 0;
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const bool rot = rot_row[k] >= 0;
      const Eigen::Vector3d p = rot ? point_base(x, k, &chain) : point_base(x, k);
      r.segment<3>(3 * static_cast<Eigen::Index>(k)) = (station(x, obs[k].station) * p - obs[k].p_station_m) / kResidualScale_m;
      if (rot)
        r.segment<3>(rot_row[k]) =
            rot_weight[k] *
            so3::log(Eigen::Matrix3d(R_measured[m++].transpose() * predicted_rotation(x, obs[k].station, chain.R_base_ee))) /
            kResidualScale_m;
    }
  }

  Eigen::VectorXd scale() const {
    Eigen::VectorXd s(layout.size);
    for (int i = 0; i < 6 * layout.stations; ++i) s[i] = i % 6 < 3 ? kAngleScale_rad : kLengthScale_m;
    if (layout.tool) s.segment<3>(layout.tool_at).setConstant(kLengthScale_m);
    if (layout.rot_at >= 0) s.segment<3>(layout.rot_at).setConstant(kAngleScale_rad);
    for (const auto& [c, at] : layout.blocks) {
      const int n = layout.dof;
      if (c == PointCandidate::geometric) {
        for (int i = 0; i < 6 * n; ++i) s[at + i] = i % 6 < 3 ? kLengthScale_m : kAngleScale_rad;
      } else if (c == PointCandidate::link_bending) {
        s.segment(at, layout.bending).setConstant(kBendingScale);
      } else if (c == PointCandidate::base_compliance) {
        s.segment<2>(at).setConstant(kComplianceScale);
      } else if (c == PointCandidate::flag_offsets) {
        for (int f = 0; f < layout.flags; ++f)
          for (int i = 0; i < n; ++i)
            s[at + f * n + i] = robot.joints[static_cast<std::size_t>(i)].kind == JointKind::prismatic ? kLengthScale_m : kAngleScale_rad;
      } else {
        for (int i = 0; i < layout.block_size(c); ++i) {
          const bool prismatic = robot.joints[static_cast<std::size_t>(i)].kind == JointKind::prismatic;
          s[at + i] = c == PointCandidate::joint_compliance ? kComplianceScale : prismatic ? kLengthScale_m : kAngleScale_rad;
        }
      }
    }
    return s;
  }

  /// ∂r/∂u (u = x / scale).
  void jacobian(const Eigen::VectorXd& x, Eigen::MatrixXd& J, const Eigen::VectorXd& scale) const {
    if (analytic) jacobian_closed_form(x, J);
    else jacobian_central_differences(x, J, scale);
    for (Eigen::Index j = 0; j < x.size(); ++j) J.col(j) *= scale[j];
  }

  /// ∂r/∂x: the chain walked once per posture. Joint values enter through q_eff (offsets, springs
  /// and backlash are each a multiple of ∂p/∂q_i); a frame error E_i = (t_i, exp(ω_i)) moves the
  /// point by the frame before it (t_i) and by the rotation Jacobian of exp(ω_i) (ω_i); a station's
  /// perturbation likewise.
  void jacobian_closed_form(const Eigen::VectorXd& x, Eigen::MatrixXd& J) const {
    const int n = robot.dof();
    J.setZero(residual_rows, x.size());
    const int off = layout.block(PointCandidate::joint_offsets), comp = layout.block(PointCandidate::joint_compliance),
              back = layout.block(PointCandidate::backlash), geo = layout.block(PointCandidate::geometric),
              flag = layout.block(PointCandidate::flag_offsets), bent = layout.block(PointCandidate::link_bending),
              base = layout.block(PointCandidate::base_compliance);
    Chain chain;
    std::size_t m = 0;
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const Eigen::Index row = 3 * static_cast<Eigen::Index>(k);
      const Eigen::Vector3d p = point_base(x, k, &chain);
      const int s = obs[k].station;
      const Eigen::Matrix3d R_station = station(x, s).linear();
      // Orientation rows: a rotation δθ of the measured frame, in the station's frame, moves the
      // residual w log(R_m⁻¹ R) by w Jr(r)⁻¹ Rᵀ δθ.
      const int rr = rot_row[k];
      Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
      if (rr >= 0) {
        const Eigen::Matrix3d R = predicted_rotation(x, s, chain.R_base_ee);
        const Eigen::Vector3d r = so3::log(Eigen::Matrix3d(R_measured[m++].transpose() * R));
        D = rot_weight[k] * so3::right_jacobian_inverse(r) * R.transpose();
        J.block<3, 3>(rr, 6 * s) = D * so3::left_jacobian(Eigen::Vector3d(x.segment<3>(6 * s)));
        if (layout.rot_at >= 0)
          J.block<3, 3>(rr, layout.rot_at) = rot_weight[k] * so3::right_jacobian_inverse(r) * so3::right_jacobian(tool_rotation(x));
      }
      const Eigen::Matrix3d D_out = D * R_station * chain.R_bend;  // a turn of the rigid chain, world frame
      J.block<3, 3>(row, 6 * s) = so3::rotate_jacobian(Eigen::Vector3d(x.segment<3>(6 * s)), T0[static_cast<std::size_t>(s)] * p);
      J.block<3, 3>(row, 6 * s + 3).setIdentity();
      if (layout.tool) J.block<3, 3>(row, layout.tool_at) = R_station * chain.R_base_ee;
      // Everything before the bending moves the rigid point; the bending turns carry that motion.
      const Eigen::Matrix3d R_out = R_station * chain.R_bend;
      const Eigen::Vector3d& p_rigid = chain.p_rigid;
      for (std::size_t l = 0; bent >= 0 && l < bend.size(); ++l) {
        const int j = bent + static_cast<int>(l);
        J.block<3, 1>(row, j) = R_station * chain.R_before_bend[l] *
                                (so3::rotate_jacobian(Eigen::Vector3d(x[j] * bend_v[k][l]), chain.w[l]) * bend_v[k][l] + bend_d[k][l]);
        if (rr >= 0)
          J.block<3, 1>(rr, j) = D * R_station * chain.R_before_bend[l] * so3::left_jacobian(Eigen::Vector3d(x[j] * bend_v[k][l])) *
                                 bend_v[k][l];
      }
      // The base's turn exp(ω) moves the rigid chain about the base origin: a change dω turns it by
      // R_turned Jr(ω) dω (world frame).
      for (int a = 0; base >= 0 && a < 2; ++a) {
        const Eigen::Vector3d dtheta = chain.R_base_turned * so3::right_jacobian(base_turn(x, k)) * Eigen::Vector3d::Unit(a) *
                                       base_moment[k][a];
        J.block<3, 1>(row, base + a) = R_out * dtheta.cross(p_rigid - robot.T_world_base.translation());
        if (rr >= 0) J.block<3, 1>(rr, base + a) = D_out * dtheta;
      }
      for (int i = 0; i < n; ++i) {
        const auto ui = static_cast<std::size_t>(i);
        const Eigen::Vector3d dp_dq = R_out * (robot.joints[ui].kind == JointKind::prismatic
                                                   ? chain.axis[ui]
                                                   : Eigen::Vector3d(chain.axis[ui].cross(p_rigid - chain.on_axis[ui])));
        // The same joint motion turns the measured frame about the joint's axis (a prismatic joint
        // does not turn it).
        const Eigen::Vector3d dr_dq = robot.joints[ui].kind == JointKind::prismatic ? Eigen::Vector3d::Zero()
                                                                                    : Eigen::Vector3d(D_out * chain.axis[ui]);
        const auto joint_column = [&](int col, double gain) {
          J.block<3, 1>(row, col) = gain * dp_dq;
          if (rr >= 0) J.block<3, 1>(rr, col) = gain * dr_dq;
        };
        if (off >= 0) joint_column(off + i, 1.0);
        for (int f = 0; flag >= 0 && f < layout.flags; ++f)
          if (obs[k].flags[static_cast<std::size_t>(f)]) joint_column(flag + f * n + i, 1.0);
        if (comp >= 0) joint_column(comp + i, -G[k][i]);
        if (back >= 0) joint_column(back + i, -sign(G[k][i]));
        if (geo >= 0) {
          const Eigen::Matrix3d R_before = chain.before_error[ui].linear();
          J.block<3, 3>(row, geo + 6 * i) = R_out * R_before;
          // p in the frame after E_i's rotation, before its translation is added back: w with
          // p = before * (t + exp(ω) w).
          const Eigen::Vector3d w = chain.after_error[ui].inverse() * p_rigid;
          J.block<3, 3>(row, geo + 6 * i + 3) = R_out * R_before * so3::rotate_jacobian(Eigen::Vector3d(x.segment<3>(geo + 6 * i + 3)), w);
          if (rr >= 0)
            J.block<3, 3>(rr, geo + 6 * i + 3) = D_out * chain.after_error[ui].linear() *
                                                 so3::right_jacobian(Eigen::Vector3d(x.segment<3>(geo + 6 * i + 3)));
        }
      }
    }
    J /= kResidualScale_m;
  }

  /// ∂r/∂x by central differences.
  void jacobian_central_differences(const Eigen::VectorXd& x, Eigen::MatrixXd& J, const Eigen::VectorXd& scale) const {
    constexpr double h = 1e-3;
    Eigen::VectorXd rp, rm, xp = x;
    J.resize(residual_rows, x.size());
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      xp[j] = x[j] + h * scale[j];
      residual(xp, rp);
      xp[j] = x[j] - h * scale[j];
      residual(xp, rm);
      xp[j] = x[j];
      J.col(j) = (rp - rm) / (2.0 * h * scale[j]);
    }
  }

  std::vector<std::string> names(std::vector<std::string>& units, std::vector<std::string>& parts) const {
    std::vector<std::string> n;
    const char* axes[] = {"rx", "ry", "rz", "x", "y", "z"};
    for (int s = 0; s < layout.stations; ++s)
      for (int a = 0; a < 6; ++a) {
        n.push_back("station " + station_names[static_cast<std::size_t>(s)] + " " + axes[a]);
        units.push_back(a < 3 ? "rad" : "m");
        parts.push_back("station");
      }
    if (layout.tool)
      for (int a = 3; a < 6; ++a) {
        n.push_back(std::string("tool ") + axes[a]);
        units.push_back("m");
        parts.push_back("tool");
      }
    if (layout.rot_at >= 0)
      for (int a = 0; a < 3; ++a) {
        n.push_back(std::string("tool ") + axes[a]);
        units.push_back("rad");
        parts.push_back("tool");
      }
    for (const auto& [c, at] : layout.blocks) {
      if (c == PointCandidate::link_bending) {
        for (const int b : bend) {
          const auto ub = static_cast<std::size_t>(b);
          n.push_back("bending " + (ub < robot.body_links.size() ? robot.body_links[ub] : "body " + std::to_string(b)));
          units.push_back("1/(N·m²)");
          parts.push_back(to_string(c));
        }
        continue;
      }
      if (c == PointCandidate::base_compliance) {
        const std::string base = robot.body_links.empty() || robot.body_links[0].empty() ? "base" : robot.body_links[0];
        for (const char* a : {"rx", "ry"}) {
          n.push_back("compliance " + base + " " + a);
          units.push_back("rad/(N·m)");
          parts.push_back(to_string(c));
        }
        continue;
      }
      if (c == PointCandidate::flag_offsets) {
        for (const auto& flag : flag_names)
          for (const auto& row : robot.joints) {
            n.push_back("offset " + row.name + " when " + flag);
            units.push_back(row.kind == JointKind::prismatic ? "m" : "rad");
            parts.push_back(to_string(c));
          }
        continue;
      }
      for (int i = 0; i < (c == PointCandidate::geometric ? layout.dof : layout.block_size(c)); ++i) {
        const auto& row = robot.joints[static_cast<std::size_t>(i)];
        const bool prismatic = row.kind == JointKind::prismatic;
        if (c == PointCandidate::geometric) {
          for (int a = 0; a < 6; ++a) {
            n.push_back("frame " + row.name + " " + (a < 3 ? std::string("d") + axes[a + 3] : std::string(axes[a - 3])));
            units.push_back(a < 3 ? "m" : "rad");
            parts.push_back(to_string(c));
          }
          continue;
        }
        const char* what = c == PointCandidate::joint_offsets      ? "offset "
                           : c == PointCandidate::joint_compliance ? "compliance "
                                                                   : "backlash ";
        n.push_back(what + row.name);
        units.push_back(c == PointCandidate::joint_compliance ? (prismatic ? "m/N" : "rad/(N·m)") : prismatic ? "m" : "rad");
        parts.push_back(to_string(c));
      }
    }
    return n;
  }
};

/// Rigid transform T minimising Σ |T b_i − m_i|² (Kabsch/Horn, by SVD).
Eigen::Isometry3d kabsch(const std::vector<Eigen::Vector3d>& b, const std::vector<Eigen::Vector3d>& m, int station) {
  if (b.size() < 3)
    throw std::invalid_argument("station " + std::to_string(station) + ": at least 3 postures are needed to place its frame");
  Eigen::Vector3d cb = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < b.size(); ++i) cb += b[i], cm += m[i];
  cb /= static_cast<double>(b.size());
  cm /= static_cast<double>(b.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < b.size(); ++i) H += (b[i] - cb) * (m[i] - cm).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (svd.singularValues()[1] < 1e-12 * std::max(1.0, svd.singularValues()[0]))
    throw std::invalid_argument("station " + std::to_string(station) + ": its postures' points lie on a line: its frame is not determined");
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixV() * D * svd.matrixU().transpose();
  T.translation() = cm - T.linear() * cb;
  return T;
}

std::vector<Eigen::Isometry3d> closed_form_stations(const Problem& P, const Eigen::VectorXd& x) {
  std::vector<Eigen::Isometry3d> T;
  for (int s = 0; s < P.layout.stations; ++s) {
    std::vector<Eigen::Vector3d> b, m;
    for (std::size_t k = 0; k < P.obs.size(); ++k)
      if (P.obs[k].station == s) b.push_back(P.point_base(x, k)), m.push_back(P.obs[k].p_station_m);
    T.push_back(kabsch(b, m, s));
  }
  return T;
}

/// Rank, condition, covariance and undetermined combinations of the fit at x.
void analyse(const Problem& P, const Eigen::VectorXd& x, const Eigen::VectorXd& r, const PointFitOptions& opt, PointFit& out) {
  const Eigen::VectorXd scale = P.scale();
  Eigen::MatrixXd J;
  P.jacobian(x, J, scale);
  // Full V: its columns beyond the rank are the null directions (more of them when J has fewer
  // rows than columns).
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const double tol = opt.rank_tolerance * (sv.size() ? sv[0] : 0.0);
  int rank = 0;
  while (rank < sv.size() && sv[rank] > tol) ++rank;
  out.rank = rank;
  out.parameters_total = static_cast<int>(x.size());
  out.condition = rank > 0 ? sv[0] / sv[rank - 1] : 0.0;
  const Eigen::Index m = r.size();
  const double ssr = (r * kResidualScale_m).squaredNorm();
  out.sigma_m = m > rank ? std::sqrt(ssr / static_cast<double>(m - rank)) : std::numeric_limits<double>::quiet_NaN();

  std::vector<std::string> units, parts;
  const auto names = P.names(units, parts);
  const Eigen::MatrixXd Vnull = svd.matrixV().rightCols(x.size() - rank);
  const Eigen::MatrixXd Vr = svd.matrixV().leftCols(rank);
  const Eigen::VectorXd inv2 = sv.head(rank).cwiseInverse().cwiseAbs2();
  const double s2 = std::pow(out.sigma_m / kResidualScale_m, 2);
  out.parameters.clear();
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    PointParameter p;
    p.name = names[static_cast<std::size_t>(j)];
    p.unit = units[static_cast<std::size_t>(j)];
    p.part = parts[static_cast<std::size_t>(j)];
    p.value = x[j];
    p.identifiable = Vnull.cols() == 0 || Vnull.row(j).norm() < 1e-2;
    const double var_u = s2 * (Vr.row(j).cwiseAbs2().transpose().cwiseProduct(inv2)).sum();
    p.std = p.identifiable ? std::sqrt(var_u) * scale[j] : std::numeric_limits<double>::quiet_NaN();
    out.parameters.push_back(p);
  }
  out.undetermined.clear();
  for (Eigen::Index c = 0; c < Vnull.cols(); ++c) {
    Eigen::VectorXd v = Vnull.col(c);
    Eigen::Index big = 0;
    v.cwiseAbs().maxCoeff(&big);
    if (v[big] < 0) v = -v;
    Undetermined u;
    std::vector<Eigen::Index> order(static_cast<std::size_t>(v.size()));
    for (Eigen::Index i = 0; i < v.size(); ++i) order[static_cast<std::size_t>(i)] = i;
    std::sort(order.begin(), order.end(), [&](auto a, auto b) { return std::abs(v[a]) > std::abs(v[b]); });
    std::ostringstream t;
    t.precision(2);
    for (const auto i : order) {
      if (std::abs(v[i]) < 0.1 || u.terms.size() >= 6) break;
      u.terms.emplace_back(names[static_cast<std::size_t>(i)], v[i]);
      t << (u.terms.size() == 1 ? (v[i] < 0 ? "−" : "") : (v[i] < 0 ? " − " : " + ")) << std::fixed << std::abs(v[i]) << " "
        << names[static_cast<std::size_t>(i)];
    }
    u.text = t.str();
    out.undetermined.push_back(u);
  }
  // Station frames as the fit leaves them: the parameters' values are the perturbations of the
  // closed-form start; report each station's frame as a whole.
  out.T_station_base.clear();
  for (int s = 0; s < P.layout.stations; ++s) {
    const Eigen::Isometry3d T = P.station(x, s);
    out.T_station_base.push_back(T);
    const Eigen::Vector3d rv = so3::log(Eigen::Matrix3d(T.linear()));
    for (int a = 0; a < 3; ++a) out.parameters[static_cast<std::size_t>(6 * s + a)].value = rv[a];
    for (int a = 0; a < 3; ++a) out.parameters[static_cast<std::size_t>(6 * s + 3 + a)].value = T.translation()[a];
  }
  out.tool_point_ee_m = P.tool(x);
}

struct Solved {
  Eigen::VectorXd x, r;
  bool converged = false;
};

Solved solve(const Problem& P, const Eigen::VectorXd& x0, const std::vector<bool>& fixed) {
  solver::Problem sp;
  const Eigen::VectorXd scale = P.scale();
  sp.scale = scale;
  sp.fixed = fixed;
  sp.residual = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    P.residual(x, r);
    return r.squaredNorm();
  };
  sp.jacobian = [&](const Eigen::VectorXd& x, const Eigen::VectorXd&, Eigen::MatrixXd& J) { P.jacobian(x, J, scale); };
  solver::Options o;
  o.max_iterations = 100;
  o.relative_decrease = 1e-12;
  const auto res = solver::levenberg_marquardt(sp, x0, o);
  return {res.x, res.r, res.converged};
}

Eigen::VectorXd start(const Problem& P, const PointFitOptions& opt) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(P.layout.size);
  if (P.layout.tool) x.segment<3>(P.layout.tool_at) = opt.tool_point_start_ee_m;
  return x;
}

/// The start in closed form: each station's frame (Kabsch on the nominal points) and, when
/// orientations are fitted, the measured frame on the tool as the rotation closest (chordal
/// mean, by SVD) to what each posture's measurement implies.
Eigen::VectorXd initial(Problem& P, const PointFitOptions& opt) {
  Eigen::VectorXd x = start(P, opt);
  P.T0 = closed_form_stations(P, x);
  if (P.layout.rot_at < 0) return x;
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  std::size_t m = 0;
  for (std::size_t k = 0; k < P.obs.size(); ++k) {
    if (P.rot_row[k] < 0) continue;
    Problem::Chain chain;
    P.point_base(x, k, &chain);
    sum += (P.station(x, P.obs[k].station).linear() * chain.R_base_ee).transpose() * P.R_measured[m++];
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  x.segment<3>(P.layout.rot_at) = so3::log(Eigen::Matrix3d(svd.matrixU() * D * svd.matrixV().transpose()));
  return x;
}

void finish(const Problem& P, const Solved& s, const PointFitOptions& opt, PointFit& out) {
  analyse(P, s.x, s.r, opt, out);
  out.converged = s.converged;
  out.residual_m = s.r * kResidualScale_m;
  out.tool_rotation_ee_rad = P.tool_rotation(s.x);
  out.orientations = 0;
  double ss_rad = 0.0;
  out.max_rad = 0.0;
  for (std::size_t k = 0; k < P.obs.size(); ++k) {
    if (P.rot_row[k] < 0) continue;
    const double a = out.residual_m.segment<3>(P.rot_row[k]).norm() / P.rot_weight[k];
    ++out.orientations;
    ss_rad += a * a;
    out.max_rad = std::max(out.max_rad, a);
  }
  out.rms_rad = out.orientations ? std::sqrt(ss_rad / out.orientations) : 0.0;
  const auto n = static_cast<Eigen::Index>(P.obs.size());
  double ss = 0.0;
  out.max_m = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double d = out.residual_m.segment<3>(3 * k).norm();
    ss += d * d;
    out.max_m = std::max(out.max_m, d);
  }
  out.rms_m = n ? std::sqrt(ss / static_cast<double>(n)) : 0.0;
}

}  // namespace

const char* to_string(PointCandidate c) {
  switch (c) {
    case PointCandidate::rigid: return "rigid";
    case PointCandidate::joint_offsets: return "joint_offsets";
    case PointCandidate::joint_compliance: return "joint_compliance";
    case PointCandidate::backlash: return "backlash";
    case PointCandidate::geometric: return "geometric";
    case PointCandidate::flag_offsets: return "flag_offsets";
    case PointCandidate::link_bending: return "link_bending";
    case PointCandidate::measured_tilt: return "measured_tilt";
    case PointCandidate::base_compliance: return "base_compliance";
  }
  return "rigid";
}

std::string to_string(const PointModel& m) {
  std::string s;
  for (const auto c : m)
    if (c != PointCandidate::rigid) s += (s.empty() ? "" : "+") + std::string(to_string(c));
  return s.empty() ? "rigid" : s;
}

PointCandidate point_candidate_from_string(const std::string& name) {
  std::string all = "rigid";
  for (const auto c : point_candidates()) {
    if (name == to_string(c)) return c;
    all += std::string(", ") + to_string(c);
  }
  if (name == "rigid") return PointCandidate::rigid;
  throw std::invalid_argument("unknown candidate '" + name + "' (" + all + ")");
}

std::vector<PointCandidate> point_candidates() {
  return {PointCandidate::joint_offsets, PointCandidate::joint_compliance, PointCandidate::backlash,      PointCandidate::geometric,
          PointCandidate::flag_offsets,  PointCandidate::link_bending,     PointCandidate::measured_tilt, PointCandidate::base_compliance};
}

bool needs_inertials(PointCandidate c) {
  return c == PointCandidate::joint_compliance || c == PointCandidate::backlash || c == PointCandidate::link_bending ||
         c == PointCandidate::base_compliance;
}

namespace {
/// Candidates whose parameters are physical only when ≥ 0 (compliances, 1/EI, half-plays).
bool signed_candidate(PointCandidate c) {
  return c == PointCandidate::joint_compliance || c == PointCandidate::backlash || c == PointCandidate::link_bending ||
         c == PointCandidate::base_compliance;
}

std::vector<int> bending_bodies(const SerialRobot& robot, const std::vector<PointObservation>& obs, const PointFitOptions& opt) {
  const int n = robot.dof();
  if (!opt.bending_bodies.empty()) {
    for (const int b : opt.bending_bodies)
      if (b < 1 || b > n)
        throw std::invalid_argument("bending body " + std::to_string(b) + ": the chain's moving bodies are 1.." + std::to_string(n));
    return opt.bending_bodies;
  }
  std::vector<int> out;
  if (obs.empty()) return out;
  const ChainPoses poses = forward(robot, obs.front().q);
  for (int b = 1; b <= n; ++b) {
    const auto ub = static_cast<std::size_t>(b);
    const Eigen::Vector3d e = b < n ? poses.p_world_joint_m[ub] : poses.T_world_body[ub].translation();
    if ((e - poses.p_world_joint_m[ub - 1]).norm() >= PointFitOptions::kMinBendingSpan_m) out.push_back(b);
  }
  return out;
}
}  // namespace

bool usable(PointCandidate c, const SerialRobot& robot, const std::vector<PointObservation>& obs, const PointFitOptions& opt,
            std::string* why) {
  const auto no = [&](const std::string& reason) {
    if (why) *why = std::string(to_string(c)) + ": " + reason;
    return false;
  };
  if (needs_inertials(c) && robot.inertials.size() != static_cast<std::size_t>(robot.dof()) + 1)
    return no("needs the robot's inertials (a URDF with <inertial> elements)");
  if (c == PointCandidate::flag_offsets) {
    if (opt.flag_names.empty()) return no("needs flag columns (flag_<name>)");
    for (std::size_t k = 0; k < obs.size(); ++k)
      if (obs[k].flags.size() != opt.flag_names.size())
        return no("posture " + std::to_string(k + 1) + " has " + std::to_string(obs[k].flags.size()) + " flags, the run names " +
                  std::to_string(opt.flag_names.size()));
    for (std::size_t f = 0; f < opt.flag_names.size(); ++f) {
      const auto set = std::count_if(obs.begin(), obs.end(), [&](const PointObservation& p) { return p.flags[f]; });
      if (set == 0 || set == static_cast<std::ptrdiff_t>(obs.size()))
        return no("flag " + opt.flag_names[f] + " is set on " + (set == 0 ? "no posture" : "every posture") +
                  ": its offsets are not told from the joints' own");
    }
  }
  if (c == PointCandidate::measured_tilt) {
    if (opt.tilts.empty()) return no("needs measured tilt columns (tilt_<link>_rx|ry)");
    for (const auto& t : opt.tilts)
      if (t.body < 0 || t.body > robot.dof() || (t.axis != 0 && t.axis != 1))
        return no("tilt column " + t.name + ": body " + std::to_string(t.body) + " axis " + std::to_string(t.axis) + " (bodies 0.." +
                  std::to_string(robot.dof()) + ", axes 0 = x, 1 = y)");
    for (std::size_t k = 0; k < obs.size(); ++k)
      if (obs[k].tilts_rad.size() != opt.tilts.size())
        return no("posture " + std::to_string(k + 1) + " has " + std::to_string(obs[k].tilts_rad.size()) + " tilts, the run names " +
                  std::to_string(opt.tilts.size()));
  }
  if (c == PointCandidate::base_compliance) {
    // A measured tilt of the base is the rotation this candidate would fit: measured_tilt applies it.
    bool about[2] = {false, false};
    for (const auto& t : opt.tilts)
      if (t.body == 0 && (t.axis == 0 || t.axis == 1)) about[t.axis] = true;
    if (about[0] && about[1]) return no("the run measures the base's tilt (tilt columns): measured_tilt applies it");
  }
  if (c == PointCandidate::link_bending && bending_bodies(robot, obs, opt).empty())
    return no("no link spans " + std::to_string(PointFitOptions::kMinBendingSpan_m) + " m or more");
  return true;
}

bool contains(PointCandidate big, PointCandidate small) {
  // A joint offset is a rotation of the joint's frame about the joint's own axis, one of the six
  // directions of that frame's geometric error.
  return big == PointCandidate::geometric && small == PointCandidate::joint_offsets;
}

PointFit fit_points(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                    const PointFitOptions& opt) {
  Problem P(robot, obs, stations, model, opt);
  Eigen::VectorXd x = initial(P, opt);
  const Solved s = solve(P, x, {});
  PointFit out;
  out.model = model;
  finish(P, s, opt, out);
  return out;
}

PointFit identifiability(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                         const PointFitOptions& opt) {
  Problem P(robot, obs, stations, model, opt);
  const Eigen::VectorXd x = initial(P, opt);
  Eigen::VectorXd r;
  P.residual(x, r);
  PointFit out;
  out.model = model;
  finish(P, {x, r, false}, opt, out);
  return out;
}

namespace {

/// How the postures are held out: whole stations when there are several, else postures in
/// interleaved folds.
struct FoldScheme {
  std::string name;
  int count = 0;
  bool by_station = false;
};

FoldScheme fold_scheme(std::size_t postures, int stations, int folds) {
  if (stations >= 2) return {"leave one station out", stations, true};
  const int n = static_cast<int>(postures);
  const int k = folds <= 0 ? n : std::min(folds, n);
  return {k == n ? "leave one posture out" : std::to_string(k) + "-fold over postures", k, false};
}

/// Fold f of the scheme: fits the model without the fold's postures and writes their held-out
/// distances (only theirs) into error_m.
void held_out_fold(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model,
                   const FoldScheme& scheme, int f, const PointFitOptions& opt, Eigen::VectorXd& error_m) {
  if (scheme.by_station) {
    // Train on the other stations (renumbered), then place the held-out station's frame on its
    // own postures with everything else held.
    std::vector<PointObservation> train, test;
    std::vector<std::size_t> test_index;
    for (std::size_t k = 0; k < obs.size(); ++k) {
      if (obs[k].station == f) {
        test.push_back(obs[k]);
        test.back().station = 0;
        test_index.push_back(k);
      } else {
        train.push_back(obs[k]);
        if (train.back().station > f) --train.back().station;
      }
    }
    Problem Ptr(robot, train, stations - 1, model, opt);
    Eigen::VectorXd x = initial(Ptr, opt);
    const Solved fit = solve(Ptr, x, {});
    Problem Pte(robot, test, 1, model, opt);
    Eigen::VectorXd xt(Pte.layout.size);
    xt.head<6>().setZero();
    xt.tail(xt.size() - 6) = fit.x.tail(fit.x.size() - 6 * (stations - 1));
    Pte.T0 = closed_form_stations(Pte, xt);
    std::vector<bool> fixed(static_cast<std::size_t>(xt.size()), true);
    for (int i = 0; i < 6; ++i) fixed[static_cast<std::size_t>(i)] = false;
    const Solved placed = solve(Pte, xt, fixed);
    for (std::size_t i = 0; i < test.size(); ++i)
      error_m[static_cast<Eigen::Index>(test_index[i])] = placed.r.segment<3>(3 * static_cast<Eigen::Index>(i)).norm() * kResidualScale_m;
    return;
  }
  std::vector<PointObservation> train;
  for (std::size_t k = 0; k < obs.size(); ++k)
    if (static_cast<int>(k) % scheme.count != f) train.push_back(obs[k]);
  Problem Ptr(robot, train, 1, model, opt);
  Eigen::VectorXd x = initial(Ptr, opt);
  const Solved fit = solve(Ptr, x, {});
  Problem Pall(robot, obs, 1, model, opt);
  Pall.T0 = Ptr.T0;
  Eigen::VectorXd r;
  Pall.residual(fit.x, r);
  for (std::size_t k = 0; k < obs.size(); ++k)
    if (static_cast<int>(k) % scheme.count == f)
      error_m[static_cast<Eigen::Index>(k)] = r.segment<3>(3 * static_cast<Eigen::Index>(k)).norm() * kResidualScale_m;
}

HeldOut empty_held_out(const PointModel& model, const FoldScheme& scheme, std::size_t postures) {
  HeldOut h;
  h.model = model;
  h.scheme = scheme.name;
  h.error_m = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(postures));
  return h;
}

void finish_held_out(HeldOut& h) {
  h.rms_m = std::sqrt(h.error_m.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, h.error_m.size())));
}

/// Held-out errors and identifiability of several models at once: every (model, fold) fit and
/// every model's rank is one task, the models with the most parameters first so that the longest
/// tasks do not come last.
struct Evaluated {
  HeldOut held_out;
  int parameters = 0, rank = 0;
};
std::vector<Evaluated> evaluate(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations,
                                const std::vector<PointModel>& models, int folds, const PointFitOptions& opt) {
  const FoldScheme scheme = fold_scheme(obs.size(), stations, folds);
  std::vector<Evaluated> out;
  for (const auto& m : models) out.push_back({empty_held_out(m, scheme, obs.size()), 0, 0});
  struct Task {
    std::size_t model;
    int fold;  ///< -1: the model's identifiability
    int size;
  };
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const int size = Layout(stations, robot.dof(), opt.fit_tool_point, models[i]).size;
    for (int f = -1; f < scheme.count; ++f) tasks.push_back({i, f, size});
  }
  std::stable_sort(tasks.begin(), tasks.end(), [](const Task& a, const Task& b) { return a.size > b.size; });
  PointFitOptions inner = opt;
  inner.threads = 1;
  parallel::run_tasks(tasks.size(), parallel::worker_count(tasks.size(), opt.threads), [&](std::size_t t, std::size_t) {
    const Task& task = tasks[t];
    Evaluated& e = out[task.model];
    if (task.fold >= 0) {
      held_out_fold(robot, obs, stations, models[task.model], scheme, task.fold, inner, e.held_out.error_m);
      return;
    }
    const PointFit f = identifiability(robot, obs, stations, models[task.model], inner);
    e.parameters = f.parameters_total;
    e.rank = f.rank;
  });
  for (auto& e : out) finish_held_out(e.held_out);
  return out;
}

/// Fits to every posture, kept by model: the physical-validity checks, the noise tests and the
/// verdict ask for the same fits, which are computed once, side by side where they can be.
class FitCache {
 public:
  FitCache(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointFitOptions& opt)
      : robot_(robot), obs_(obs), stations_(stations), opt_(opt) {}

  /// Fits the models not yet fitted, one task each, the largest first.
  void prefit(std::vector<PointModel> models) {
    std::sort(models.begin(), models.end());
    models.erase(std::unique(models.begin(), models.end()), models.end());
    models.erase(std::remove_if(models.begin(), models.end(), [&](const PointModel& m) { return fits_.count(m) > 0; }), models.end());
    const auto size = [&](const PointModel& m) { return Layout(stations_, robot_.dof(), opt_.fit_tool_point, m).size; };
    std::stable_sort(models.begin(), models.end(), [&](const PointModel& a, const PointModel& b) { return size(a) > size(b); });
    std::vector<PointFit> out(models.size());
    PointFitOptions inner = opt_;
    inner.threads = 1;
    parallel::run_tasks(models.size(), parallel::worker_count(models.size(), opt_.threads),
                        [&](std::size_t t, std::size_t) { out[t] = fit_points(robot_, obs_, stations_, models[t], inner); });
    for (std::size_t t = 0; t < models.size(); ++t) fits_.emplace(models[t], std::move(out[t]));
  }

  const PointFit& operator()(const PointModel& m) {
    if (!fits_.count(m)) prefit({m});
    return fits_.at(m);
  }

 private:
  const SerialRobot& robot_;
  const std::vector<PointObservation>& obs_;
  int stations_;
  PointFitOptions opt_;
  std::map<PointModel, PointFit> fits_;
};

}  // namespace

std::pair<Eigen::MatrixXd, Eigen::MatrixXd> detail::point_jacobians(const SerialRobot& robot, const std::vector<PointObservation>& obs,
                                                                    int stations, const PointModel& model, const Eigen::VectorXd& dx,
                                                                    const PointFitOptions& opt) {
  Problem P(robot, obs, stations, model, opt);
  Eigen::VectorXd x = initial(P, opt);
  if (dx.size() != x.size())
    throw std::invalid_argument("point_jacobians: dx has " + std::to_string(dx.size()) + " entries, the model " + std::to_string(x.size()));
  x += dx;
  const Eigen::VectorXd scale = P.scale();
  std::pair<Eigen::MatrixXd, Eigen::MatrixXd> J;
  P.analytic = true;
  P.jacobian(x, J.first, scale);
  P.analytic = false;
  P.jacobian(x, J.second, scale);
  return J;
}

HeldOut held_out_error(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, const PointModel& model, int folds,
                       const PointFitOptions& opt) {
  const FoldScheme scheme = fold_scheme(obs.size(), stations, folds);
  HeldOut h = empty_held_out(model, scheme, obs.size());
  PointFitOptions inner = opt;
  inner.threads = 1;
  parallel::run_tasks(static_cast<std::size_t>(scheme.count), parallel::worker_count(static_cast<std::size_t>(scheme.count), opt.threads),
                      [&](std::size_t f, std::size_t) {
                        held_out_fold(robot, obs, stations, model, scheme, static_cast<int>(f), inner, h.error_m);
                      });
  finish_held_out(h);
  return h;
}

namespace {

/// 99 % quantile of χ² with `dof` degrees of freedom (Wilson-Hilferty: within 0.5 % from 3 dof on).
double chi_square_quantile_99(double dof) {
  if (dof <= 0) return 0.0;
  constexpr double z99 = 2.3263478740408408;
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z99 * std::sqrt(a), 3);
}

/// Σ|r_k|²/σ_k² of a fit to every posture, with the postures' stated noise; the rotation rows
/// (weighted by σ_m/σ_rad, so over σ_m they are over σ_rad) follow in posture order.
double chi_square(const PointFit& f, const std::vector<PointObservation>& obs) {
  double chi2 = 0.0;
  Eigen::Index rot = 3 * static_cast<Eigen::Index>(obs.size());
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const double s2 = obs[k].sigma_m * obs[k].sigma_m;
    chi2 += f.residual_m.segment<3>(3 * static_cast<Eigen::Index>(k)).squaredNorm() / s2;
    if (f.orientations > 0 && obs[k].r_station_rad) chi2 += f.residual_m.segment<3>(rot).squaredNorm() / s2, rot += 3;
  }
  return chi2;
}

/// Paired z of the squared held-out errors: how surely `b` predicts better than `a`.
double paired_z(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd d = a.cwiseAbs2() - b.cwiseAbs2();
  const double n = static_cast<double>(d.size());
  if (n < 2) return 0.0;
  const double mean = d.mean();
  const double sd = std::sqrt((d.array() - mean).square().sum() / (n - 1.0));
  return sd > 0 ? mean / (sd / std::sqrt(n)) : (mean > 0 ? std::numeric_limits<double>::infinity() : 0.0);
}

}  // namespace

namespace {

/// The links whose bending is physical: fits link_bending to every posture and drops, one at a
/// time, the link whose 1/EI is furthest below zero beyond its 95 % interval (the elastostatic
/// paper's model reduction: a parameter the data make unphysical leaves the model). Writes the
/// links kept into opt.bending_bodies and why each other was dropped into `dropped`.
void reduce_bending_links(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations, PointFitOptions& opt,
                          std::vector<std::string>& dropped) {
  opt.bending_bodies = bending_bodies(robot, obs, opt);
  while (!opt.bending_bodies.empty()) {
    const PointFit f = fit_points(robot, obs, stations, {PointCandidate::link_bending}, opt);
    std::size_t worst = 0;
    double worst_z = -1.96;
    const PointParameter* worst_p = nullptr;
    std::size_t l = 0;
    for (const auto& p : f.parameters) {
      if (p.part != to_string(PointCandidate::link_bending)) continue;
      if (p.identifiable && p.std > 0 && p.value / p.std < worst_z) worst_z = p.value / p.std, worst = l, worst_p = &p;
      ++l;
    }
    if (!worst_p) return;
    std::ostringstream why;
    why.precision(3);
    why << worst_p->name << " dropped from link_bending: 1/EI = " << worst_p->value << " ± " << 1.96 * worst_p->std << " " << worst_p->unit
        << " (95 %), below zero";
    dropped.push_back(why.str());
    opt.bending_bodies.erase(opt.bending_bodies.begin() + static_cast<std::ptrdiff_t>(worst));
  }
}

}  // namespace

PointComparison compare_point_candidates(const SerialRobot& robot, const std::vector<PointObservation>& obs, int stations,
                                         const std::vector<PointCandidate>& candidates, int folds, const PointFitOptions& options) {
  // The rules, fixed before any data (docs/calibration.md, "Point calibration"): a candidate is a
  // cause when it lowers the held-out error by at least kMinGain with a paired z of at least kMinZ;
  // the cause is the one with the largest gain; a second cause is a candidate added to the cause
  // that passes the same rules against the cause alone.
  constexpr double kMinGain = 0.05, kMinZ = 2.0;
  PointComparison c;
  auto row = [&](const Evaluated& e, const HeldOut& base) {
    PointComparison::Row r;
    r.model = e.held_out.model;
    r.held_out = e.held_out;
    r.gain = base.rms_m > 0 ? 1.0 - r.held_out.rms_m / base.rms_m : 0.0;
    r.z = paired_z(base.error_m, r.held_out.error_m);
    r.parameters = e.parameters;
    r.rank = e.rank;
    return r;
  };
  PointFitOptions opt = options;
  std::vector<PointModel> singles{{}};
  for (const auto cand : candidates) {
    if (cand == PointCandidate::rigid || !usable(cand, robot, obs, opt)) continue;
    if (cand == PointCandidate::link_bending) {
      reduce_bending_links(robot, obs, stations, opt, c.bending_dropped);
      c.bending_bodies = opt.bending_bodies;
      if (opt.bending_bodies.empty()) continue;
    }
    singles.push_back({cand});
  }
  FitCache fit(robot, obs, stations, opt);
  const auto first = evaluate(robot, obs, stations, singles, folds, opt);
  c.rigid = first[0].held_out;
  for (std::size_t i = 1; i < first.size(); ++i) c.rows.push_back(row(first[i], c.rigid));
  const std::size_t single_rows = c.rows.size();
  // The rigid model against the stated noise: with it, `none` is a finding (the residual is the
  // noise) rather than the absence of a better candidate.
  c.noise.stated = !obs.empty() && std::all_of(obs.begin(), obs.end(), [&](const PointObservation& p) {
    return p.sigma_m > 0.0 && (!opt.fit_orientation || !p.r_station_rad || p.sigma_rad > 0.0);
  });
  // The fits the checks below need, side by side: the rigid model's (the noise test) and each
  // model that passes the rules and has a signed part (physical validity).
  const auto passes = [&](const PointComparison::Row& r) { return r.gain >= kMinGain && r.z >= kMinZ; };
  const auto signed_model = [](const PointModel& m) { return std::any_of(m.begin(), m.end(), signed_candidate); };
  {
    std::vector<PointModel> need;
    for (const auto& r : c.rows)
      if (passes(r) && signed_model(r.model)) need.push_back(r.model);
    if (c.noise.stated) need.push_back({});
    fit.prefit(need);
  }
  if (c.noise.stated) {
    const PointFit& rigid = fit({});
    c.noise.chi2 = chi_square(rigid, obs);
    c.noise.dof = static_cast<double>(rigid.residual_m.size() - rigid.rank);
    c.noise.bound_99 = chi_square_quantile_99(c.noise.dof);
    c.noise.within = c.noise.chi2 <= c.noise.bound_99;
    c.noise.rms_over_sigma = c.noise.dof > 0 ? std::sqrt(c.noise.chi2 / c.noise.dof) : 0.0;
  }
  // Physical validity of the models that pass the rules, on their fit to every posture: a
  // compliance, 1/EI or half-play below zero by more than its 95 % interval is not a cause.
  const auto physical_model = [&](const PointModel& m) {
    if (!signed_model(m)) return true;
    const PointFit& f = fit(m);
    for (const auto& p : f.parameters) {
      const bool positive = std::any_of(m.begin(), m.end(),
                                        [&](PointCandidate k) { return signed_candidate(k) && p.part == to_string(k); });
      if (!positive || !p.identifiable || !(p.value < -1.96 * p.std)) continue;
      std::ostringstream why;
      why.precision(3);
      why << to_string(m) << ": " << p.name << " = " << p.value << " ± " << 1.96 * p.std << " " << p.unit << " (95 %), below zero";
      c.not_physical.push_back(why.str());
      return false;
    }
    return true;
  };
  std::vector<bool> physical(c.rows.size(), true);
  for (std::size_t i = 0; i < c.rows.size(); ++i)
    if (c.rows[i].gain >= kMinGain && c.rows[i].z >= kMinZ) physical[i] = physical_model(c.rows[i].model);
  double best = -1.0;
  for (std::size_t i = 0; i < c.rows.size(); ++i)
    if (physical[i] && c.rows[i].gain >= kMinGain && c.rows[i].z >= kMinZ && c.rows[i].gain > best)
      best = c.rows[i].gain, c.cause = static_cast<int>(i);
  std::ostringstream v;
  v.precision(3);
  if (c.noise.stated && c.noise.within) {
    // Within the noise nothing is named, even a candidate that passes the held-out rules (with
    // many postures a gain far below the noise can be significant).
    c.cause = -1;
    c.kind = "none";
    v << "none: the rigid model is within the stated measurement noise (χ² " << c.noise.chi2 << " on " << c.noise.dof
      << " degrees of freedom, 99 % bound " << c.noise.bound_99 << "; residual " << c.noise.rms_over_sigma << " σ)";
    c.verdict = v.str();
    return c;
  }
  if (c.cause < 0) {
    if (c.noise.stated) {
      c.kind = "unexplained";
      v << "unexplained: no candidate predicts the held-out postures better than the rigid model by the rules (gain ≥ 5 %, z ≥ 2), yet "
           "the rigid model's residual is "
        << c.noise.rms_over_sigma << " times the stated noise (χ² " << c.noise.chi2 << " on " << c.noise.dof
        << " degrees of freedom, 99 % bound " << c.noise.bound_99 << "): an effect outside the candidates, or a noise stated too small";
    } else {
      v << "none: no candidate predicts the held-out postures better than the rigid model by the rules (gain ≥ 5 %, z ≥ 2): rigid model's "
           "held-out error "
        << c.rigid.rms_m * 1e3 << " mm RMS (no measurement noise stated to test it against)";
    }
    for (const auto& n : c.not_physical) v << "; not physical: " << n;
    for (const auto& d : c.bending_dropped) v << "; " << d;
    c.verdict = v.str();
    return c;
  }
  c.kind = "cause";
  const auto cause = c.rows[static_cast<std::size_t>(c.cause)];
  std::vector<PointModel> pairs;
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const PointCandidate other = c.rows[i].model.front();
    // A candidate nested in the cause (or containing it) adds nothing a second cause could be.
    if (static_cast<int>(i) == c.cause || contains(cause.model.front(), other) || contains(other, cause.model.front())) continue;
    PointModel m = cause.model;
    m.push_back(other);
    pairs.push_back(m);
  }
  const std::size_t pair_rows = c.rows.size();
  for (const auto& e : evaluate(robot, obs, stations, pairs, folds, opt)) c.rows.push_back(row(e, cause.held_out));
  // The second cause is the passing pair with the largest gain that is physical, checked from the
  // largest gain down. (Fitting the next pairs on the idle core meanwhile was tried: a pair with
  // geometric took up to five times as long as the one that decided, and was waited for.)
  std::vector<std::size_t> by_gain;
  for (std::size_t i = pair_rows; i < c.rows.size(); ++i)
    if (passes(c.rows[i])) by_gain.push_back(i);
  std::stable_sort(by_gain.begin(), by_gain.end(), [&](std::size_t a, std::size_t b) { return c.rows[a].gain > c.rows[b].gain; });
  for (std::size_t k = 0; k < by_gain.size() && c.second_cause < 0; ++k)
    if (physical_model(c.rows[by_gain[k]].model)) c.second_cause = static_cast<int>(by_gain[k]);
  // Parsimony between nested candidates: a named candidate that contains a smaller one (geometric
  // contains joint_offsets) gives way to it unless it predicts better than the smaller one by the
  // same rules. Otherwise hidden joint offsets would be named "geometric", which explains them as
  // well with five more parameters per joint.
  const PointModel named = c.rows[static_cast<std::size_t>(c.second_cause >= 0 ? c.second_cause : c.cause)].model;
  for (std::size_t at = 0; at < named.size() && c.reduced.empty(); ++at) {
    for (const auto small : point_candidates()) {
      if (!contains(named[at], small)) continue;
      PointModel reduced = named;
      reduced[at] = small;
      const Evaluated e = evaluate(robot, obs, stations, {reduced}, folds, opt).front();
      const HeldOut& big = c.rows[static_cast<std::size_t>(c.second_cause >= 0 ? c.second_cause : c.cause)].held_out;
      const double gain = e.held_out.rms_m > 0 ? 1.0 - big.rms_m / e.held_out.rms_m : 0.0;
      const double z = paired_z(e.held_out.error_m, big.error_m);
      std::ostringstream why;
      why.precision(3);
      why << to_string(small) << " named, not " << to_string(named[at]) << ", which contains it and does not predict better by the rules ("
          << e.held_out.rms_m * 1e3 << " → " << big.rms_m * 1e3 << " mm, gain " << gain * 100 << " %, z " << z << ")";
      if (gain >= kMinGain && z >= kMinZ) break;
      c.reduced = why.str();
      // The smaller candidate takes the larger's place: as the cause (its single row), or as the
      // second cause (the reduced pair's row against the cause alone).
      int single = -1;
      for (std::size_t i = 0; i < single_rows; ++i)
        if (c.rows[i].model == PointModel{small}) single = static_cast<int>(i);
      if (at == 0 && single < 0) {
        c.rows.push_back(row(evaluate(robot, obs, stations, {{small}}, folds, opt).front(), c.rigid));
        single = static_cast<int>(c.rows.size() - 1);
      }
      if (at == 0) c.cause = single;
      if (named.size() == 1) {
        c.second_cause = -1;
        break;
      }
      c.rows.push_back(row(e, c.rows[static_cast<std::size_t>(c.cause)].held_out));
      const auto& r = c.rows.back();
      c.second_cause = r.gain >= kMinGain && r.z >= kMinZ ? static_cast<int>(c.rows.size() - 1) : -1;
      break;
    }
  }
  const auto& named_cause = c.rows[static_cast<std::size_t>(c.cause)];
  // What these postures cannot tell from the cause: single candidates that pass the rules too and
  // that the cause does not beat by them (nested ones are the parsimony rule's).
  for (std::size_t i = 0; i < single_rows; ++i) {
    const auto& r = c.rows[i];
    if (static_cast<int>(i) == c.cause || !physical[i] || !(r.gain >= kMinGain && r.z >= kMinZ)) continue;
    if (contains(r.model.front(), named_cause.model.front()) || contains(named_cause.model.front(), r.model.front())) continue;
    const double gain = r.held_out.rms_m > 0 ? 1.0 - named_cause.held_out.rms_m / r.held_out.rms_m : 0.0;
    if (!(gain >= kMinGain && paired_z(r.held_out.error_m, named_cause.held_out.error_m) >= kMinZ))
      c.alternatives.push_back(static_cast<int>(i));
  }
  v << "cause: " << to_string(named_cause.model) << " (held-out error " << c.rigid.rms_m * 1e3 << " → " << named_cause.held_out.rms_m * 1e3
    << " mm RMS, gain " << named_cause.gain * 100 << " %, z " << named_cause.z << ")";
  if (!c.alternatives.empty()) {
    v << "; not told apart from";
    for (std::size_t a = 0; a < c.alternatives.size(); ++a) {
      const auto& r = c.rows[static_cast<std::size_t>(c.alternatives[a])];
      v << (a ? "," : "") << " " << to_string(r.model) << " (→ " << r.held_out.rms_m * 1e3 << " mm)";
    }
    v << " by these postures: each explains them as well within the rules";
  }
  if (c.second_cause >= 0) {
    const auto& s = c.rows[static_cast<std::size_t>(c.second_cause)];
    v << "; second: " << to_string(s.model) << " (→ " << s.held_out.rms_m * 1e3 << " mm, a further " << s.gain * 100 << " %)";
  }
  if (!c.reduced.empty()) v << "; " << c.reduced;
  for (const auto& n : c.not_physical) v << "; not physical: " << n;
  for (const auto& d : c.bending_dropped) v << "; " << d;
  if (c.noise.stated) {
    // Whether what was named explains the run down to the noise, or something else remains.
    const PointModel& m = c.rows[static_cast<std::size_t>(c.second_cause >= 0 ? c.second_cause : c.cause)].model;
    const PointFit& f = fit(m);
    c.noise.after_chi2 = chi_square(f, obs);
    c.noise.after_dof = static_cast<double>(f.residual_m.size() - f.rank);
    c.noise.after_bound_99 = chi_square_quantile_99(c.noise.after_dof);
    c.noise.after_within = c.noise.after_chi2 <= c.noise.after_bound_99;
    c.noise.after_rms_over_sigma = c.noise.after_dof > 0 ? std::sqrt(c.noise.after_chi2 / c.noise.after_dof) : 0.0;
    if (c.noise.after_within) v << "; the named model leaves the stated noise (" << c.noise.after_rms_over_sigma << " σ)";
    else
      v << "; yet the named model still leaves " << c.noise.after_rms_over_sigma << " σ (χ² " << c.noise.after_chi2 << " on "
        << c.noise.after_dof << " degrees of freedom, 99 % bound " << c.noise.after_bound_99 << "): something else remains";
  }
  c.verdict = v.str();
  return c;
}

}  // namespace hil::calibration
