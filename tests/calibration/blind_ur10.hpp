#pragma once
// What both series of the serial-robot blind suite share (rules in docs/calibration.md, "The blind
// suite"): the UR10 as hil reads it, the suite's fixed sizes and its uniform draws. The draws'
// order is each series' own; these helpers consume the random stream exactly as written.
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <hil/calibration/point_calibration.hpp>
#include <hil/format/urdf.hpp>
#include <hil/models/stiffness.hpp>

#include "serial_truth.hpp"

namespace hil::test::blind {

inline const std::string kUr10 = std::string(HIL_SOURCE_DIR) + "/examples/robots/ur10.urdf";
inline constexpr int kDraws = 20;
inline constexpr int kMinRight = 18;
inline constexpr int kPostures = 72;
inline constexpr int kStations = 3;
inline constexpr double kNoise_m = 50e-6;

inline const calibration::SerialRobot& ur10() {
  static const calibration::SerialRobot r = models::to_serial_robot(format::read_urdf_robot(kUr10, "base_link", "wrist_3_link"));
  return r;
}

inline double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
/// A magnitude uniform in [lo, hi], then a random sign.
inline double signed_uniform(std::mt19937& rng, double lo, double hi) {
  const double m = uniform(rng, lo, hi);
  return std::uniform_int_distribution<int>(0, 1)(rng) ? m : -m;
}

/// The joints' ranges the postures are drawn from (rad): the shoulder lift keeps the arm above
/// the base, the elbow away from its stops.
inline const std::vector<std::pair<double, double>> kRange = {{-3.0, 3.0}, {-2.6, -0.5}, {-2.5, 2.5},
                                                              {-3.0, 3.0}, {-3.0, 3.0},  {-3.0, 3.0}};

/// A draw's UR10 truth before its effect: base_link → wrist_3_link, the stations' frames (up to 3 rad,
/// 3 m), the tool point in [−5, 5] × [−5, 5] × [5, 15] cm, the point noise; drawn in that order.
inline serial::Truth ur10_truth(std::mt19937& rng) {
  serial::Truth t;
  t.urdf = kUr10;
  t.base = "base_link";
  t.tip = "wrist_3_link";
  for (int s = 0; s < kStations; ++s) t.T_station_base.push_back(serial::random_station(rng, 3.0, 3.0));
  t.tool_point_m = Eigen::Vector3d(uniform(rng, -0.05, 0.05), uniform(rng, -0.05, 0.05), uniform(rng, 0.05, 0.15));
  t.noise_m = kNoise_m;
  return t;
}

}  // namespace hil::test::blind
