#include <hil/contact_id/online.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace hil::contact_id {

OnlineEstimator::OnlineEstimator(Scene scene, double v_tm, double force_scale_n, double moment_scale_nm)
    : scene_(std::move(scene)), v_tm_(v_tm), wf_(1.0 / force_scale_n), wm_(1.0 / moment_scale_nm) {
  if (!(force_scale_n > 0.0 && moment_scale_nm > 0.0)) throw std::invalid_argument("online estimation needs F_max > 0 and M_max > 0");
}

OnlineEstimate OnlineEstimator::update(const Measurement& m) {
  OnlineEstimate out;
  out.t_s = m.t_s;
  out.global = last_;
  if (!(m.kin.T_world_ee.matrix().allFinite() && m.kin.v_world_ee.allFinite() && m.kin.w_world_ee.allFinite() && m.w_fp.allFinite()))
    return out;  // skipped: non-finite sample
  mindist(scene_, m.kin, scene_.design(), v_tm_, contacts_, ws_);
  out.contacts = static_cast<int>(contacts_.size());
  if (contacts_.empty()) return out;
  const Eigen::Isometry3d T = body_pose(scene_.bodies[0], m.kin.T_world_ee);
  Regressor A = regressor(contacts_, T);
  Vector6d b = plate_to_object1(m.w_fp, scene_.T_world_fp, T);
  A.topRows<3>() *= wf_;
  A.bottomRows<3>() *= wm_;
  b.head<3>() *= wf_;
  b.tail<3>() *= wm_;
  if (A.col(0).norm() > 0.0) {
    const auto e = solve_theta(A, b);
    out.instantaneous_valid = true;
    out.K_instant = e.K;
    out.mu_instant = e.mu_identifiable ? e.mu : std::numeric_limits<double>::quiet_NaN();
  }
  rls_.add(A, b);
  last_ = rls_.estimate();
  out.global = last_;
  return out;
}

}  // namespace hil::contact_id
