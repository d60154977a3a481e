#pragma once
/// \file The stiffness-table family: a stiffness experiment (loaded configurations and the measured
/// tool displacements, docs/calibration.md) diagnosed against the model labs usually start from,
/// joint compliances only (the VJM model of the stiffness paper with rigid links). 6 rows per table
/// row: the tool displacement [dx dy dz rx ry rz] (world; m, rad) under the tool-point load w
/// (world; N, N m). With M_p = J_s E_p J_sᵀ the Cartesian compliance of parameter p at the row's
/// configuration (J_s the spring's Jacobian, E_p its entry):
///
///   nominal          t = Σ_j c_j M_j w'                c_j: joint compliances J1..Jn (linear)
///   link_compliance  + Σ_r l_r (Σ_p v_rp M_p) w'      the link springs' symmetric entries, reduced
///                                                     to the directions v_r this table identifies
///                                                     beside the joints (SVD; linear)
///   sensor_bias      + b                              constant offsets of the displacement
///                                                     measurement (6, linear)
///   sensor_gain      w' = diag(1 + g) w               the load cell's scale error per component
///                                                     (5: the largest component is the reference)
///   load_offset      w' = w + w0                      an unmodelled constant load (a tool's weight,
///                                                     a cable), world, at the tool point (6)
#include <set>
#include <string>
#include <vector>

#include <hil/calibration/observation.hpp>
#include <hil/diagnose/engine.hpp>

namespace hil::diagnose {

const std::vector<std::string>& stiffness_extensions();

struct StiffnessData {
  Observations obs;                               ///< t_s: the row number (blocked folds hold out neighbouring rows)
  std::vector<Eigen::Matrix<double, 6, 1>> load;  ///< per row: w (world; N, N m)
  /// Per row, per compliance parameter (joints first, then the link directions): M_p (6x6).
  std::vector<std::vector<Eigen::Matrix<double, 6, 6>>> joint_ops, link_ops;
  std::vector<std::string> joint_names;  ///< "J1".."Jn" (rad/(N m))
  std::vector<int> config;               ///< per row: the configuration id
  int gain_reference = 2;                ///< the load component with the largest rms (its gain is 1)
};

/// From a stiffness table (pose6 measurements) of `model`'s robot.
/// \throws std::runtime_error on too few rows, a measurement that is not a 6-D tool displacement or
/// non-finite values (naming the row).
StiffnessData make_stiffness_data(const calibration::VjmModel& model, const std::vector<calibration::Measurement>& rows);

class StiffnessFamily : public ModelFamily {
 public:
  /// \throws std::invalid_argument on an extension that does not apply to a stiffness table.
  StiffnessFamily(const StiffnessData& d, std::set<std::string> extensions);
  std::string name() const override;
  std::vector<Param> linear() const override { return linear_; }
  std::vector<Param> nonlinear() const override { return nonlinear_; }
  using ModelFamily::design;
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override;
  /// Joint compliances must not be negative (beyond two standard deviations).
  std::string check(const Fit& f) const override;

 private:
  const StiffnessData& d_;
  std::set<std::string> ext_;
  std::vector<Param> linear_, nonlinear_;
  bool links_ = false;
  int j_bias_ = -1, i_gain_ = -1, i_offset_ = -1;
};

}  // namespace hil::diagnose
