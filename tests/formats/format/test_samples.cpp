#include <gtest/gtest.h>

#include <hil/format/samples.hpp>
#include <hil/test/files.hpp>

using hil::format::parse_samples;
using hil::test::fails_with;

namespace {
const std::string kHeader = "t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,mx,my,mz";
std::string row(double t, const std::string& q = "1,0,0,0", const std::string& f = "1,2,3") {
  return std::to_string(t) + ",0.1,0.2,0.3," + q + ",0,0,0,0,0,0," + f + ",0,0,0";
}
auto parse(const std::string& text) {
  return [text] { parse_samples(text, "run/samples.csv"); };
}
}  // namespace

TEST(Samples, ReadsValidTableWithJointsAndExtras) {
  const std::string text = "# comment line\n" + kHeader + ",j1,j2,note\n" + row(0.0) + ",0.5,-0.5,a\n" + row(0.02) + ",0.6,-0.4,b\n";
  const auto t = parse_samples(text, "x.csv");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.joint_count(), 2u);
  EXPECT_DOUBLE_EQ(t.joints_rad(1, 0), 0.6);
  EXPECT_DOUBLE_EQ(t.samples[1].t_s, 0.02);
  EXPECT_DOUBLE_EQ(t.samples[0].f_fp_n.z(), 3.0);
  ASSERT_EQ(t.extra_columns.size(), 1u);
  EXPECT_EQ(t.extra_columns[0], "note");
  EXPECT_EQ(t.line[1], 4u);
}

TEST(Samples, MissingColumn) {
  std::string h = kHeader;
  h.replace(h.find(",fz"), 3, "");
  std::string r = row(0.0);
  r.replace(r.find(",1,2,3"), 6, ",1,2");
  EXPECT_TRUE(fails_with(parse(h + "\n" + r + "\n"), 1, "fz", "required column is missing"));
}

TEST(Samples, MisspeltColumnIsNamed) {
  std::string h = kHeader;
  h.replace(h.find(",fz"), 3, ",Fz");
  EXPECT_TRUE(fails_with(parse(h + "\n" + row(0.0) + "\n"), 1, "fz", "'Fz': misspelt?"));
}

TEST(Samples, NonNumericCell) {
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0) + "\n" + row(0.1, "1,0,0,0", "1,abc,3") + "\n"), 3, "fy",
                         "expected a number, found 'abc'"));
}

TEST(Samples, NaNAndInfAreRefused) {
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0, "1,0,0,0", "nan,2,3") + "\n"), 2, "fx", "finite"));
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0, "1,0,0,0", "1,2,-inf") + "\n"), 2, "fz", "finite"));
}

TEST(Samples, NonUnitQuaternion) {
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0, "0.9,0.1,0,0") + "\n"), 2, "qw qx qy qz", "not a unit quaternion"));
}

TEST(Samples, NearlyUnitQuaternionIsRenormalised) {
  const auto t = parse_samples(kHeader + "\n" + row(0.0, "0.7071,0.7071,0,0") + "\n", "x.csv");
  EXPECT_NEAR(t.samples[0].q_world_ee.norm(), 1.0, 1e-15);
}

TEST(Samples, TimeGoingBackwards) {
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.1) + "\n" + row(0.05) + "\n"), 3, "t", "time goes backwards"));
}

TEST(Samples, DuplicatedTimestamp) {
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.1) + "\n" + row(0.1) + "\n"), 3, "t", "duplicated timestamp"));
}

TEST(Samples, TruncatedLastLine) {
  const std::string cut = row(0.02).substr(0, 20);
  EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0) + "\n" + cut), 3, "", "truncated last line"));
}

TEST(Samples, RaggedRow) { EXPECT_TRUE(fails_with(parse(kHeader + "\n" + row(0.0) + ",7\n"), 2, "", "row has 21 cells, header has 20")); }

TEST(Samples, EmptyFile) {
  EXPECT_TRUE(fails_with(parse(""), 0, "", "empty file"));
  EXPECT_TRUE(fails_with(parse("\n\n"), 0, "", "empty file"));
  EXPECT_TRUE(fails_with(parse(kHeader + "\n"), 0, "", "no samples"));
}

TEST(Samples, JointColumnsWithoutGap) {
  EXPECT_TRUE(fails_with(parse(kHeader + ",j1,j3\n" + row(0.0) + ",0,0\n"), 0, "j2", "without gaps"));
}

TEST(Samples, WriterRoundTripsLosslessly) {
  hil::test::TempDir dir;
  hil::format::SampleTable t;
  t.joints_rad.resize(3, 2);
  for (int i = 0; i < 3; ++i) {
    hil::format::Sample s;
    s.t_s = 0.1 * i + 1e-13;
    s.p_world_ee_m = {0.1 / 3.0, -2.0 / 7.0, 1e-9 * i};
    s.q_world_ee = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    s.f_fp_n = {1.0 / 3.0, 2.5, -600.123456789};
    t.samples.push_back(s);
    t.joints_rad.row(i) << 0.1 * i, -1.0 / 9.0;
  }
  const auto path = dir.path() + "/samples.csv";
  hil::format::write_samples(path, t);
  const auto back = hil::format::read_samples(path);
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back.samples[i].t_s, t.samples[i].t_s);
    EXPECT_EQ(back.samples[i].p_world_ee_m, t.samples[i].p_world_ee_m);
    EXPECT_EQ(back.samples[i].f_fp_n, t.samples[i].f_fp_n);
    EXPECT_NEAR(back.samples[i].q_world_ee.angularDistance(t.samples[i].q_world_ee), 0.0, 1e-15);
  }
  EXPECT_EQ(back.joints_rad, t.joints_rad);
}

TEST(Samples, MissingFileIsAnErrorNotACrash) {
  EXPECT_TRUE(fails_with([] { hil::format::read_samples("/nonexistent/samples.csv"); }, 0, "", "cannot open"));
}
