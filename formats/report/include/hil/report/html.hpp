#pragma once
/// \file A small, dependency-free HTML report writer with inline SVG plots (line, scatter, log
/// axes). One self-contained page: no scripts, no external files, viewable offline.
#include <string>
#include <utility>
#include <vector>

namespace hil::report {

/// One data series. NaN values break lines (and are skipped for points).
struct Series {
  Series() = default;
  Series(std::string name_, std::vector<double> x_, std::vector<double> y_, std::string color_ = "", bool points_ = false,
         bool dashed_ = false, double point_radius_ = 2.0)
      : name(std::move(name_)), x(std::move(x_)), y(std::move(y_)), color(std::move(color_)), points(points_), dashed(dashed_),
        point_radius(point_radius_) {}
  std::string name;
  std::vector<double> x, y;
  std::string color;    ///< CSS colour; empty = from the palette
  bool points = false;  ///< scatter (circles) instead of a line
  bool dashed = false;
  double point_radius = 2.0;
};

struct PlotOptions {
  PlotOptions() = default;
  PlotOptions(std::string title_, std::string xlabel_, std::string ylabel_, bool logx_ = false, bool logy_ = false)
      : title(std::move(title_)), xlabel(std::move(xlabel_)), ylabel(std::move(ylabel_)), logx(logx_), logy(logy_) {}
  std::string title;
  std::string xlabel, ylabel;
  bool logx = false, logy = false;
  int width = 720, height = 280;
  /// Optional annotations: points drawn as a labelled ring.
  struct Mark {
    double x, y;
    std::string label;
  };
  std::vector<Mark> marks;
};

/// The SVG element of one plot.
std::string svg_plot(const std::vector<Series>& series, const PlotOptions& options);

/// One plot's data as CSV: every sample of every series (not the pixel-decimated drawing), numbers
/// in their shortest exact form, NaN as an empty cell. When the series share their x, one x column
/// ("t (s)") and one column per series ("measured (N)"); otherwise an x and a y column per series
/// ("measured: t (s)", "measured (N)"), shorter series padded with empty cells. Header cells
/// holding a comma or a quote are quoted (RFC 4180).
std::string csv_table(const std::vector<Series>& series, const PlotOptions& options);

/// HTML-escapes text.
std::string escape(const std::string& s);

/// A report page built in order, then written at once.
class Page {
 public:
  explicit Page(std::string title);
  void heading(const std::string& text, int level = 2);
  void paragraph(const std::string& text);  ///< escaped
  void preformatted(const std::string& text);
  void table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows);
  void plot(const std::vector<Series>& series, const PlotOptions& options);
  std::string html() const;
  /// \throws std::runtime_error if the file cannot be written.
  void write(const std::string& path) const;
  /// Each plot as a standalone SVG file in `dir` (created), named "NN-title.svg" in page order,
  /// and its data beside it as "NN-title.csv" (csv_table); returns the SVG paths.
  /// \throws std::runtime_error if a file cannot be written.
  std::vector<std::string> write_figures(const std::string& dir) const;

 private:
  struct Figure {
    std::string base;  ///< file name without extension
    std::string svg, csv;
  };
  std::string title_;
  std::string body_;
  std::vector<Figure> figures_;
};

}  // namespace hil::report
