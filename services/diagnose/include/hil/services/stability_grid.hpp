#pragma once
// The cross-validation settings `hil diagnose --stability` diagnoses a run under (issue 32, item
// 5): pure parsing, apart from the diagnosis so that it can be fuzzed alone.
#include <string>
#include <utility>
#include <vector>

namespace hil::services::diagnose {

/// The bounds of one setting, as `--folds` and `--cv-offsets` take them.
constexpr int kMinFolds = 2, kMaxFolds = 1000, kMaxCvOffsets = 64;

/// The (folds, cv offsets) settings `hil diagnose --stability` tries: 5, 8 and 10 blocks, each on
/// one grid and pooled over 2 and 8 grid offsets.
std::vector<std::pair<int, int>> default_stability_grid();

/// "5:1,8:2" -> {(5, 1), (8, 2)}: decimal digits only (no sign, no spaces), every setting within
/// the bounds above. \throws std::invalid_argument naming the bad item and its position.
std::vector<std::pair<int, int>> parse_stability_grid(const std::string& text);

}  // namespace hil::services::diagnose
