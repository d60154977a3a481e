#pragma once
/// \file A run (`hil contact simulate`) of the rig's contact scene along a trajectory, optionally
/// with hidden effects (the diagnosis' candidates) drawn by seed. Used by the command and the demo.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace hil::services::contact {

/// -1 / empty: the rig's or the truth file's value.
struct SimulateArgs {
  std::string rig, trajectory, truth, out;
  int decimate = 1;
  double force_resolution = -1, moment_resolution = -1, position_resolution = -1, velocity_resolution = -1;
  double force_noise = -1, moment_noise = -1;
  int seed = -1;
  std::vector<std::string> inject;  ///< hidden effects (diagnosis candidates) drawn with effect_seed
  unsigned effect_seed = 1;
  std::string truth_out;
};

/// Writes the run folder (run.yaml, samples.csv, rig.yaml) and, with inject, the truth JSON.
/// \throws error::FormatError / std::runtime_error on bad input.
int simulate_run(const SimulateArgs& a);

/// The JSON schema of the truth file (hil.hidden_effects, docs/schemas/): the simulation's own
/// fields and every injectable effect's (hil::diagnose::truth_file_fields), from the effect registry.
nlohmann::json hidden_effects_schema();

}  // namespace hil::services::contact
