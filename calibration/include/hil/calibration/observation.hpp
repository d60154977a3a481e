#pragma once
/// \file Compliance parameters, measurements and the observation matrix A(q, w | π) (paper eq. 3-5).
///
/// A parameter is one entry (or, once symmetrised, one symmetric pair of entries) of one spring's
/// compliance matrix: k_s = Σ_p π_p E_p with E_p = e_r e_cᵀ (plain) or e_r e_cᵀ + e_c e_rᵀ (symmetric,
/// r ≠ c). Its column of the observation matrix for a tool-point wrench w is J_s E_p J_sᵀ w, so that
/// the tool displacement is t = A(q, w | π) π exactly (the oracle the tests check).
#include <string>
#include <vector>

#include <hil/calibration/vjm.hpp>

namespace hil::calibration {

struct Parameter {
  int spring = 0;  ///< index into VjmModel::springs()
  int row = 0;     ///< 0-based entry of the spring's compliance matrix
  int col = 0;
  bool symmetric = false;  ///< one parameter for (row, col) and (col, row)
  std::string name;        ///< "L2.k26" (1-based entries), "J3.k"
  bool diagonal() const { return row == col; }
};
using ParameterSet = std::vector<Parameter>;

/// Name of an entry: "L2.k26" for link springs (1-based row and column), "J3.k" for joint springs.
std::string parameter_name(const VjmModel& model, int spring, int row, int col);

/// The complete model: every entry of every spring, 36 per link and 1 per joint (258 for 6R).
ParameterSet complete_parameters(const VjmModel& model);
/// Parameter whose name is `name`, or -1.
int find_parameter(const ParameterSet& set, const std::string& name);

/// k = base + Σ values_p E_p.
ComplianceSet assemble(const VjmModel& model, const ParameterSet& set, const Eigen::Ref<const Eigen::VectorXd>& values,
                       const ComplianceSet* base = nullptr);
/// Values of the parameters read from a compliance set (symmetric parameters read (row, col)).
Eigen::VectorXd parameter_values(const ParameterSet& set, const ComplianceSet& k);

/// Moves each joint's compliance into the preceding link's matrix (k_link += k_joint e eᵀ, e the joint
/// axis in the link spring frame, rotation block for revolute joints): the same deflections for every
/// configuration and load, the form the model takes after M3.
ComplianceSet aggregate_joints(const VjmModel& model, const ComplianceSet& k);

/// A(q, w | π) for the 6-D tool displacement (6 x n) from spring Jacobians already in ws.
void tool_observation(const VjmModel& model, const ParameterSet& set, const VjmWorkspace& ws, const Vector6d& w_world,
                      Eigen::Ref<Eigen::MatrixXd> A6);

enum class MeasurementKind {
  pose6,   ///< tool displacement [dx dy dz rx ry rz] (m, rad; world)
  point3,  ///< tool point displacement [dx dy dz] (m; world)
  markers  ///< displacement [dx dy dz] (m; world) of each marker fixed to the tool
};

/// One loaded configuration and what was measured.
struct Measurement {
  int config = 0;                       ///< configuration id (several loads may share one)
  Eigen::VectorXd q_rad;                ///< joint values (rad or m)
  Vector6d w_world = Vector6d::Zero();  ///< load [f (N); m (N·m)] at the tool point, world frame
  MeasurementKind kind = MeasurementKind::pose6;
  std::vector<Eigen::Vector3d> p_ee_marker_m;  ///< markers: positions in the tool frame
  Eigen::VectorXd displacement;                ///< measured values, measurement_rows() of them (may be empty for prediction)
};

/// Noise of the measuring device: standard deviation per axis (diagonal Σ, η = Σ^-1/2).
struct NoiseModel {
  double position_m = 0.0;
  double rotation_rad = 0.0;
};

int measurement_rows(const Measurement& m);
/// Axis of each measured row: 0..2 = x y z translation, 3..5 = x y z rotation (world).
void row_axes(const Measurement& m, std::vector<int>& axes);
/// S (rows x 6) such that measured = S t for the tool displacement t; T_world_ee at the configuration.
Eigen::MatrixXd projection(const Measurement& m, const Eigen::Isometry3d& T_world_ee);

/// Weighted least-squares system η A π ≈ η t for a parameter set over many measurements.
struct WeightedSystem {
  Eigen::MatrixXd A_w;           ///< m x n
  Eigen::VectorXd t_w;           ///< m
  Eigen::VectorXd sigma;         ///< per-row standard deviation (m or rad); η = 1/σ
  std::vector<int> axis;         ///< per-row axis (see row_axes)
  std::vector<int> measurement;  ///< per-row index of its measurement
};
/// \throws std::invalid_argument on shape mismatch or non-positive noise.
WeightedSystem build_system(const VjmModel& model, const ParameterSet& set, const std::vector<Measurement>& data, const NoiseModel& noise);

/// Predicted measurement (S t) for a compliance set.
Eigen::VectorXd predict(const VjmModel& model, const ComplianceSet& k, const Measurement& m);

}  // namespace hil::calibration
