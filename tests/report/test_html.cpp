// The HTML report writer: plots that keep their picture at any number of samples, and the
// standalone SVG figures written beside a page.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <unistd.h>

#include "hil/report/html.hpp"

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
  for (std::sregex_iterator it(d.begin(), d.end(), re), end; it != end; ++it)
    pts.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
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
  std::filesystem::remove_all(dir);
  // A folder that cannot be created is an error naming it.
  try {
    page.write_figures("/proc/hil-no-such/figures");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/hil-no-such/figures"), std::string::npos);
  }
}

}  // namespace
}  // namespace hil::report
