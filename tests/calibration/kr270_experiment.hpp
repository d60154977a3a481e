#pragma once
// The simulated stiffness experiment several calibration tests start from: the KR-270-like robot's
// VJM model, its example compliance, an experiment plan's configurations with 10 µm / 10 µrad noise,
// and the physical reduction (M1-M3) of the pipeline's default options.
#include <vector>

#include <hil/calibration/experiment.hpp>
#include <hil/calibration/identification.hpp>
#include <hil/calibration/reduction.hpp>
#include <hil/calibration/vjm.hpp>

namespace hil::test {

struct Kr270Experiment {
  calibration::VjmModel model{calibration::kr270_like()};
  calibration::NoiseModel noise{10e-6, 10e-6};
  calibration::PipelineOptions options;
  std::vector<calibration::Measurement> data;
  calibration::ParameterSet physical;  ///< M1-M3's parameters
};

inline Kr270Experiment kr270_experiment(int configurations, double moment_nm, unsigned seed) {
  Kr270Experiment e;
  calibration::ExperimentPlan plan;
  plan.configurations = configurations;
  plan.moment_nm = moment_nm;
  plan.seed = seed;
  e.data = calibration::simulate(e.model, calibration::example_compliance(e.model), plan, e.noise);
  std::vector<calibration::ReductionLine> lines;
  e.physical = calibration::physical_reduction(e.model, e.options, lines);
  return e;
}

}  // namespace hil::test
