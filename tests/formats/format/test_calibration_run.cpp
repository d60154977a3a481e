// The calibration run (formats/format/src/calibration_run.cpp): what a well-formed table gives, and
// every kind of bad input refused with its line, column and what is wrong.
#include <gtest/gtest.h>

#include <hil/error/error.hpp>
#include <hil/format/calibration_run.hpp>
#include <hil/format/urdf.hpp>

namespace hf = hil::format;

namespace {

const std::string kUrdf = std::string(HIL_SOURCE_DIR) + "/examples/stiffness/kr270_like.urdf";

hf::RobotSpec robot() { return hf::read_urdf_robot(kUrdf, "base_link", "tool0"); }

const std::string kHeader = "posture,station,a1,a2,a3,a4,a5,a6,px,py,pz";

/// The error of parsing `text`, or "(no error)".
hil::error::FormatError error_of(const std::string& text) {
  try {
    hf::parse_calibration_run(text, "run.csv", robot());
  } catch (const hil::error::FormatError& e) {
    return e;
  }
  return hil::error::FormatError({"", 0, 0, ""}, "(no error)");
}

}  // namespace

TEST(CalibrationRun, ReadsPosturesStationsFlagsTiltsAndLoads) {
  const std::string text =
      "# two stations of a laser tracker\n"
      "posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,rx,ry,rz,sigma_m,sigma_rad,flag_elbow_up,tilt_base_link_rx,tilt_link_1_ry,"
      "payload_kg,payload_cz,fx,fy,fz,mx,my,mz\n"
      "p1,A,0.1,-1.0,0.5,0,0.3,0,1.5,0.2,1.1,0,0,0.5,2e-5,1e-4,1,0.001,-0.002,12.5,0.08,0,0,-100,0,0,0\n"
      "p2,B,-0.1,-1.2,0.4,0,-0.3,1,1.4,-0.2,1.2,0.1,0,0,2e-5,1e-4,0,0.0012,-0.001,12.5,0.08,0,0,-100,0,0,0\n"
      "p3,A,0,-0.5,0,0,0,0,2.0,0.0,1.3,0,0.2,0,3e-5,1e-4,0,0.0008,0,0,0,0,0,0,0,0,0\n";
  const auto run = hf::parse_calibration_run(text, "run.csv", robot());
  ASSERT_EQ(run.postures.size(), 3u);
  EXPECT_EQ(run.stations, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(run.flag_names, (std::vector<std::string>{"elbow_up"}));
  ASSERT_EQ(run.tilts.size(), 2u);
  EXPECT_EQ(run.tilts[0].link, "base_link");
  EXPECT_EQ(run.tilts[1].axis, 1);
  EXPECT_TRUE(run.has_orientation && run.has_sigma && run.has_payload && run.has_wrench);
  const auto& p2 = run.postures[1];
  EXPECT_EQ(p2.id, "p2");
  EXPECT_EQ(p2.station, "B");
  EXPECT_EQ(p2.line, 4u);
  EXPECT_DOUBLE_EQ(p2.q[1], -1.2);
  EXPECT_DOUBLE_EQ(p2.p_measured_m.y(), -0.2);
  EXPECT_DOUBLE_EQ(p2.r_measured_rad->x(), 0.1);
  EXPECT_DOUBLE_EQ(p2.sigma_m, 2e-5);
  EXPECT_EQ(p2.flags, (std::vector<bool>{false}));
  EXPECT_DOUBLE_EQ(p2.tilts_rad[0], 0.0012);
  EXPECT_DOUBLE_EQ(p2.payload_kg, 12.5);
  EXPECT_DOUBLE_EQ(p2.payload_com_m.z(), 0.08);
  EXPECT_DOUBLE_EQ((*p2.wrench)[2], -100.0);
  // The minimal table: one station, no orientation, no sigma (estimated later).
  const auto minimal = hf::parse_calibration_run("posture,a1,a2,a3,a4,a5,a6,px,py,pz\n7,0,-1,0,0,0,0,1,2,3\n", "m.csv", robot());
  EXPECT_EQ(minimal.stations, (std::vector<std::string>{"1"}));
  EXPECT_EQ(minimal.postures[0].id, "7");
  EXPECT_FALSE(minimal.postures[0].r_measured_rad.has_value());
  EXPECT_EQ(minimal.postures[0].sigma_m, 0.0);
}

TEST(CalibrationRun, BadInputIsNamedByLineAndColumn) {
  struct Case {
    std::string text, field, says;
    std::size_t line;
  };
  const std::string row = "p1,A,0,-1,0,0,0,0,1,2,3";
  const std::vector<Case> cases = {
      {kHeader + "\n" + row + "\np1,A,0,-1,0,0,0,0,1,2,3\n", "posture", "appears twice", 3},
      {kHeader + "\np1,A,0,-95,0,0,0,0,1,2,3\n", "a2", "outside the joint's limits [-2.44, -0.09] rad (degrees?)", 2},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,pzz\n" + row + ",0\n", "pzz", "did you mean 'pz'", 1},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,rx,ry\n" + row + ",0,0\n", "rz", "needs all of its columns", 1},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,sigma_m\n" + row + ",0\n", "sigma_m", "must be > 0", 2},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,flag_flip\n" + row + ",2\n", "flag_flip", "0 or 1", 2},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,tilt_column_rx\n" + row + ",0\n", "tilt_column_rx", "does not have", 1},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,tilt_link_2_rx\n" + row + ",2.5\n", "tilt_link_2_rx", "degrees?", 2},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,payload_cz\n" + row + ",0.1\n", "payload_cz", "without payload_kg", 1},
      {"posture,station,a1,a2,a3,a4,a5,a6,px,py,pz,rx,ry,rz\n" + row + ",4,0,0\n", "rx", "longer than π", 2},
      {"posture,station,a1,a2,a3,a4,a5,px,py,pz\np1,A,0,-1,0,0,0,1,2,3\n", "a6", "", 1},
      {kHeader + "\np1,A,0,-1,0,0,0,0,1,x,3\n", "py", "expected a number", 2},
      {kHeader + "\n", "", "at least one posture", 1},
  };
  for (const auto& c : cases) {
    const auto e = error_of(c.text);
    EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << c.text << " -> " << e.what();
    EXPECT_EQ(e.where().field, c.field) << e.what();
    EXPECT_EQ(e.where().line, c.line) << e.what();
  }
}

TEST(CalibrationRun, TellsItselfFromSamples) {
  EXPECT_TRUE(hf::looks_like_calibration_run({"posture", "a1", "px", "py", "pz"}));
  EXPECT_FALSE(hf::looks_like_calibration_run({"t", "px", "py", "pz", "fx"}));
}
