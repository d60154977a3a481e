// The real TIAGo-on-a-force-plate data (../shared/data/tiago-suspension, not copied into the repo)
// imported with examples/import/tiago_suspension.yaml: plausible numbers and a valid run.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include <hil/format/run.hpp>
#include <hil/import/importer.hpp>

namespace hil::import {
namespace {

const std::string kData = std::string(HIL_SHARED_DIR) + "/data/tiago-suspension/tiago_xyz_vicon_1640.csv";
const std::string kConfig = std::string(HIL_SOURCE_DIR) + "/examples/import/tiago_suspension.yaml";

class Tiago : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_TRUE(std::filesystem::exists(kData)) << kData << " is missing (the shared data sits beside the repo)";
    const auto cfg = load_import_config(kConfig);
    run_ = new ImportedRun(import_table(read_delimited(kData, cfg.delimiter, cfg.header, cfg.columns), cfg));
  }
  static void TearDownTestSuite() { delete run_; }
  static const BodyStats& body(const std::string& name) {
    for (const auto& b : run_->report.bodies)
      if (b.name == name) return b;
    throw std::runtime_error("no body " + name);
  }
  static ImportedRun* run_;
};
ImportedRun* Tiago::run_ = nullptr;

TEST_F(Tiago, RowsTimeAndGaps) {
  const auto& r = run_->report;
  std::cout << report_text(r);
  EXPECT_EQ(r.rows_read, 5547u);
  EXPECT_EQ(r.rows_written, 5547u);
  EXPECT_TRUE(r.dropped.empty());
  EXPECT_NEAR(r.duration_s, 56.022098, 1e-9);
  EXPECT_NEAR(r.median_dt_s, 0.01, 0.0005);
  EXPECT_GT(r.gaps.size(), 10u);  // kept and reported
  EXPECT_GT(r.max_dt_s, 0.025);
  EXPECT_LT(r.max_dt_s, 0.028);
  EXPECT_EQ(r.start_time_utc, "2023-09-20T16:40:52.540797Z");
  EXPECT_TRUE(r.clock_taken_as_utc);
  EXPECT_NE(run_->info.notes.find("taken as UTC"), std::string::npos);
  EXPECT_NEAR(run_->info.output_rate_hz, 100.0, 5.0);
}

TEST_F(Tiago, BaseIsTheEeAndMovesByMillimetresAndMilliradians) {
  const auto& b = body("base");
  EXPECT_TRUE(b.is_ee);
  EXPECT_EQ(b.fitted, 5547u);
  EXPECT_LT(b.rms_mean_m, 0.3e-3);  // the three base markers stay rigid to a fraction of a mm
  EXPECT_LT(b.rms_max_m, 1e-3);
  EXPECT_GT(b.max_displacement_m, 0.5e-3);  // it does move ...
  EXPECT_LT(b.max_displacement_m, 20e-3);   // ... by millimetres
  EXPECT_GT(b.max_rotation_rad, 0.5e-3);
  EXPECT_LT(b.max_rotation_rad, 50e-3);  // 26 mrad, mostly yaw
  for (const auto& s : run_->table.samples) {
    EXPECT_LT(s.v_world_ee_m_per_s.norm(), 0.2);
    EXPECT_LT(s.w_world_ee_rad_per_s.norm(), 0.5);
  }
  // The gripper swings by tens of centimetres.
  EXPECT_GT(body("gripper").max_displacement_m, 0.3);
  EXPECT_LT(body("gripper").rms_mean_m, 2e-3);
}

TEST_F(Tiago, WrenchOnThePlateAndCentreOfPressure) {
  const auto& names = run_->extra_names;
  const auto cx = std::find(names.begin(), names.end(), "cop_x_m") - names.begin();
  const auto cy = std::find(names.begin(), names.end(), "cop_y_m") - names.begin();
  ASSERT_LT(static_cast<std::size_t>(cy), names.size());
  double worst = 0;
  for (std::size_t i = 0; i < run_->table.size(); ++i) {
    const auto& s = run_->table.samples[i];
    EXPECT_GT(s.f_fp_n.z(), -840.0);
    EXPECT_LT(s.f_fp_n.z(), -620.0);
    // Moments about the plate origin, which sits at (0.9, 0.45, 0) in the Vicon world: the centre of
    // pressure on the plate surface is (-my/fz, mx/fz), and the data's own COP column agrees.
    const Eigen::Index ii = static_cast<Eigen::Index>(i);
    const double x = 0.9 - s.m_fp_nm.y() / s.f_fp_n.z(), y = 0.45 + s.m_fp_nm.x() / s.f_fp_n.z();
    worst = std::max({worst, std::abs(x - run_->extra_values(ii, cx)), std::abs(y - run_->extra_values(ii, cy))});
  }
  EXPECT_LT(worst, 1e-6);
}

TEST_F(Tiago, WrittenRunPassesTheStrictReader) {
  const auto dir = (std::filesystem::temp_directory_path() / fmt::format("hil_tiago_import_{}", ::getpid())).string();
  write_imported_run(dir, *run_);
  const auto back = format::load_run(dir);
  EXPECT_EQ(back.info.rig, "tiago_suspension");
  EXPECT_EQ(back.samples.size(), 5547u);
  EXPECT_EQ(back.info.sources.at(0).kind, "import");
  const auto sum = format::summarize(back.samples);
  EXPECT_NEAR(sum.duration_s, 56.022098, 1e-6);
  EXPECT_FALSE(sum.gaps.empty());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hil::import
