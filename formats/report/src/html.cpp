#include <hil/report/html.hpp>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace hil::report {

namespace {

const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

std::string px(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

/// "Nice" tick values covering [lo, hi].
std::vector<double> ticks(double lo, double hi, bool log) {
  std::vector<double> t;
  if (log) {
    for (double e = std::floor(lo); e <= std::ceil(hi) + 1e-9; e += 1.0)
      if (e >= lo - 1e-9 && e <= hi + 1e-9) t.push_back(e);
    return t;
  }
  const double span = hi - lo;
  if (!(span > 0)) return {lo};
  const double raw = span / 5.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) {
      step = m * mag;
      break;
    }
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) t.push_back(std::abs(v) < 1e-12 * span ? 0.0 : v);
  return t;
}

/// The points of a line series in pixels. A run of finite points within one pixel column is
/// drawn as its first, lowest, highest and last point, in their order: the same picture (the
/// envelope and every excursion stay), a page that does not grow with the number of samples.
/// NaN points are kept (they break the line).
template <class FX, class FY>
std::vector<std::pair<double, double>> pixel_path(const Series& sr, std::size_t n, const FX& X, const FY& Y) {
  std::vector<std::pair<double, double>> out;
  std::vector<std::size_t> col;  // indices of the current column's run
  auto flush = [&] {
    if (col.size() <= 4) {
      for (auto i : col) out.emplace_back(X(sr.x[i]), Y(sr.y[i]));
    } else {
      std::size_t lo = col.front(), hi = col.front();
      for (auto i : col) {
        if (Y(sr.y[i]) > Y(sr.y[lo])) lo = i;  // (pixel y grows downwards)
        if (Y(sr.y[i]) < Y(sr.y[hi])) hi = i;
      }
      std::vector<std::size_t> keep = {col.front(), lo, hi, col.back()};
      std::sort(keep.begin(), keep.end());
      keep.erase(std::unique(keep.begin(), keep.end()), keep.end());
      for (auto i : keep) out.emplace_back(X(sr.x[i]), Y(sr.y[i]));
    }
    col.clear();
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double a = X(sr.x[i]), b = Y(sr.y[i]);
    if (!std::isfinite(a) || !std::isfinite(b)) {
      flush();
      out.emplace_back(a, b);
      continue;
    }
    if (!col.empty() && std::floor(a) != std::floor(X(sr.x[col.front()]))) flush();
    col.push_back(i);
  }
  flush();
  return out;
}

/// A file name from a plot title: lower case letters and digits, '-' between words.
std::string slug(const std::string& title) {
  std::string s;
  for (char c : title) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!s.empty() && s.back() != '-') {
      s += '-';
    }
    if (s.size() >= 60) break;
  }
  while (!s.empty() && s.back() == '-') s.pop_back();
  return s.empty() ? "plot" : s;
}

/// The shortest text that reads back to the same double; empty for NaN (a missing value).
std::string exact(double v) {
  if (std::isnan(v)) return "";
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// "name (unit)" for a column; the plot's axis label is the unit or the quantity.
std::string column(const std::string& name, const std::string& label) {
  if (label.empty()) return name;
  return name.empty() ? label : name + " (" + label + ")";
}

}  // namespace

