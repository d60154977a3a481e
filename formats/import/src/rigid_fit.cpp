#include <hil/import/rigid_fit.hpp>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include <hil/so3/so3.hpp>

namespace hil::import {

double planarity_ratio(const Eigen::Matrix3Xd& points) {
  if (points.cols() < 3) return 0.0;
  const Eigen::Matrix3Xd c = points.colwise() - points.rowwise().mean();
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(c);
  const auto s = svd.singularValues();
  return s(0) > 0.0 ? s(1) / s(0) : 0.0;
}

std::optional<RigidFit> fit_rigid_body(const Eigen::Matrix3Xd& body_m, const Eigen::Matrix3Xd& world_m, const std::vector<bool>& seen,
                                       std::size_t min_markers, FitFailure* failure) {
  const auto n_all = static_cast<std::size_t>(body_m.cols());
  std::size_t n = 0;
  for (std::size_t i = 0; i < n_all; ++i) n += seen[i] ? 1 : 0;
  auto fail = [&](std::string why) -> std::optional<RigidFit> {
    if (failure) failure->reason = std::move(why);
    return std::nullopt;
  };
  if (n < std::max<std::size_t>(min_markers, 3)) return fail(fmt::format("{} of {} markers seen", n, n_all));
  Eigen::Matrix3Xd B(3, static_cast<Eigen::Index>(n)), W(3, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0, k = 0; i < n_all; ++i) {
    if (!seen[i]) continue;
    B.col(static_cast<Eigen::Index>(k)) = body_m.col(static_cast<Eigen::Index>(i));
    W.col(static_cast<Eigen::Index>(k)) = world_m.col(static_cast<Eigen::Index>(i));
    ++k;
  }
  // Nearly collinear markers leave the rotation about their line undetermined.
  if (planarity_ratio(B) < 1e-3) return fail("seen markers are (nearly) collinear");
  // Least-squares rotation and translation (Kabsch/Umeyama, a rotation, never a reflection).
  const Eigen::Matrix4d T = Eigen::umeyama(B, W, false);
  RigidFit f;
  f.R_world_body = T.topLeftCorner<3, 3>();
  f.p_world_body_m = T.topRightCorner<3, 1>();
  const Eigen::Matrix3Xd r = (f.R_world_body * B).colwise() + f.p_world_body_m - W;
  f.residual_rms_m = std::sqrt(r.colwise().squaredNorm().sum() / static_cast<double>(n));
  f.markers_used = n;
  return f;
}

Twist twist_from_poses(const PoseTrack& track, double window_s) {
  const std::size_t n = track.t_s.size();
  Twist out;
  out.v_world_m_per_s.assign(n, Eigen::Vector3d::Zero());
  out.w_world_rad_per_s.assign(n, Eigen::Vector3d::Zero());
  if (n < 2) return out;
  const double half = window_s / 2.0;
  std::size_t lo = 0, hi = 0;  // window [lo, hi)
  for (std::size_t i = 0; i < n; ++i) {
    const double ti = track.t_s[i];
    while (track.t_s[lo] < ti - half) ++lo;
    if (hi < i + 1) hi = i + 1;
    while (hi < n && track.t_s[hi] <= ti + half) ++hi;
    std::size_t a = lo, b = hi;
    if (b - a < 2) {  // only the sample itself: use its neighbours
      a = i > 0 ? i - 1 : i;
      b = std::min(n, i + 2);
    }
    const Eigen::Matrix3d Ri_T = track.q_world_body[i].toRotationMatrix().transpose();
    double t_mean = 0.0;
    Eigen::Vector3d p_mean = Eigen::Vector3d::Zero(), phi_mean = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> phi(b - a);
    for (std::size_t j = a; j < b; ++j) {
      phi[j - a] = so3::log(track.q_world_body[j].toRotationMatrix() * Ri_T);
      t_mean += track.t_s[j] - ti;
      p_mean += track.p_world_body_m[j];
      phi_mean += phi[j - a];
    }
    const double m = static_cast<double>(b - a);
    t_mean /= m;
    p_mean /= m;
    phi_mean /= m;
    double stt = 0.0;
    Eigen::Vector3d stp = Eigen::Vector3d::Zero(), stphi = Eigen::Vector3d::Zero();
    for (std::size_t j = a; j < b; ++j) {
      const double dt = track.t_s[j] - ti - t_mean;
      stt += dt * dt;
      stp += dt * (track.p_world_body_m[j] - p_mean);
      stphi += dt * (phi[j - a] - phi_mean);
    }
    out.v_world_m_per_s[i] = stp / stt;
    out.w_world_rad_per_s[i] = stphi / stt;
  }
  return out;
}

}  // namespace hil::import
