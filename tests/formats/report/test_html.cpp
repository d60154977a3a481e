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

}  // namespace
}  // namespace hil::report
