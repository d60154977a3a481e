// The HTML report writer: plots that keep their picture at any number of samples, and the
// standalone SVG figures written beside a page.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <unistd.h>

#include <hil/report/html.hpp>

namespace hil::report {
namespace {

/// The path's points (pixel x, y) of the first <path d='...'> in an SVG.
std::vector<std::pair<double, double>> path_points(const std::string& svg) {
  const auto b = svg.find("<path d='");
  EXPECT_NE(b, std::string::npos);
  const auto e = svg.find('\'', b + 9);
  const std::string d = svg.substr(b + 9, e - b - 9);
  std::vector<std::pair<double, double>> pts;
  static const std::regex re("[ML]([-0-9.]+),([-0-9.]+)");
  for (std::sregex_iterator it(d.begin(), d.end(), re), end; it != end; ++it) pts.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  return pts;
}

TEST(Report, LongLinesKeepTheirEnvelopeAtPixelResolution) {
  // 200,000 samples of a sine with one single-sample spike: far more points than pixels.
  const std::size_t n = 200000;
  Series s;
  s.name = "signal";
  for (std::size_t i = 0; i < n; ++i) {
    s.x.push_back(static_cast<double>(i) * 1e-3);
    s.y.push_back(std::sin(static_cast<double>(i) * 1e-3) + (i == 123457 ? 5.0 : 0.0));
  }
  const std::string svg = svg_plot({s}, PlotOptions("spike", "t", "y"));
  const auto pts = path_points(svg);
  // At most 4 points per pixel column of a 500-pixel-wide plot area.
  EXPECT_LE(pts.size(), 4u * 501u);
  EXPECT_GT(pts.size(), 500u);
  // The spike (the top of the plot area) and the sine's lowest value survive.
  double top = 1e9, bottom = -1e9;
  for (const auto& p : pts) top = std::min(top, p.second), bottom = std::max(bottom, p.second);
  EXPECT_NEAR(top, 26.0 + 0.04 / 1.08 * 212.0, 1.0);  // y1 + pad maps to mt + pad pixels
  EXPECT_GT(bottom, 200.0);
  // The points stay in time order.
  for (std::size_t i = 1; i < pts.size(); ++i) ASSERT_GE(pts[i].first, pts[i - 1].first);
}

TEST(Report, ShortLinesAreDrawnPointByPoint) {
  Series s("few", {0, 1, 2, 3}, {0, 1, 0, 1});
  EXPECT_EQ(path_points(svg_plot({s}, PlotOptions("few", "x", "y"))).size(), 4u);
}

TEST(Report, NaNBreaksTheLine) {
  Series s("gap", {0, 1, 2, 3, 4}, {0, 1, std::nan(""), 1, 0});
  const std::string svg = svg_plot({s}, PlotOptions("gap", "x", "y"));
  const auto d = svg.substr(svg.find("<path d='"));
  EXPECT_EQ(std::count(d.begin(), d.begin() + static_cast<long>(d.find('\'', 9)), 'M'), 2);
}

TEST(Report, EachPlotIsAlsoAStandaloneFigure) {
  Page page("t");
  page.plot({Series("a", {0, 1}, {0, 1})}, PlotOptions("Measured vs nominal: fx (N)", "t", "N"));
  page.plot({Series("b", {0, 1}, {1, 0})}, PlotOptions("", "t", "N"));
  const auto dir = std::filesystem::temp_directory_path() / ("hil_report_test_" + std::to_string(::getpid()));
  const auto files = page.write_figures((dir / "figures").string());
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(std::filesystem::path(files[0]).filename(), "01-measured-vs-nominal-fx-n.svg");
  EXPECT_EQ(std::filesystem::path(files[1]).filename(), "02-plot.svg");
  std::ifstream f(files[0]);
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_NE(ss.str().find("<svg xmlns='http://www.w3.org/2000/svg'"), std::string::npos);
  // Each figure's data beside it, same base name.
  const std::vector<std::string> want = {"t,a (N)\n0,0\n1,1\n", "t,b (N)\n0,1\n1,0\n"};
  for (std::size_t k = 0; k < files.size(); ++k) {
    auto csv = std::filesystem::path(files[k]).replace_extension(".csv");
    ASSERT_TRUE(std::filesystem::exists(csv)) << csv;
    std::ifstream c(csv);
    std::stringstream cs;
    cs << c.rdbuf();
    EXPECT_EQ(cs.str(), want[k]);
  }
  std::filesystem::remove_all(dir);
  // A folder that cannot be created is an error naming it.
  try {
    page.write_figures("/proc/hil-no-such/figures");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/hil-no-such/figures"), std::string::npos);
  }
}

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::size_t b = 0;
    for (std::size_t e; (e = line.find(',', b)) != std::string::npos; b = e + 1) cells.push_back(line.substr(b, e - b));
    cells.push_back(line.substr(b));
    rows.push_back(cells);
  }
  return rows;
}

