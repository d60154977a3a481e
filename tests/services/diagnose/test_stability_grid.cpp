// `hil diagnose --stability-grid`: the settings parsed as written, anything else refused with the
// item and its position named.
#include <gtest/gtest.h>

#include <hil/services/stability_grid.hpp>

namespace hil::services::diagnose {
namespace {

using Grid = std::vector<std::pair<int, int>>;

TEST(StabilityGrid, ParsesSettingsInTheirOrder) {
  EXPECT_EQ(parse_stability_grid("5:1"), (Grid{{5, 1}}));
  EXPECT_EQ(parse_stability_grid("5:1,8:2,10:64"), (Grid{{5, 1}, {8, 2}, {10, 64}}));
  EXPECT_EQ(parse_stability_grid("1000:1,2:1"), (Grid{{1000, 1}, {2, 1}}));
  EXPECT_EQ(parse_stability_grid("05:08"), (Grid{{5, 8}}));
  EXPECT_EQ(default_stability_grid().size(), 9U);
  for (const auto& [f, o] : default_stability_grid()) {
    EXPECT_GE(f, kMinFolds);
    EXPECT_LE(o, kMaxCvOffsets);
  }
}

TEST(StabilityGrid, RefusesWhatIsNotASettingAndNamesIt) {
  const auto refused = [](const std::string& text, const std::string& named) {
    try {
      parse_stability_grid(text);
      ADD_FAILURE() << "'" << text << "' was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  };
  refused("", "setting 1 ''");
  refused("5", "setting 1 '5'");
  refused("5:1,", "setting 2 ''");
  refused("5:1,,8:2", "setting 2 ''");
  refused("1:1", "'1:1'");        // one fold holds nothing out
  refused("1001:1", "'1001:1'");  // beyond --folds' bound
  refused("5:0", "'5:0'");        // no grid
  refused("5:65", "'5:65'");      // beyond --cv-offsets' bound
  refused("5:1,8:-2", "setting 2 '8:-2'");
  refused(" 5:1", "' 5:1'");
  refused("+5:1", "'+5:1'");
  refused("5:1:2", "'5:1:2'");
  refused("99999999999:1", "99999999999");
  refused("5:1x", "'5:1x'");
}

}  // namespace
}  // namespace hil::services::diagnose
