#pragma once
/// \file The deflection family: when the rig has no contact geometry, the quantity the model must
/// predict is how the ee (a robot's end effector, or a mobile base standing on the plate) moves away
/// from its rest pose under the measured load. The nominal model is rigid: a constant pose.
///
///   y_k = [p_k - p_0 ; log(R_k R_0ᵀ)]  (world axes; m, rad)
///   nominal           y = d (6 constants)
///   robot_compliance  y = d + C w(t)        C symmetric 6x6 (21 entries, linear; rank-revealing LS
///                                           keeps the identifiable part), w the load the body puts
///                                           on its support (= the plate's wrench) about its rest
///                                           position, world axes
///   time_offset       y = d + C w(t - τ)    the deflection lags the load by τ (with compliance)
#include <set>
#include <string>
#include <vector>

#include "hil/contact_id/model.hpp"
#include "hil/diagnose/engine.hpp"

namespace hil::diagnose {

const std::vector<std::string>& deflection_extensions();

struct DeflectionData {
  Observations obs;             ///< deflection: dx dy dz (m), rx ry rz (rad)
  Eigen::MatrixXd load;         ///< N x 6: the plate's force (N) and moment (N m) about p_0, world axes
  std::vector<double> speed_m_per_s;
};

/// From poses (ee in world) and plate wrenches (fp frame, about the fp origin).
/// \throws std::runtime_error on too few samples or non-finite values.
DeflectionData make_deflection_data(const std::vector<double>& t_s, const std::vector<contact_id::Kinematics>& kin,
                                    const std::vector<Eigen::Matrix<double, 6, 1>>& w_fp, const Eigen::Isometry3d& T_world_fp);

class DeflectionFamily : public Model {
 public:
  DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions);
  std::string name() const override;
  std::vector<Param> linear() const override { return linear_; }
  std::vector<Param> nonlinear() const override { return nonlinear_; }
  std::vector<Eigen::VectorXd> starts() const override;
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A) const override;
  /// C must be symmetric positive semi-definite (within two standard deviations).
  std::string check(const Fit& f) const override;

 private:
  const DeflectionData& d_;
  std::set<std::string> ext_;
  std::vector<Param> linear_, nonlinear_;
  bool compliance_ = false;
  int i_tau_ = -1;
};

}  // namespace hil::diagnose
