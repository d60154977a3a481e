// Hidden-truth reader of `hil contact simulate --truth` (formats/models): parse_truth on arbitrary
// text against the shipped press bench rig (its nominal contact model is what an absent value falls
// back to). An answer is a Truth whose model passes its own check, or a FormatError.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/format/rig.hpp>
#include <hil/models/contact.hpp>

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const hil::format::RigSpec rig = hil::format::load_rig(HIL_FUZZ_RIG);
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_contact_truth", [&] {
    const auto t = hil::models::parse_truth(text, "fuzz.truth.yaml", rig);
    if (!(t.model.K > 0) || !(t.model.mu >= 0) || !std::isfinite(t.model.K) || !std::isfinite(t.model.mu))
      hil::fuzz::violated("fuzz_contact_truth", "an accepted truth has K > 0 and mu >= 0, finite");
  });
  return 0;
}
