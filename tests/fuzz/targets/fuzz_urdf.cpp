// URDF reader (formats/format/src/urdf.cpp): parse_urdf_robot on arbitrary text, the chain from
// base_link to tool0 (the names the seeds use). What urdfdom and KDL return must come out as a
// robot whose joints have unit axes and ordered limits and one inertial per body, or a FormatError.
#include "fuzz_common.hpp"
#include <cmath>
#include <hil/error/error.hpp>
#include <hil/format/urdf.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_urdf", [&] {
    const auto r = hil::format::parse_urdf_robot(text, "fuzz.urdf", "base_link", "tool0");
    if (r.joints.empty()) hil::fuzz::violated("fuzz_urdf", "a robot without moving joints");
    if (r.inertials.size() != r.joints.size() + 1 || r.body_links.size() != r.joints.size() + 1)
      hil::fuzz::violated("fuzz_urdf", "one inertial and one link per body");
    for (const auto& j : r.joints) {
      if (!(j.lower < j.upper)) hil::fuzz::violated("fuzz_urdf", "joint limits out of order");
      if (!(std::abs(j.axis.norm() - 1.0) < 1e-9)) hil::fuzz::violated("fuzz_urdf", "a joint axis that is not a unit vector");
    }
  });
  return 0;
}
