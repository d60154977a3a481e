#pragma once
/// \file Simulated stiffness experiments (for tests, benchmarks and experiment planning) and
/// physically plausible compliance sets.
#include <cstdint>
#include <vector>

#include <hil/calibration/observation.hpp>

namespace hil::calibration {

struct ExperimentPlan {
  int configurations = 50;   ///< random configurations, uniform within the joint limits
  int loads_per_config = 1;  ///< random loads per configuration
  double force_n = 1000.0;   ///< magnitude of the force of each load (random direction)
  double moment_nm = 0.0;    ///< magnitude of the moment of each load (random direction); 0 = pure force
  MeasurementKind kind = MeasurementKind::pose6;
  std::vector<Eigen::Vector3d> p_ee_marker_m;  ///< markers in the tool frame (kind == markers)
  std::uint64_t seed = 1;
};

/// Measurements of `truth` under random configurations and loads, plus Gaussian noise
/// (N(0, σ²) per measured axis; σ = 0 gives exact data).
std::vector<Measurement> simulate(const VjmModel& model, const ComplianceSet& truth, const ExperimentPlan& plan, const NoiseModel& noise);

/// Tip compliance (6x6, frame at the tip, x along the beam) of a cantilever of length L with axial
/// rigidity EA (N), bending rigidities EI_y, EI_z (N·m²) and torsional rigidity GJ (N·m²):
/// Euler-Bernoulli, the pattern of the beam template (eq. 12). Symmetric positive definite.
Matrix6d beam_compliance(double length_m, double EA_n, double EIy_nm2, double EIz_nm2, double GJ_nm2);

/// A plausible compliance set for a heavy industrial robot: steel-tube links (beam_compliance with
/// each link's length, 0.2 m for links of zero length) scaled by `link_scale`, joint compliances
/// like the paper's Table II (0.3-3.3 µrad/(N·m)) scaled by `joint_scale`.
ComplianceSet example_compliance(const VjmModel& model, double link_scale = 1.0, double joint_scale = 1.0);

}  // namespace hil::calibration