TEST(Report, PlotDataIsEverySampleWrittenExactly) {
  // Far more samples than the drawing keeps, values that need 17 digits, and a NaN.
  const std::size_t n = 20000;
  Series a, b;
  a.name = "measured";
  b.name = "nominal";
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / 3.0;
    a.x.push_back(t);
    b.x.push_back(t);
    a.y.push_back(std::sin(t) / 7.0);
    b.y.push_back(i == 5 ? std::nan("") : std::exp(-t) * 1e-300 + 0.1);
  }
  const PlotOptions o("fx", "t (s)", "N");
  ASSERT_LT(path_points(svg_plot({a, b}, o)).size(), n / 4);  // the drawing is decimated...
  const auto rows = csv_rows(csv_table({a, b}, o));
  ASSERT_EQ(rows.size(), n + 1);  // ...the data is not
  EXPECT_EQ(rows[0], (std::vector<std::string>{"t (s)", "measured (N)", "nominal (N)"}));
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(rows[i + 1].size(), 3u) << i;
    EXPECT_EQ(std::stod(rows[i + 1][0]), a.x[i]);
    EXPECT_EQ(std::stod(rows[i + 1][1]), a.y[i]);
    if (i == 5) EXPECT_EQ(rows[i + 1][2], "");
    else EXPECT_EQ(std::stod(rows[i + 1][2]), b.y[i]) << rows[i + 1][2];
  }
}

TEST(Report, PlotDataOfSeriesOnDifferentAxes) {
  // Points and a two-point line: an x and a y column per series, the shorter one padded.
  const Series pts("instantaneous", {0.5, 1.5, 2.5}, {10, 20, 30});
  const Series g("global, fitted", {0, 3}, {15, 15});
  const auto rows = csv_rows(csv_table({pts, g}, PlotOptions("K", "t (s)", "N/m")));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0][0], "instantaneous: t (s)");
  EXPECT_EQ(rows[0][1], "instantaneous (N/m)");
  // A header with a comma is quoted (the naive split above cuts it in two).
  EXPECT_EQ(rows[0][2] + "," + rows[0][3], "\"global, fitted: t (s)\"");
  EXPECT_EQ(rows[1], (std::vector<std::string>{"0.5", "10", "0", "15"}));
  EXPECT_EQ(rows[3], (std::vector<std::string>{"2.5", "30", "", ""}));
}

