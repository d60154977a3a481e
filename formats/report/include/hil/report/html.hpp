#pragma once
/// \file A small, dependency-free HTML report writer with inline SVG figures (line, scatter, log
/// axes, interval forest plots, grouped bars). One self-contained page: no scripts, no external
/// files, viewable offline and printable; the verdict block first, then a table of contents, then
/// the sections, their figures in a grid that is two columns wide where the screen allows.
/// Written here rather than taken from a plotting library: Debian has none for C++ that writes
/// self-contained SVG without a scripting runtime (docs/architecture.md, "Reports").
#include <limits>
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
  bool wide = false;  ///< spans the page's width in the page's figure grid (e.g. a long time series)
  /// Optional annotations: points drawn as a labelled ring.
  struct Mark {
    double x, y;
    std::string label;
  };
  std::vector<Mark> marks;
};

/// The SVG element of one plot. Scatter series draw at most one point per pixel (the picture of a
/// dense cloud, not its sample count).
std::string svg_plot(const std::vector<Series>& series, const PlotOptions& options);

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

/// One row of a forest plot: a parameter's value and interval. Parameters differ in units, so each
/// row is drawn on its own scale, its ends labelled.
struct Interval {
  std::string name, unit;
  double value = 0.0, lower = 0.0, upper = 0.0;
  double reference = kNoValue;  ///< e.g. the nominal value (a grey tick); NaN: none
  double truth = kNoValue;      ///< the true value where the run knows it (a hidden-effect simulation)
};

/// A forest plot: per row the interval as a bar, the value as a dot, the reference and the truth.
std::string svg_forest(const std::vector<Interval>& rows, const std::string& title, const std::string& reference_label = "nominal");

/// Horizontal bars, grouped: per group (a row: a candidate, a posture) one bar per series, each with
/// an optional interval whisker.
struct Bars {
  std::vector<std::string> groups;         ///< row labels
  std::vector<std::string> series;         ///< bar labels within a group (the legend)
  std::vector<std::vector<double>> value;  ///< [series][group]; NaN: no bar, "not scored" written
  /// [series][group] or empty: the whisker's ends (NaN: none)
  std::vector<std::vector<double>> lower, upper;
  std::vector<std::string> colors;  ///< per series; empty: the palette
};
std::string svg_bars(const Bars& bars, const PlotOptions& options);

/// One span of a timeline: [start, end) with its label (e.g. a time window's verdict) and a detail.
struct Span {
  double start = 0.0, end = 0.0;
  std::string label, detail;
};
/// A timeline: the spans on one time axis, one colour per distinct label ("none" green, "not
/// diagnosed" grey), each span labelled in place.
std::string svg_timeline(const std::vector<Span>& spans, const PlotOptions& options);

/// The verdict block that opens a report: what was found in words and numbers, and what to do.
struct Verdict {
  /// The block's kind, also its colour: "cause" (a cause named), "none" (nothing to explain),
  /// "unexplained" (structure left that nothing explains), "identified" (parameters estimated).
  std::string kind;
  std::string headline;                                    ///< one sentence
  std::vector<std::pair<std::string, std::string>> facts;  ///< label, value
  std::string next;                                        ///< what to do next, one sentence
};

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
  /// The verdict block, placed above the table of contents whatever the order of the calls.
  void verdict(const Verdict& v);
  /// Level-2 headings are the sections of the table of contents.
  void heading(const std::string& text, int level = 2);
  void paragraph(const std::string& text);  ///< escaped
  void preformatted(const std::string& text);
  /// Rows listed in `emphasised` (e.g. the named cause) are set in bold.
  void table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
             const std::vector<std::size_t>& emphasised = {});
  void plot(const std::vector<Series>& series, const PlotOptions& options);
  void forest(const std::vector<Interval>& rows, const std::string& title, const std::string& reference_label = "nominal");
  void bars(const Bars& bars, const PlotOptions& options);
  void timeline(const std::vector<Span>& spans, const PlotOptions& options);
  /// A text kept whole (e.g. the command's text summary): folded away, and a link that saves it as
  /// `file_name` (a data: URL, so the page stays one file).
  void text_download(const std::string& label, const std::string& file_name, const std::string& text);
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
  void figure(std::string svg, std::string csv, const std::string& title, bool wide);
  void end_figures();  ///< closes the figure grid before a non-figure element
  std::string title_;
  std::string verdict_;
  std::vector<std::pair<std::string, std::string>> toc_;  ///< anchor, heading
  std::string body_;
  bool in_figures_ = false;
  std::vector<Figure> figures_;
};

}  // namespace hil::report
