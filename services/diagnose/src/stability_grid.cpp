#include <hil/services/stability_grid.hpp>

#include <stdexcept>

namespace hil::services::diagnose {

std::vector<std::pair<int, int>> default_stability_grid() {
  return {{5, 1}, {5, 2}, {5, 8}, {8, 1}, {8, 2}, {8, 8}, {10, 1}, {10, 2}, {10, 8}};
}

namespace {

/// A decimal count of at most 4 digits (the bounds are below 10,000), or -1.
int count_of(const std::string& s) {
  if (s.empty() || s.size() > 4) return -1;
  int v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return -1;
    v = 10 * v + (c - '0');
  }
  return v;
}

}  // namespace

std::vector<std::pair<int, int>> parse_stability_grid(const std::string& text) {
  std::vector<std::pair<int, int>> grid;
  std::size_t at = 0;
  for (int n = 1;; ++n) {
    const std::size_t end = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, end - at);
    const auto colon = item.find(':');
    const int folds = colon == std::string::npos ? -1 : count_of(item.substr(0, colon));
    const int offsets = colon == std::string::npos ? -1 : count_of(item.substr(colon + 1));
    if (folds < kMinFolds || folds > kMaxFolds || offsets < 1 || offsets > kMaxCvOffsets)
      throw std::invalid_argument("--stability-grid: setting " + std::to_string(n) + " '" + item + "' is not FOLDS:OFFSETS with " +
                                  std::to_string(kMinFolds) + "-" + std::to_string(kMaxFolds) + " folds and 1-" +
                                  std::to_string(kMaxCvOffsets) + " offsets");
    grid.emplace_back(folds, offsets);
    if (end == text.size()) return grid;
    at = end + 1;
  }
}

}  // namespace hil::services::diagnose