TEST(Report, LogLogPlotSkipsNonPositiveValues) {
  PlotOptions o{"t", "x", "y", true, true};
  const auto svg = svg_plot({{"s", {1e-3, 0.0, 1e2}, {1.0, 2.0, -1.0}}}, o);
  EXPECT_NE(svg.find("<path"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(escape("<a&b>"), "&lt;a&amp;b&gt;");
}

/// Count of non-overlapping occurrences of `what` in `s`.
std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (auto p = s.find(what); p != std::string::npos; p = s.find(what, p + what.size())) ++n;
  return n;
}

TEST(Report, ADenseScatterDrawsOnePointPerPixel) {
  // 100,000 points on 10 distinct values: a cloud the size of the picture, not of the data.
  Series s("cloud", {}, {}, "", true);
  for (int i = 0; i < 100000; ++i) s.x.push_back(i % 10), s.y.push_back(i % 10);
  const auto svg = svg_plot({s}, PlotOptions("cloud", "x", "y"));
  EXPECT_EQ(count(svg, "<circle"), 10u);
  // Every sample is still in the figure's data.
  const auto csv = csv_table({s}, PlotOptions("cloud", "x", "y"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 100001);
}

TEST(Report, ForestRowsKeepTheirOwnScaleAndMarkTheTruth) {
  // Two parameters six orders of magnitude apart: each row spans its own interval.
  const std::vector<Interval> rows{{"K", "N/m", 1.8e5, 1.7e5, 1.9e5}, {"bias_fx", "N", -7.66, -7.73, -7.59, 0.0, -7.662}};
  const auto svg = svg_forest(rows, "intervals");
  EXPECT_NE(svg.find("K (N/m)"), std::string::npos);
  EXPECT_NE(svg.find("bias_fx (N)"), std::string::npos);
  EXPECT_NE(svg.find("[1.7e+05, 1.9e+05]"), std::string::npos);
  // The interval bars: K's spans most of its row whatever its units; bias_fx's row also holds its
  // reference (0, no effect), so its interval sits at the row's far end, drawn but short.
  static const std::regex bar("<line x1='([0-9.]+)' x2='([0-9.]+)' y1='[0-9.]+' y2='[0-9.]+' stroke='#1f77b4' stroke-width='5'");
  std::vector<double> widths;
  for (std::sregex_iterator it(svg.begin(), svg.end(), bar), end; it != end; ++it)
    widths.push_back(std::stod((*it)[2]) - std::stod((*it)[1]));
  ASSERT_EQ(widths.size(), 2u);
  EXPECT_GT(widths[0], 0.6 * (720 - 190 - 200));
  EXPECT_GT(widths[1], 1.0);
  EXPECT_EQ(count(svg, "stroke='#888' stroke-width='2'"), 1u + 1u);  // the reference tick, and its legend key
  // The truth is drawn where given (one row), and named in the legend.
  EXPECT_EQ(count(svg, "stroke='#d62728' stroke-width='2'"), 1u);
  EXPECT_NE(svg.find("truth"), std::string::npos);
  const auto no_truth = svg_forest({rows[0]}, "intervals");
  EXPECT_EQ(no_truth.find("truth"), std::string::npos);
}

TEST(Report, BarsWithWhiskersAndUnscoredRows) {
  Bars b;
  b.groups = {"nominal", "sensor_bias", "time_offset"};
  b.series = {"held-out error"};
  b.value = {{20.0, 0.2, std::nan("")}};
  b.lower = {{std::nan(""), 0.1, std::nan("")}};
  b.upper = {{std::nan(""), 2.0, std::nan("")}};
  const auto svg = svg_bars(b, PlotOptions("errors", "held-out relative error (%)", ""));
  EXPECT_EQ(count(svg, "<rect x="), 2u + 1u);  // two bars and the legend's key
  EXPECT_EQ(count(svg, "not scored"), 1u);
  EXPECT_EQ(count(svg, "stroke='#222'"), 1u);  // one whisker
}

TEST(Report, TheVerdictComesFirstThenTheContentsThenTheSections) {
  Page page("Diagnosis: r");
  page.heading("Candidates");
  page.table({"candidate", "gain"}, {{"a", "1 %"}, {"b", "2 %"}}, {1});
  page.plot({Series("a", {0, 1}, {0, 1})}, PlotOptions("one", "t", "N"));
  page.plot({Series("b", {0, 1}, {1, 0})}, PlotOptions("two", "t", "N"));
  page.heading("Parameters & intervals");
  page.text_download("the summary", "d.txt", "line 1, 100 %\nline <2>\n");
  page.verdict({"cause", "Named cause: a", {{"gain", "12 %"}}, "re-identify"});  // called last, placed first
  const auto html = page.html();
  const auto v = html.find("<section id='verdict' class='verdict cause'>"), toc = html.find("<nav class='toc'>"),
             h2 = html.find("<h2 id='s1-candidates'>");
  ASSERT_NE(v, std::string::npos);
  ASSERT_NE(toc, std::string::npos);
  ASSERT_NE(h2, std::string::npos);
  EXPECT_LT(v, toc);
  EXPECT_LT(toc, h2);
  EXPECT_NE(html.find("<a href='#s1-candidates'>Candidates</a>"), std::string::npos);
  EXPECT_NE(html.find("<a href='#s2-parameters-intervals'>Parameters &amp; intervals</a>"), std::string::npos);
  EXPECT_NE(html.find("<tr class='em'><td>b</td>"), std::string::npos);
  // Consecutive figures share one grid; the next heading closes it.
  EXPECT_EQ(count(html, "<div class='figs'>"), 1u);
  EXPECT_LT(html.find("<div class='figs'>"), html.find("id='fig-1'"));
  EXPECT_LT(html.find("id='fig-2'"), html.find("</div>\n<h2 id='s2"));
  // The text is kept whole as a data: URL that decodes back to it.
  EXPECT_NE(html.find("href='data:text/plain;charset=utf-8,line%201%2C%20100%20%25%0Aline%20%3C2%3E%0A'"), std::string::npos);
  EXPECT_NE(html.find("download='d.txt'"), std::string::npos);
  // Figures scale to their column.
  EXPECT_NE(html.find("viewBox='0 0 720.0 280.0'"), std::string::npos);
}

TEST(Report, AnAxisLabelWithItsUnitGivesTheColumnsTheUnit) {
  const auto rows = csv_rows(csv_table({Series("measured", {0}, {1}), Series("nominal", {0}, {2})}, PlotOptions("fx", "t (s)", "fx (N)")));
  EXPECT_EQ(rows[0], (std::vector<std::string>{"t (s)", "measured (N)", "nominal (N)"}));
}

TEST(Report, ATimelineColoursEachVerdictOnceAndSpansTheRun) {
  const std::vector<Span> spans{{0, 6.5, "none", "0.16 %"},
                                {6.5, 13, "none", "0.22 %"},
                                {13, 19.5, "sensor_bias", "gain 88 %"},
                                {19.5, 26, "sensor_bias", "gain 85 %"},
                                {26, 27, "not diagnosed", "too few samples"}};
  const auto svg = svg_timeline(spans, PlotOptions("verdicts", "t (s)", ""));
  EXPECT_EQ(count(svg, "fill='#b7dfb0'"), 2u);  // none
  EXPECT_EQ(count(svg, "fill='#1f77b4'"), 2u);  // the first named cause's colour, both its windows
  EXPECT_EQ(count(svg, "fill='#e4e4e4'"), 1u);  // not diagnosed
  // The first block starts at the left margin, the last ends at the right one.
  EXPECT_NE(svg.find("<rect x='21.0' y='30.0'"), std::string::npos);
  EXPECT_NE(svg.find(">gain 88 %<"), std::string::npos);
}

TEST(Report, ALongLegendLabelIsCondensedNotCut) {
  const auto svg = svg_plot({Series("robot_compliance+rest_change+sensor_gain", {0, 1}, {0, 1}), Series("short", {0, 1}, {1, 0})},
                            PlotOptions("t", "x", "y"));
  EXPECT_EQ(count(svg, "lengthAdjust='spacingAndGlyphs'"), 1u);
  EXPECT_NE(svg.find(">robot_compliance+rest_change+sensor_gain<"), std::string::npos);
}

}  // namespace
}  // namespace hil::report
