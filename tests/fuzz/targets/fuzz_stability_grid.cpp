// `hil diagnose --stability-grid` (services/diagnose/src/stability_grid.cpp): the command line's
// text. A grid that parses holds only settings within the bounds, one per comma-separated item.
#include "fuzz_common.hpp"
#include <algorithm>
#include <stdexcept>
#include <hil/services/stability_grid.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  namespace d = hil::services::diagnose;
  hil::fuzz::answers_or<std::invalid_argument>("fuzz_stability_grid", [&] {
    const auto grid = d::parse_stability_grid(text);
    if (grid.size() != static_cast<std::size_t>(std::count(text.begin(), text.end(), ',')) + 1)
      hil::fuzz::violated("fuzz_stability_grid", "one setting per item");
    for (const auto& [folds, offsets] : grid)
      if (folds < d::kMinFolds || folds > d::kMaxFolds || offsets < 1 || offsets > d::kMaxCvOffsets)
        hil::fuzz::violated("fuzz_stability_grid", "a setting outside the bounds");
  });
  return 0;
}
