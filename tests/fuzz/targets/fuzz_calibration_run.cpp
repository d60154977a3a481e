// Calibration-run reader (formats/format/src/calibration_run.cpp) on arbitrary text, for a fixed
// four-joint robot (a1 revolute in [-1, 1], a2 prismatic in [0, 0.5], a3 revolute, a4 a mimic of
// a1: -2 a1 + 0.1, in [-1.5, 1.5]) whose chain has the links base, l1, l2, l3, l4. Every posture
// must come out complete and within the limits; a4, when its column is absent, as its coupling says.
#include "fuzz_common.hpp"
#include <cmath>
#include <hil/error/error.hpp>
#include <hil/format/calibration_run.hpp>

namespace {
hil::format::RobotSpec robot() {
  hil::format::RobotSpec r;
  r.name = "fuzz";
  r.convention = hil::format::DhConvention::urdf;
  for (int i = 1; i <= 4; ++i) {
    hil::format::DhJointSpec j;
    j.name = "a" + std::to_string(i);
    r.joints.push_back(j);
  }
  r.joints[0].lower = -1.0, r.joints[0].upper = 1.0;
  r.joints[1].type = hil::format::JointType::prismatic, r.joints[1].lower = 0.0, r.joints[1].upper = 0.5;
  r.joints[3].mimic_of = "a1", r.joints[3].mimic_multiplier = -2.0, r.joints[3].mimic_offset = 0.1;
  r.joints[3].lower = -1.5, r.joints[3].upper = 1.5;
  r.body_links = {"base", "l1", "l2", "l3", "l4"};
  return r;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto r = robot();
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_calibration_run", [&] {
    const auto run = hil::format::parse_calibration_run(text, "fuzz.csv", r);
    if (run.postures.empty() || run.stations.empty()) hil::fuzz::violated("fuzz_calibration_run", "a run without postures or stations");
    for (const auto& p : run.postures) {
      if (p.q.size() != 4 || !p.p_measured_m.allFinite()) hil::fuzz::violated("fuzz_calibration_run", "an incomplete posture");
      if (text.find("a4") == std::string::npos && p.q[3] != -2.0 * p.q[0] + 0.1)
        hil::fuzz::violated("fuzz_calibration_run", "a mimic joint not derived from its master");
      for (int j = 0; j < 4; ++j)
        if (p.q[j] < r.joints[static_cast<std::size_t>(j)].lower - 1e-6 || p.q[j] > r.joints[static_cast<std::size_t>(j)].upper + 1e-6)
          hil::fuzz::violated("fuzz_calibration_run", "a joint value outside its limits");
      if (p.flags.size() != run.flag_names.size() || p.tilts_rad.size() != run.tilts.size())
        hil::fuzz::violated("fuzz_calibration_run", "flags or tilts missing from a posture");
      if (run.has_sigma && !(p.sigma_m > 0)) hil::fuzz::violated("fuzz_calibration_run", "a sigma that is not > 0");
    }
  });
  return 0;
}
