// The mapping config: every field read, and bad configs refused with file, line and field.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <hil/error/error.hpp>
#include <hil/import/config.hpp>
#include <hil/import/timeparse.hpp>

namespace hil::import {
namespace {

const char* kGood = R"(format_version: 1
rig: bench
source: vicon
csv:
  delimiter: ";"
  header: false
  columns: [t, a_xyz, b_xyz, c_xyz, d_xyz, F_xyz, M_xyz, cop]
time:
  column: t
  format: seconds
  unit: ms
  start_time: 2026-11-21T10:00:00.5Z
markers:
  unit: mm
  zero_is_missing: false
bodies:
  - name: tool
    markers: [a, b, {name: c, columns: [c_x, c_y, c_z]}]
    reference_m: {a: [0.1, 0, 0], b: [0, 0.1, 0], c: [0, 0, 0.1]}
  - name: other
    markers: [a, b, c, d]
    reference_rows: 5
    origin: world
    min_markers: 4
    max_residual_m: 0.002
ee: tool
wrench:
  force: [F_x, F_y, F_z]
  moment: [M_x, M_y, M_z]
  force_unit: kN
  moment_unit: N*mm
  measured: on_body
  plate_axes: [-y, x, z]
  moment_point_m: [0.1, 0.2, -0.03]
joints: {columns: [cop], unit: deg}
extra_columns:
  - cop
  - {column: a_x, name: ax_m, scale: 0.001}
twist:
  window_s: 0.08
)";

/// Parses `text` and returns the FormatError it must raise.
error::FormatError error_of(const std::string& text) {
  try {
    parse_import_config(text, "map.yaml");
  } catch (const error::FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return error::FormatError({}, "");
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

TEST(ImportConfig, ReadsEveryField) {
  const auto c = parse_import_config(kGood, "map.yaml");
  EXPECT_EQ(c.rig, "bench");
  EXPECT_EQ(c.source_name, "vicon");
  EXPECT_EQ(c.delimiter, ';');
  EXPECT_FALSE(c.header);
  ASSERT_EQ(c.columns.size(), 1u + 6 * 3 + 1);
  EXPECT_EQ(c.columns[1], "a_x");
  EXPECT_EQ(c.columns[18], "M_z");
  EXPECT_EQ(c.columns.back(), "cop");
  EXPECT_EQ(c.time.format, TimeFormat::seconds);
  EXPECT_DOUBLE_EQ(c.time.s_per_unit, 1e-3);
  EXPECT_EQ(c.time.start_time_utc, "2026-11-21T10:00:00.5Z");
  EXPECT_DOUBLE_EQ(c.marker_m_per_unit, 1e-3);
  EXPECT_FALSE(c.zero_marker_is_missing);
  ASSERT_EQ(c.bodies.size(), 2u);
  EXPECT_EQ(c.bodies[0].markers[2].columns[2], "c_z");
  EXPECT_EQ(c.bodies[0].markers[0].columns[1], "a_y");
  ASSERT_EQ(c.bodies[0].reference_body_m.size(), 3u);
  EXPECT_DOUBLE_EQ(c.bodies[0].reference_body_m[1].y(), 0.1);
  EXPECT_EQ(c.bodies[1].reference_rows, 5u);
  EXPECT_EQ(c.bodies[1].origin, BodyOrigin::world);
  EXPECT_EQ(c.bodies[1].min_markers, 4u);
  EXPECT_DOUBLE_EQ(c.bodies[1].max_residual_m, 0.002);
  EXPECT_EQ(c.ee_body, "tool");
  EXPECT_DOUBLE_EQ(c.wrench.n_per_unit, 1e3);
  EXPECT_DOUBLE_EQ(c.wrench.nm_per_unit, 1e-3);
  EXPECT_TRUE(c.wrench.measured_on_body);
  // plate x = data -y, plate y = data x.
  EXPECT_TRUE(c.wrench.R_fp_data.isApprox((Eigen::Matrix3d() << 0, -1, 0, 1, 0, 0, 0, 0, 1).finished()));
  EXPECT_DOUBLE_EQ(c.wrench.moment_point_fp_m.z(), -0.03);
  ASSERT_EQ(c.joint_columns.size(), 1u);
  EXPECT_NEAR(c.joint_si_per_unit, 0.017453292519943295, 1e-15);
  ASSERT_EQ(c.extras.size(), 2u);
  EXPECT_EQ(c.extras[0].name, "cop");
  EXPECT_EQ(c.extras[1].name, "ax_m");
  EXPECT_DOUBLE_EQ(c.extras[1].scale, 0.001);
  EXPECT_DOUBLE_EQ(c.twist_window_s, 0.08);
}

TEST(ImportConfig, ExpandsXyzColumns) {
  EXPECT_EQ(expand_columns({"time", "m1_xyz", "xyz", "F_x"}), (std::vector<std::string>{"time", "m1_x", "m1_y", "m1_z", "xyz", "F_x"}));
}

TEST(ImportConfig, UnknownKeyNamesLineFieldAndSuggestion) {
  const auto e = error_of(replace(kGood, "  window_s: 0.08", "  window_sec: 0.08"));
  EXPECT_EQ(e.where().file, "map.yaml");
  EXPECT_EQ(e.where().line, 40u);
  EXPECT_EQ(e.where().field, "twist.window_sec");
  EXPECT_NE(std::string(e.what()).find("did you mean 'window_s'"), std::string::npos) << e.what();
}

TEST(ImportConfig, FewerThanThreeMarkersIsAnError) {
  const auto e = error_of(replace(kGood, "markers: [a, b, {name: c, columns: [c_x, c_y, c_z]}]", "markers: [a, b]"));
  EXPECT_EQ(e.where().field, "bodies[0].markers");
  EXPECT_EQ(e.where().line, 18u);
  EXPECT_NE(e.message().find("at least 3 markers"), std::string::npos) << e.what();
}

TEST(ImportConfig, BadValuesAreRefused) {
  struct Case {
    const char* from;
    const char* to;
    const char* field;
  };
  const Case cases[] = {
      {"ee: tool", "ee: gripper", "ee"},
      {"plate_axes: [-y, x, z]", "plate_axes: [y, x, z]", "wrench.plate_axes"},
      {"plate_axes: [-y, x, z]", "plate_axes: [x, w, z]", "wrench.plate_axes[1]"},
      {"force_unit: kN", "force_unit: lbf", "wrench.force_unit"},
      {"unit: ms", "unit: min", "time.unit"},
      {"format: seconds", "format: clock", "time.format"},
      {"start_time: 2026-11-21T10:00:00.5Z", "start_time: 2026-11-21 10:00", "time.start_time"},
      {"    min_markers: 4", "    min_markers: 2", "bodies[1].min_markers"},
      {"    min_markers: 4", "    min_markers: 5", "bodies[1].min_markers"},
      {"reference_m: {a: [0.1, 0, 0],", "reference_m: {e: [0.1, 0, 0], a: [0.1, 0, 0],", "bodies[0].reference_m.e"},
      {"c: [0, 0, 0.1]}", "c: [0, 0]}", "bodies[0].reference_m.c"},
      {"  - name: other", "  - name: tool", "bodies[1].name"},
      {"delimiter: \";\"", "delimiter: ab", "csv.delimiter"},
      {"  header: false", "  header: true", "csv.columns"},
      {"  - cop\n", "  - fz\n", "extra_columns[0]"},
      {"window_s: 0.08", "window_s: -1", "twist.window_s"},
      {"format_version: 1", "format_version: 2", "format_version"},
  };
  for (const auto& c : cases) {
    const auto e = error_of(replace(kGood, c.from, c.to));
    EXPECT_EQ(e.where().field, c.field) << c.to << ": " << e.what();
    EXPECT_GT(e.where().line, 0u) << c.to << ": " << e.what();
  }
}

TEST(ImportConfig, MissingRequiredFields) {
  EXPECT_EQ(error_of(replace(kGood, "ee: tool\n", "")).where().field, "ee");
  EXPECT_EQ(error_of(replace(kGood, "  columns: [t, a_xyz, b_xyz, c_xyz, d_xyz, F_xyz, M_xyz, cop]\n", "")).where().field, "csv.columns");
  EXPECT_EQ(error_of("format_version: 1\n").where().field, "time");
  EXPECT_EQ(error_of("").message(), "empty import config");
  EXPECT_GT(error_of("a: [1, 2\n").where().line, 0u);  // YAML syntax error
}

TEST(ImportConfig, DatetimePatternIsChecked) {
  const std::string dt = replace(replace(replace(kGood, "format: seconds", "format: datetime"), "  unit: ms\n", ""),
                                 "  start_time: 2026-11-21T10:00:00.5Z\n", "  pattern: \"%Y-%m-%d %H:%M\"\n");
  const auto e = error_of(dt);
  EXPECT_EQ(e.where().field, "time.pattern");
  EXPECT_NE(e.message().find("lacks %S"), std::string::npos) << e.what();
  EXPECT_EQ(error_of(replace(dt, "%H:%M\"", "%H:%M:%S.%f\"\n  unit: s")).where().field, "time.unit");
  const auto c = parse_import_config(replace(dt, "%H:%M\"", "%H:%M:%S.%f\"\n  utc_offset_h: 2"), "m.yaml");
  EXPECT_EQ(c.time.format, TimeFormat::datetime);
  EXPECT_EQ(c.time.utc_offset_h.value_or(0), 2.0);
}

TEST(TimeText, ParsesDatetimeToMicroseconds) {
  std::string why;
  const auto us = parse_datetime_us("2023-09-20_16:40:52.540797", "%Y-%m-%d_%H:%M:%S.%f", &why);
  ASSERT_TRUE(us) << why;
  EXPECT_EQ(format_iso8601_utc_us(*us), "2023-09-20T16:40:52.540797Z");
  EXPECT_EQ(*us, 1695228052540797LL);  // date -u -d '2023-09-20 16:40:52' +%s = 1695228052
  EXPECT_EQ(*parse_datetime_us("2024-02-29 00:00:00.5", "%Y-%m-%d %H:%M:%S.%f", nullptr) -
                *parse_datetime_us("2024-02-28 23:59:59.25", "%Y-%m-%d %H:%M:%S.%f", nullptr),
            1250000);
  EXPECT_EQ(*parse_datetime_us("1970-01-01T00:00:01.0000004", "%Y-%m-%dT%H:%M:%S.%f", nullptr), 1000000);
  EXPECT_EQ(*parse_iso8601_utc_us("2026-11-21T10:00:00Z") + 500000, *parse_iso8601_utc_us("2026-11-21T10:00:00.5Z"));
}

TEST(TimeText, BadTextSaysWhatWasExpectedWhere) {
  const std::string p = "%Y-%m-%d_%H:%M:%S.%f";
  std::string why;
  EXPECT_FALSE(parse_datetime_us("2023-09-20 16:40:52.5", p, &why));
  EXPECT_NE(why.find("'_' at character 11"), std::string::npos) << why;
  EXPECT_FALSE(parse_datetime_us("2023-13-20_16:40:52.5", p, &why));
  EXPECT_NE(why.find("month"), std::string::npos) << why;
  EXPECT_FALSE(parse_datetime_us("2023-02-29_16:40:52.5", p, &why));
  EXPECT_NE(why.find("2023-02 has 28 days"), std::string::npos) << why;
  EXPECT_FALSE(parse_datetime_us("2023-09-20_16:40:52.5x", p, &why));
  EXPECT_NE(why.find("end of the time text"), std::string::npos) << why;
  EXPECT_FALSE(parse_datetime_us("2023-09-20_16:40:52.", p, &why));
  EXPECT_FALSE(parse_iso8601_utc_us("2026-11-21T10:00:00"));
  EXPECT_THAT([] { check_datetime_pattern("%Y-%m-%d %H:%M:%S %q"); }, ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr(
                                                                          "unknown directive %q (known: %Y %m %d %H %M %S %f %%)")));
  EXPECT_THAT([] { check_datetime_pattern("%Y-%m-%d %H:%M:%S %Y"); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("%Y appears twice")));
}
}  // namespace
}  // namespace hil::import
