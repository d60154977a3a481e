// Table -> run: synthetic markers on a moving body, a mapped wrench, missing markers, bad rows,
// gaps, and bad input reported with file, line and field.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <numbers>

#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/import/importer.hpp>
#include <hil/import/rigid_fit.hpp>
#include <hil/test/files.hpp>

namespace hil::import {
namespace {

using hil::test::fails_with;

const char* kConfig = R"(format_version: 1
rig: synthetic_bench
time: {column: time, format: seconds, start_time: 2026-11-21T09:00:00Z}
bodies:
  - name: tool
    markers: [m1, m2, m3, m4]
    reference_m: {m1: [0.1, 0, 0], m2: [0, 0.12, 0], m3: [-0.08, -0.05, 0.02], m4: [0, 0, 0.15]}
ee: tool
wrench:
  force: [Fx, Fy, Fz]
  moment: [Mx, My, Mz]
  force_unit: kN
  moment_unit: N*mm
  measured: on_body
  plate_axes: [-y, x, z]
  moment_point_m: [0.1, 0.2, -0.03]
extra_columns: [cop]
twist: {window_s: 0.05}
)";

const Eigen::Vector3d kV(0.02, -0.01, 0.005), kW(0.2, -0.3, 0.1), kP0(0.5, 0.4, 0.3);
const Eigen::Vector3d kC(0.1, 0.2, -0.03);
const Eigen::Matrix3d kRfpData = (Eigen::Matrix3d() << 0, -1, 0, 1, 0, 0, 0, 0, 1).finished();

Eigen::Matrix3Xd reference() {
  Eigen::Matrix3Xd b(3, 4);
  b << 0.1, 0, -0.08, 0, 0, 0.12, -0.05, 0, 0, 0, 0.02, 0.15;
  return b;
}
Eigen::Matrix3d R_at(double t) {
  return Eigen::AngleAxisd(kW.norm() * t, kW.normalized()).toRotationMatrix() *
         Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}
Eigen::Vector3d p_at(double t) { return kP0 + kV * t; }
Eigen::Vector3d f_fp_at(double t) { return {5 * std::sin(t), -3 + t, -700 - 50 * t}; }
Eigen::Vector3d m_fp_at(double t) { return {10 * std::cos(t), 4 - t, 1.5 * t}; }

struct Synthetic {
  std::vector<double> t;  // time of each data row
  std::vector<std::vector<std::string>> cells;
  std::string text() const {
    std::string s = "time,m1_x,m1_y,m1_z,m2_x,m2_y,m2_z,m3_x,m3_y,m3_z,m4_x,m4_y,m4_z,Fx,Fy,Fz,Mx,My,Mz,cop\n";
    for (const auto& r : cells) {
      for (std::size_t c = 0; c < r.size(); ++c) s += (c ? "," : "") + r[c];
      s += '\n';
    }
    return s;
  }
};

/// 100 rows at 100 Hz (one 30 ms gap before row 50) of the body moving at constant twist.
Synthetic make_rows() {
  Synthetic s;
  double t = 0;
  for (int i = 0; i < 100; ++i) {
    if (i > 0) t += (i == 50) ? 0.03 : 0.01;
    s.t.push_back(t);
    std::vector<std::string> r{fmt::format("{}", t)};
    const Eigen::Matrix3Xd w = (R_at(t) * reference()).colwise() + p_at(t);
    for (Eigen::Index m = 0; m < 4; ++m)
      for (Eigen::Index k = 0; k < 3; ++k) r.push_back(fmt::format("{}", w(k, m)));
    // The data: reaction on the body, in kN and N*mm, data axes, moment about kC.
    const Eigen::Vector3d f_fp = f_fp_at(t), m_point = m_fp_at(t) - kC.cross(f_fp);
    const Eigen::Vector3d f_data = -kRfpData.transpose() * f_fp / 1e3, m_data = -kRfpData.transpose() * m_point / 1e-3;
    for (int k = 0; k < 3; ++k) r.push_back(fmt::format("{}", f_data[k]));
    for (int k = 0; k < 3; ++k) r.push_back(fmt::format("{}", m_data[k]));
    r.push_back(fmt::format("{}", 0.01 * i));
    s.cells.push_back(r);
  }
  return s;
}

ImportedRun import_text(const std::string& data, const std::string& config) {
  const auto cfg = parse_import_config(config, "map.yaml");
  return import_table(format::parse_csv(data, data_options(cfg.delimiter, cfg.header, cfg.columns, "data.csv")), cfg);
}

error::FormatError error_of(const std::string& data, const std::string& config = kConfig) {
  try {
    import_text(data, config);
  } catch (const error::FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return error::FormatError({}, "");
}

TEST(Import, SyntheticBodyPoseTwistAndWrench) {
  Synthetic s = make_rows();
  s.cells[10][4] = s.cells[10][5] = s.cells[10][6] = "";   // m2 not seen: fitted with 3
  s.cells[20][7] = s.cells[20][8] = s.cells[20][9] = "0";  // m3 zero-filled: fitted with 3
  s.cells[30][1] = s.cells[30][4] = "NaN";                 // m1 and m2 not seen: dropped
  s.cells[40][0] = s.cells[39][0];                         // duplicated time: dropped
  s.cells[60][0] = s.cells[58][0];                         // backwards: dropped
  const auto run = import_text(s.text(), kConfig);
  const auto& rep = run.report;
  EXPECT_EQ(rep.rows_read, 100u);
  ASSERT_EQ(rep.rows_written, 97u);
  ASSERT_EQ(rep.dropped.size(), 3u);
  for (const auto& d : rep.dropped) {
    EXPECT_EQ(d.count, 1u);
    if (d.reason == "duplicated timestamp") EXPECT_EQ(d.first_line, 42u);
    else if (d.reason == "time goes backwards") EXPECT_EQ(d.first_line, 62u);
    else EXPECT_EQ(d.reason, "body 'tool' (the ee): 2 of 4 markers seen");
  }
  ASSERT_EQ(rep.bodies.size(), 1u);
  EXPECT_EQ(rep.bodies[0].reduced, 2u);
  EXPECT_LT(rep.bodies[0].rms_max_m, 1e-9);
  // Gaps: the 30 ms step and the three 20 ms holes left by dropped rows.
  EXPECT_NEAR(rep.median_dt_s, 0.01, 1e-12);
  ASSERT_EQ(rep.gaps.size(), 4u);
  EXPECT_NEAR(rep.max_dt_s, 0.03, 1e-12);
  EXPECT_EQ(rep.start_time_utc, "2026-11-21T09:00:00.000000Z");

  const auto& tab = run.table;
  for (std::size_t i = 0; i < tab.size(); ++i) {
    const auto& smp = tab.samples[i];
    const double t = smp.t_s;
    EXPECT_LT((smp.p_world_ee_m - p_at(t)).norm(), 1e-9) << i;
    EXPECT_LT((smp.q_world_ee.toRotationMatrix() - R_at(t)).norm(), 1e-9) << i;
    EXPECT_LT((smp.v_world_ee_m_per_s - kV).norm(), 1e-7) << i;
    EXPECT_LT((smp.w_world_ee_rad_per_s - kW).norm(), 1e-7) << i;
    EXPECT_LT((smp.f_fp_n - f_fp_at(t)).norm(), 1e-9) << i;
    EXPECT_LT((smp.m_fp_nm - m_fp_at(t)).norm(), 1e-9) << i;
  }
  ASSERT_EQ(run.extra_names, (std::vector<std::string>{"tool_fit_rms_m", "tool_markers_seen", "cop"}));
  EXPECT_EQ(run.extra_values(10, 1), 3.0);
  EXPECT_EQ(run.extra_values(11, 1), 4.0);
  EXPECT_DOUBLE_EQ(run.extra_values(11, 2), 0.11);
  EXPECT_EQ(tab.line[10], 12u);

  // The run folder passes the strict reader, with the extra columns kept.
  const auto dir = (std::filesystem::temp_directory_path() / fmt::format("hil_import_test_{}", ::getpid())).string();
  write_imported_run(dir, run);
  const auto back = format::load_run(dir);
  EXPECT_EQ(back.info.rig, "synthetic_bench");
  ASSERT_EQ(back.info.sources.size(), 1u);
  EXPECT_EQ(back.info.sources[0].kind, "import");
  EXPECT_NEAR(back.info.output_rate_hz, 100.0, 1e-9);
  ASSERT_EQ(back.samples.size(), 97u);
  EXPECT_EQ(back.samples.extra_columns, run.extra_names);
  EXPECT_EQ(back.samples.samples[5].p_world_ee_m, tab.samples[5].p_world_ee_m);  // lossless
  EXPECT_NE(back.info.notes.find("dropped"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Import, MissingExtraCellIsWrittenAsNan) {
  Synthetic s = make_rows();
  s.cells[3][19] = "";
  const auto run = import_text(s.text(), kConfig);
  EXPECT_TRUE(std::isnan(run.extra_values(3, 2)));
  EXPECT_EQ(run.report.extra_missing, 1u);
}

TEST(Import, ReferenceFromFirstRowsAtTheMarkerCentroid) {
  Synthetic s = make_rows();
  std::string cfg = kConfig;
  cfg.replace(cfg.find("reference_m"), cfg.find('\n', cfg.find("reference_m")) - cfg.find("reference_m"), "reference_rows: 1");
  const auto run = import_text(s.text(), cfg);
  // The body frame is the world-aligned frame at the markers' centroid in the first row.
  const Eigen::Vector3d c0 = ((R_at(0) * reference()).colwise() + p_at(0)).rowwise().mean();
  EXPECT_LT((run.table.samples[0].p_world_ee_m - c0).norm(), 1e-12);
  EXPECT_LT(run.table.samples[0].q_world_ee.angularDistance(Eigen::Quaterniond::Identity()), 1e-9);
  EXPECT_LT((run.table.samples[50].w_world_ee_rad_per_s - kW).norm(), 1e-7);
  EXPECT_EQ(run.report.bodies[0].reference_rows_used, 1u);
}

TEST(Import, SecondBodyResidualLimitAndJoints) {
  Synthetic s = make_rows();
  s.cells[5][7] = fmt::format("{}", std::stod(s.cells[5][7]) + 1e-3);  // m3 off by 1 mm
  s.cells[10][4] = "";                                                 // m2 not seen
  std::string cfg = kConfig;
  cfg.replace(cfg.find("ee: tool"), 0,
              "  - {name: probe, markers: [m1, m2, m3], reference_rows: 1, origin: world, max_residual_m: 1.0e-6}\n");
  cfg += "joints: {columns: [cop], unit: deg}\n";
  const auto run = import_text(s.text(), cfg);
  ASSERT_EQ(run.table.size(), 100u);
  const auto& names = run.extra_names;
  const auto px = std::find(names.begin(), names.end(), "probe_px") - names.begin();
  const auto qw = std::find(names.begin(), names.end(), "probe_qw") - names.begin();
  const auto rms = std::find(names.begin(), names.end(), "probe_fit_rms_m") - names.begin();
  ASSERT_LT(static_cast<std::size_t>(qw), names.size());
  EXPECT_TRUE(std::isnan(run.extra_values(5, px)));   // residual above the limit
  EXPECT_TRUE(std::isnan(run.extra_values(10, px)));  // 2 of 3 markers
  EXPECT_TRUE(std::isnan(run.extra_values(10, rms)));
  EXPECT_GT(run.table.samples[5].p_world_ee_m.norm(), 0.0);  // the ee has no limit: row kept
  EXPECT_EQ(run.report.bodies[1].no_pose, 2u);
  EXPECT_EQ(run.report.bodies[1].fitted, 98u);
  // The probe's frame is the world frame in row 0: R_probe(t) = R_tool(t) R_tool(0)^T.
  const Eigen::Quaterniond q50(run.extra_values(50, qw), run.extra_values(50, qw + 1), run.extra_values(50, qw + 2),
                               run.extra_values(50, qw + 3));
  const double t50 = run.table.samples[50].t_s;
  EXPECT_LT((q50.toRotationMatrix() - R_at(t50) * R_at(0).transpose()).norm(), 1e-9);
  ASSERT_EQ(run.table.joint_count(), 1u);
  EXPECT_NEAR(run.table.joints_rad(7, 0), 0.07 * std::numbers::pi / 180.0, 1e-15);
}

TEST(Import, BadInputNamesFileLineAndField) {
  const Synthetic good = make_rows();
  {
    Synthetic s = good;
    s.cells[7][5] = "0.1x";
    const auto e = error_of(s.text());
    EXPECT_EQ(e.where().file, "data.csv");
    EXPECT_EQ(e.where().line, 9u);
    EXPECT_EQ(e.where().column, 6u);
    EXPECT_EQ(e.where().field, "m2_y");
    EXPECT_NE(e.message().find("expected a number, found '0.1x'"), std::string::npos);
  }
  {
    Synthetic s = good;
    s.cells[7][14] = "";  // an empty force cell drops the row; text is an error
    EXPECT_EQ(import_text(s.text(), kConfig).report.rows_written, 99u);
    s.cells[7][14] = "inf";
    EXPECT_EQ(error_of(s.text()).where().field, "Fy");
  }
  {
    std::string cfg = kConfig;
    cfg.replace(cfg.find("markers: [m1, m2, m3, m4]"), 25, "markers: [m1, m2, m3, m5]");
    cfg.replace(cfg.find("m4: [0, 0, 0.15]"), 2, "m5");
    const auto e = error_of(good.text(), cfg);
    EXPECT_EQ(e.where().line, 1u);
    EXPECT_EQ(e.where().field, "m5_x");
    EXPECT_NE(e.message().find("marker 'm5' of body 'tool'"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("misspelt?"), std::string::npos) << e.what();
  }
  {
    Synthetic s = good;
    s.cells[12].pop_back();
    const auto e = error_of(s.text());
    EXPECT_EQ(e.where().line, 14u);
    EXPECT_NE(e.message().find("row has 19 cells, header has 20"), std::string::npos) << e.what();
  }
  {
    Synthetic s = good;
    s.cells[40][0] = s.cells[39][0];
    std::string cfg = kConfig;
    cfg.replace(cfg.find("start_time"), 0, "non_increasing: error, ");
    const auto e = error_of(s.text(), cfg);
    EXPECT_EQ(e.where().line, 42u);
    EXPECT_EQ(e.where().field, "time");
    EXPECT_NE(e.message().find("duplicated timestamp"), std::string::npos) << e.what();
  }
  {
    Synthetic s = good;
    for (auto& r : s.cells) r[1] = r[4] = "";
    const auto e = error_of(s.text());
    EXPECT_NE(e.message().find("only 0 usable rows of 100"), std::string::npos) << e.what();
  }
}

TEST(Import, DatetimeColumnWithGapsAndUtcOffset) {
  const std::string cfg = R"(format_version: 1
csv: {delimiter: ";", header: false, columns: [when, a_xyz, b_xyz, c_xyz, F_xyz, M_xyz]}
time: {column: when, format: datetime, pattern: "%d/%m/%Y %H:%M:%S.%f", utc_offset_h: 2}
bodies: [{name: base, markers: [a, b, c], reference_rows: 2}]
ee: base
wrench: {force: [F_x, F_y, F_z], moment: [M_x, M_y, M_z]}
)";
  const std::string rows[] = {"20/09/2023 16:40:59.995", "20/09/2023 16:41:00.005", "20/09/2023 16:41:00.032", "20/09/2023 16:41:00.042"};
  std::string data;
  for (const auto& r : rows) data += r + ";1;0;0;0;1;0;0;0;1;0;0;-700;0;0;0\n";
  const auto run = import_text(data, cfg);
  EXPECT_EQ(run.info.start_time_utc, "2023-09-20T14:40:59.995000Z");
  EXPECT_EQ(run.info.rig, "imported");
  EXPECT_FALSE(run.report.clock_taken_as_utc);
  ASSERT_EQ(run.table.size(), 4u);
  EXPECT_NEAR(run.table.samples[2].t_s, 0.037, 1e-12);
  ASSERT_EQ(run.report.gaps.size(), 1u);
  EXPECT_NEAR(run.report.gaps[0].dt_s, 0.027, 1e-12);
  EXPECT_EQ(run.report.gaps[0].line, 3u);
  EXPECT_EQ(run.extra_names.size(), 2u);

  const auto e = error_of(data + "20/09/2023 16:41:00,052;1;0;0;0;1;0;0;0;1;0;0;-700;0;0;0\n", cfg);
  EXPECT_EQ(e.where().line, 5u);
  EXPECT_EQ(e.where().column, 1u);
  EXPECT_EQ(e.where().field, "when");
  EXPECT_NE(e.message().find("bad time text '20/09/2023 16:41:00,052'"), std::string::npos) << e.what();
}

TEST(Import, DelimitedTextTabsCrlfByteOrderMarkAndTruncation) {
  auto parse = [](const std::string& text, char delimiter, bool header, const std::vector<std::string>& names) {
    return format::parse_csv(text, data_options(delimiter, header, names, "d.csv"));
  };
  const auto t = parse("\xEF\xBB\xBF# comment\r\nt\tx y\r\n0\t 1.5 \r\n\r\n1\t\r\n", '\t', true, {});
  EXPECT_EQ(t.header, (std::vector<std::string>{"t", "x y"}));
  EXPECT_EQ(t.header_line, 2u);
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.text("x y")[0], "1.5");
  EXPECT_EQ(t.text("x y")[1], "");
  EXPECT_EQ(t.row_line[1], 5u);
  EXPECT_TRUE(fails_with([&] { parse("0;1;2\n3;4", ';', false, {"a", "b", "c"}); }, 2, "b", "truncated last line"));
  EXPECT_TRUE(fails_with([&] { parse("# only a comment\n", ',', true, {}); }, 0, "", "empty file: expected a header line"));
  EXPECT_TRUE(fails_with([&] { parse("a,a\n1,2\n", ',', true, {}); }, 1, "a", "column name appears twice in header"));
  const auto cfg = parse_import_config(kConfig, "map.yaml");
  EXPECT_TRUE(fails_with([&] { import_table(parse("a,b\n", ',', true, {}), cfg); }, 0, "", "no data rows"));
}

}  // namespace
}  // namespace hil::import