std::string csv_table(const std::vector<Series>& series, const PlotOptions& o) {
  const std::string xlabel = o.xlabel.empty() ? "x" : o.xlabel;
  auto name = [&](std::size_t k) { return series[k].name.empty() ? "series " + std::to_string(k + 1) : series[k].name; };
  bool shared = !series.empty();
  std::size_t rows = 0;
  for (const auto& s : series) {
    shared = shared && s.x == series.front().x && s.y.size() >= s.x.size();
    rows = std::max(rows, std::min(s.x.size(), s.y.size()));
  }
  std::string out;
  if (shared) {
    out += csv_cell(xlabel);
    for (std::size_t k = 0; k < series.size(); ++k) out += "," + csv_cell(column(name(k), o.ylabel));
    out += "\n";
    for (std::size_t i = 0; i < rows; ++i) {
      out += exact(series.front().x[i]);
      for (const auto& s : series) out += "," + exact(s.y[i]);
      out += "\n";
    }
    return out;
  }
  for (std::size_t k = 0; k < series.size(); ++k)
    out += (k ? "," : "") + csv_cell(name(k) + ": " + xlabel) + "," + csv_cell(column(name(k), o.ylabel));
  out += "\n";
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t k = 0; k < series.size(); ++k) {
      const auto& s = series[k];
      const bool has = i < std::min(s.x.size(), s.y.size());
      out += (k ? "," : "") + (has ? exact(s.x[i]) : "") + "," + (has ? exact(s.y[i]) : "");
    }
    out += "\n";
  }
  return out;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '&': o += "&amp;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string svg_plot(const std::vector<Series>& series, const PlotOptions& o) {
  const double W = o.width, H = o.height, ml = 70, mr = 150, mt = 26, mb = 42;
  auto tx = [&](double v) { return o.logx ? (v > 0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN()) : v; };
  auto ty = [&](double v) { return o.logy ? (v > 0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN()) : v; };
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  auto extend = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  };
  for (const auto& s : series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) extend(tx(s.x[i]), ty(s.y[i]));
  for (const auto& m : o.marks) extend(tx(m.x), ty(m.y));
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (x1 == x0) x0 -= 0.5, x1 += 0.5;
  if (y1 == y0) y0 -= std::max(0.5, std::abs(y0) * 0.1), y1 += std::max(0.5, std::abs(y1) * 0.1);
  const double pad = 0.04 * (y1 - y0);
  y0 -= pad, y1 += pad;
  if (o.logx) x0 = std::floor(x0 * 1e9) / 1e9, x1 = std::ceil(x1 * 1e9) / 1e9;
  auto X = [&](double v) { return ml + (tx(v) - x0) / (x1 - x0) * (W - ml - mr); };
  auto Y = [&](double v) { return H - mb - (ty(v) - y0) / (y1 - y0) * (H - mt - mb); };
  std::string s = "<svg xmlns='http://www.w3.org/2000/svg' width='" + px(W) + "' height='" + px(H) +
                  "' font-family='sans-serif' font-size='11'>\n";
  s += "<rect x='" + px(ml) + "' y='" + px(mt) + "' width='" + px(W - ml - mr) + "' height='" + px(H - mt - mb) +
       "' fill='white' stroke='#888'/>\n";
  if (!o.title.empty()) s += "<text x='" + px(ml) + "' y='16' font-weight='bold'>" + escape(o.title) + "</text>\n";
  for (double t : ticks(x0, x1, o.logx)) {
    const double xp = ml + (t - x0) / (x1 - x0) * (W - ml - mr);
    s += "<line x1='" + px(xp) + "' x2='" + px(xp) + "' y1='" + px(mt) + "' y2='" + px(H - mb) + "' stroke='#eee'/>";
    s += "<text x='" + px(xp) + "' y='" + px(H - mb + 14) + "' text-anchor='middle'>" + (o.logx ? "1e" + fmt(t) : fmt(t)) + "</text>\n";
  }
  for (double t : ticks(y0, y1, o.logy)) {
    const double yp = H - mb - (t - y0) / (y1 - y0) * (H - mt - mb);
    s += "<line x1='" + px(ml) + "' x2='" + px(W - mr) + "' y1='" + px(yp) + "' y2='" + px(yp) + "' stroke='#eee'/>";
    s += "<text x='" + px(ml - 4) + "' y='" + px(yp + 4) + "' text-anchor='end'>" + (o.logy ? "1e" + fmt(t) : fmt(t)) + "</text>\n";
  }
  s += "<text x='" + px((ml + W - mr) / 2) + "' y='" + px(H - 8) + "' text-anchor='middle'>" + escape(o.xlabel) + "</text>\n";
  s += "<text transform='translate(14," + px((mt + H - mb) / 2) + ") rotate(-90)' text-anchor='middle'>" + escape(o.ylabel) + "</text>\n";
  for (std::size_t k = 0; k < series.size(); ++k) {
    const auto& sr = series[k];
    const std::string col = sr.color.empty() ? kPalette[k % 8] : sr.color;
    const std::size_t n = std::min(sr.x.size(), sr.y.size());
    if (sr.points) {
      for (std::size_t i = 0; i < n; ++i) {
        const double a = X(sr.x[i]), b = Y(sr.y[i]);
        if (std::isfinite(a) && std::isfinite(b))
          s += "<circle cx='" + px(a) + "' cy='" + px(b) + "' r='" + px(sr.point_radius) + "' fill='" + col + "'/>";
      }
    } else {
      std::string d;
      bool pen = false;
      for (const auto& [a, b] : pixel_path(sr, n, X, Y)) {
        if (!std::isfinite(a) || !std::isfinite(b)) {
          pen = false;
          continue;
        }
        d += (pen ? "L" : "M") + px(a) + "," + px(b);
        pen = true;
      }
      s += "<path d='" + d + "' fill='none' stroke='" + col + "' stroke-width='1.3'" + (sr.dashed ? " stroke-dasharray='5,3'" : "") + "/>";
    }
    const double ly = mt + 14 + 16 * static_cast<double>(k);
    s += "\n<rect x='" + px(W - mr + 10) + "' y='" + px(ly - 8) + "' width='12' height='8' fill='" + col + "'/>";
    s += "<text x='" + px(W - mr + 26) + "' y='" + px(ly) + "'>" + escape(sr.name) + "</text>\n";
  }
  for (const auto& m : o.marks) {
    const double a = X(m.x), b = Y(m.y);
    if (!std::isfinite(a) || !std::isfinite(b)) continue;
    s += "<circle cx='" + px(a) + "' cy='" + px(b) + "' r='6' fill='none' stroke='black' stroke-width='2'/>";
    s += "<text x='" + px(a + 8) + "' y='" + px(b - 8) + "'>" + escape(m.label) + "</text>\n";
  }
  s += "</svg>\n";
  return s;
}

