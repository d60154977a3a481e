// Writes a calibration run (docs/formats.md, "The calibration run") of the UR10 from the independent
// serial truth (serial_truth.cpp: KDL and the equations, no hil code), for the command-line tests of
// the candidates that read flag and tilt columns. Usage:
//   serial_truth_run OUT.csv EFFECT SEED
// EFFECT: clean | flag_offsets | base_springs. Every run has a flag column (flag_elbow_flipped, set
// with probability 1/2) and the base inclinometer's two tilt columns; 3 stations, 72 postures,
// 50 µm point noise stated as sigma_m, 10 µrad tilt noise. Magnitudes as in the blind suite's
// second series, drawn from SEED.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "serial_truth.hpp"

namespace ts = hil::test::serial;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: serial_truth_run OUT.csv clean|flag_offsets|base_springs SEED\n";
    return 2;
  }
  const std::string out = argv[1], effect = argv[2];
  std::mt19937 rng(static_cast<unsigned>(std::stoul(argv[3])));
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  ts::Truth t;
  t.urdf = std::string(HIL_SOURCE_DIR) + "/examples/robots/ur10.urdf";
  t.base = "base_link";
  t.tip = "wrist_3_link";
  for (int s = 0; s < 3; ++s) t.T_station_base.push_back(ts::random_station(rng, 3.0, 3.0));
  t.tool_point_m = Eigen::Vector3d(uniform(-0.05, 0.05), uniform(-0.05, 0.05), uniform(0.05, 0.15));
  t.noise_m = 50e-6;
  t.tilt_noise_rad = 10e-6;
  if (effect == "flag_offsets") {
    t.flag_offset_rad = Eigen::VectorXd::Zero(6);
    for (const int j : {2, 3, 4}) t.flag_offset_rad[j] = (uniform(0, 1) < 0.5 ? -1 : 1) * uniform(0.5e-3, 2e-3);
  } else if (effect == "base_springs") {
    t.base_stiffness_Nm_per_rad = uniform(2e5, 6e5);
  } else if (effect != "clean") {
    std::cerr << "serial_truth_run: unknown effect '" << effect << "'\n";
    return 2;
  }
  const std::vector<std::pair<double, double>> range = {{-3.0, 3.0}, {-2.6, -0.5}, {-2.5, 2.5}, {-3.0, 3.0}, {-3.0, 3.0}, {-3.0, 3.0}};
  const auto postures = ts::draw_postures(72, range, rng);
  std::vector<bool> flags;
  for (std::size_t k = 0; k < postures.size(); ++k) flags.push_back(std::bernoulli_distribution(0.5)(rng));
  const auto samples = ts::generate(t, postures, flags, rng);
  std::ofstream f(out);
  f << "# UR10 from the serial truth, effect " << effect << ", seed " << argv[3] << "\n";
  f << "posture,station,shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint,px,py,pz,sigma_m,"
       "flag_elbow_flipped,tilt_base_link_rx,tilt_base_link_ry\n";
  f.precision(12);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto& s = samples[k];
    f << "p" << k + 1 << ",S" << s.station + 1;
    for (int j = 0; j < 6; ++j) f << "," << s.q[j];
    f << "," << s.p_station_m.x() << "," << s.p_station_m.y() << "," << s.p_station_m.z() << ",5e-05," << (s.flag ? 1 : 0) << ","
      << s.base_tilt_rad.x() << "," << s.base_tilt_rad.y() << "\n";
  }
  return f ? 0 : 1;
}