Page::Page(std::string title) : title_(std::move(title)) {}

void Page::heading(const std::string& text, int level) {
  const auto l = std::to_string(std::clamp(level, 1, 6));
  body_ += "<h" + l + ">" + escape(text) + "</h" + l + ">\n";
}
void Page::paragraph(const std::string& text) { body_ += "<p>" + escape(text) + "</p>\n"; }
void Page::preformatted(const std::string& text) { body_ += "<pre>" + escape(text) + "</pre>\n"; }
void Page::table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  body_ += "<table><tr>";
  for (const auto& h : header) body_ += "<th>" + escape(h) + "</th>";
  body_ += "</tr>\n";
  for (const auto& r : rows) {
    body_ += "<tr>";
    for (const auto& c : r) body_ += "<td>" + escape(c) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
}
void Page::plot(const std::vector<Series>& series, const PlotOptions& options) {
  std::string svg = svg_plot(series, options);
  body_ += "<div class='plot'>" + svg + "</div>\n";
  char n[8];
  std::snprintf(n, sizeof n, "%02zu-", figures_.size() + 1);
  figures_.push_back({n + slug(options.title), std::move(svg), csv_table(series, options)});
}

std::string Page::html() const {
  return "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>" + escape(title_) +
         "</title>\n<style>body{font-family:sans-serif;max-width:980px;margin:1em auto;color:#222}"
         "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}"
         "th{background:#f4f4f4}pre{background:#f8f8f8;padding:6px;overflow-x:auto}.plot{margin:0.6em 0}</style>\n"
         "</head><body>\n<h1>" +
         escape(title_) + "</h1>\n" + body_ + "</body></html>\n";
}

void Page::write(const std::string& path) const {
  std::ofstream f(path, std::ios::binary);
  f << html();
  if (!f) throw std::runtime_error(path + ": cannot write the report");
}

std::vector<std::string> Page::write_figures(const std::string& dir) const {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the figures folder: " + ec.message());
  std::vector<std::string> written;
  for (const auto& fig : figures_) {
    const std::string path = (std::filesystem::path(dir) / (fig.base + ".svg")).string();
    std::ofstream f(path, std::ios::binary);
    f << "<?xml version='1.0' encoding='utf-8'?>\n" << fig.svg;
    if (!f) throw std::runtime_error(path + ": cannot write the figure");
    const std::string data = (std::filesystem::path(dir) / (fig.base + ".csv")).string();
    std::ofstream c(data, std::ios::binary);
    c << fig.csv;
    if (!c) throw std::runtime_error(data + ": cannot write the figure's data");
    written.push_back(path);
  }
  return written;
}

}  // namespace hil::report
