#include <hil/report/html.hpp>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
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

/// An SVG element's opening tag: its size for a standalone file, a viewBox so that a page can
/// scale it to its column.
std::string svg_open(double W, double H) {
  return "<svg xmlns='http://www.w3.org/2000/svg' width='" + px(W) + "' height='" + px(H) + "' viewBox='0 0 " + px(W) + " " + px(H) +
         "' font-family='sans-serif' font-size='11'>\n";
}

std::string text_at(double x, double y, const std::string& text, const char* anchor = "start", const char* extra = "") {
  return "<text x='" + px(x) + "' y='" + px(y) + "' text-anchor='" + anchor + "'" + extra + ">" + escape(text) + "</text>";
}

/// A legend label within `room` pixels: a label longer than the room (at ~6.2 px a character of
/// the 11 px font) is condensed to fit rather than cut at the figure's edge.
std::string legend_text(double x, double y, const std::string& text, double room) {
  std::size_t chars = 0;
  for (unsigned char c : text) chars += (c & 0xC0) != 0x80 ? 1 : 0;  // UTF-8 code points
  if (6.2 * static_cast<double>(chars) <= room) return text_at(x, y, text);
  return text_at(x, y, text, "start", (" textLength='" + px(room) + "' lengthAdjust='spacingAndGlyphs'").c_str());
}

/// Percent-encodes text for a data: URL.
std::string url_encode(const std::string& s) {
  static const char* hex = "0123456789ABCDEF";
  std::string o;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      o += static_cast<char>(c);
    } else {
      o += '%';
      o += hex[c >> 4];
      o += hex[c & 15];
    }
  }
  return o;
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

/// "name (unit)" for a column; the plot's axis label is the unit, the quantity, or both as
/// "quantity (unit)" (then the unit is the column's).
std::string column(const std::string& name, const std::string& axis_label) {
  std::string label = axis_label;
  if (const auto open = label.rfind(" ("); open != std::string::npos && !label.empty() && label.back() == ')')
    label = label.substr(open + 2, label.size() - open - 3);
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
  std::string s = svg_open(W, H);
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
  int legend = 0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const auto& sr = series[k];
    const std::string col = sr.color.empty() ? kPalette[k % 8] : sr.color;
    const std::size_t n = std::min(sr.x.size(), sr.y.size());
    if (sr.points) {
      std::set<std::pair<long, long>> drawn;  // one circle per pixel: a cloud of 10^5 samples stays a small page
      for (std::size_t i = 0; i < n; ++i) {
        const double a = X(sr.x[i]), b = Y(sr.y[i]);
        if (std::isfinite(a) && std::isfinite(b) && drawn.insert({std::lround(a), std::lround(b)}).second)
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
    if (sr.name.empty()) continue;  // unnamed: a second line of a named series (e.g. a bound's lower side)
    const double ly = mt + 14 + 16 * static_cast<double>(legend++);
    s += "\n<rect x='" + px(W - mr + 10) + "' y='" + px(ly - 8) + "' width='12' height='8' fill='" + col + "'/>";
    s += legend_text(W - mr + 26, ly, sr.name, mr - 30) + "\n";
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

std::string svg_forest(const std::vector<Interval>& rows, const std::string& title, const std::string& reference_label) {
  // Label column, interval column (each row on its own scale), value column.
  // The value column holds "value  [lower, upper]": up to 40 characters of 7 px.
  const double W = 820, ml = 190, mr = 300, mt = 30, row_h = 36, mb = 34;
  const double H = mt + row_h * static_cast<double>(std::max<std::size_t>(rows.size(), 1)) + mb;
  const double x0 = ml, x1 = W - mr;
  std::string s = svg_open(W, H);
  if (!title.empty()) s += text_at(ml, 18, title, "start", " font-weight='bold'") + "\n";
  bool any_reference = false, any_truth = false;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto& r = rows[k];
    const double y = mt + row_h * (static_cast<double>(k) + 0.5);
    double lo = std::min(r.lower, r.value), hi = std::max(r.upper, r.value);
    for (double v : {r.reference, r.truth})
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!std::isfinite(lo) || !std::isfinite(hi)) lo = hi = std::isfinite(r.value) ? r.value : 0.0;
    if (!(hi > lo)) {
      const double d = std::max(std::abs(lo) * 0.1, 1e-12);
      lo -= d, hi += d;
    }
    const double pad = 0.08 * (hi - lo);
    lo -= pad, hi += pad;
    auto X = [&](double v) { return x0 + (v - lo) / (hi - lo) * (x1 - x0); };
    if (k % 2 == 0) s += "<rect x='0' y='" + px(y - row_h / 2) + "' width='" + px(W) + "' height='" + px(row_h) + "' fill='#f6f8fa'/>";
    s += text_at(ml - 8, y + 4, r.name + (r.unit.empty() || r.unit == "-" ? "" : " (" + r.unit + ")"), "end");
    s += "<line x1='" + px(x0) + "' x2='" + px(x1) + "' y1='" + px(y) + "' y2='" + px(y) + "' stroke='#ccc'/>";
    s += text_at(x0, y + 16, fmt(lo), "start", " font-size='10' fill='#777'");
    s += text_at(x1, y + 16, fmt(hi), "end", " font-size='10' fill='#777'");
    if (std::isfinite(r.reference)) {
      any_reference = true;
      s += "<line x1='" + px(X(r.reference)) + "' x2='" + px(X(r.reference)) + "' y1='" + px(y - 9) + "' y2='" + px(y + 9) +
           "' stroke='#888' stroke-width='2'/>";
    }
    if (std::isfinite(r.lower) && std::isfinite(r.upper))
      s += "<line x1='" + px(X(r.lower)) + "' x2='" + px(X(r.upper)) + "' y1='" + px(y) + "' y2='" + px(y) +
           "' stroke='#1f77b4' stroke-width='5' stroke-linecap='round' opacity='0.55'/>";
    if (std::isfinite(r.value)) s += "<circle cx='" + px(X(r.value)) + "' cy='" + px(y) + "' r='4.5' fill='#1f77b4'/>";
    if (std::isfinite(r.truth)) {
      any_truth = true;
      const double t = X(r.truth);
      s += "<path d='M" + px(t) + "," + px(y - 7) + "L" + px(t + 6) + "," + px(y) + "L" + px(t) + "," + px(y + 7) + "L" + px(t - 6) + "," +
           px(y) + "Z' fill='none' stroke='#d62728' stroke-width='2'/>";
    }
    s += text_at(x1 + 10, y + 4, fmt(r.value) + "  [" + fmt(r.lower) + ", " + fmt(r.upper) + "]");
    s += "\n";
  }
  // The legend under the rows.
  const double ly = H - 12;
  double lx = ml;
  s += "<circle cx='" + px(lx) + "' cy='" + px(ly - 4) + "' r='4' fill='#1f77b4'/>" + text_at(lx + 8, ly, "value, 95 % interval");
  lx += 150;
  if (any_reference) {
    s += "<line x1='" + px(lx) + "' x2='" + px(lx) + "' y1='" + px(ly - 11) + "' y2='" + px(ly + 2) + "' stroke='#888' stroke-width='2'/>" +
         text_at(lx + 6, ly, reference_label);
    lx += 110;
  }
  if (any_truth) s += text_at(lx, ly, "◇ truth", "start", " fill='#d62728'");
  s += text_at(W - 6, ly, "each row on its own scale", "end", " font-size='9' fill='#888'");
  s += "\n</svg>\n";
  return s;
}

std::string svg_bars(const Bars& b, const PlotOptions& o) {
  const std::size_t ns = std::max<std::size_t>(b.series.size(), 1), ng = b.groups.size();
  const double W = o.width, ml = 190, mr = 150, mt = 30, mb = 42, bar_h = 11;
  const double group_h = bar_h * static_cast<double>(ns) + 10;
  const double H = mt + group_h * static_cast<double>(std::max<std::size_t>(ng, 1)) + mb;
  auto at = [](const std::vector<std::vector<double>>& v, std::size_t k, std::size_t g) {
    return k < v.size() && g < v[k].size() ? v[k][g] : kNoValue;
  };
  double lo = 0.0, hi = 0.0;  // bars start at zero
  for (std::size_t k = 0; k < ns; ++k)
    for (std::size_t g = 0; g < ng; ++g)
      for (double v : {at(b.value, k, g), at(b.lower, k, g), at(b.upper, k, g)})
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(hi > lo)) hi = lo + 1.0;
  const double pad = 0.05 * (hi - lo);
  if (lo < 0) lo -= pad;
  hi += pad;
  auto X = [&](double v) { return ml + (v - lo) / (hi - lo) * (W - ml - mr); };
  std::string s = svg_open(W, H);
  if (!o.title.empty()) s += text_at(ml, 18, o.title, "start", " font-weight='bold'") + "\n";
  for (double t : ticks(lo, hi, false)) {
    s += "<line x1='" + px(X(t)) + "' x2='" + px(X(t)) + "' y1='" + px(mt) + "' y2='" + px(H - mb) + "' stroke='#eee'/>";
    s += text_at(X(t), H - mb + 14, fmt(t), "middle");
  }
  s += "<line x1='" + px(X(0)) + "' x2='" + px(X(0)) + "' y1='" + px(mt) + "' y2='" + px(H - mb) + "' stroke='#888'/>\n";
  s += text_at((ml + W - mr) / 2, H - 8, o.xlabel, "middle") + "\n";
  for (std::size_t g = 0; g < ng; ++g) {
    const double y0 = mt + group_h * static_cast<double>(g) + 5;
    s += text_at(ml - 8, y0 + bar_h * static_cast<double>(ns) / 2 + 4, b.groups[g], "end");
    for (std::size_t k = 0; k < ns; ++k) {
      const std::string col = k < b.colors.size() && !b.colors[k].empty() ? b.colors[k] : kPalette[k % 8];
      const double y = y0 + bar_h * static_cast<double>(k);
      const double v = at(b.value, k, g);
      if (!std::isfinite(v)) {
        s += text_at(X(0) + 4, y + bar_h - 2, "not scored", "start", " font-size='9' fill='#888'");
        continue;
      }
      const double a = std::min(X(0), X(v)), w = std::abs(X(v) - X(0));
      s += "<rect x='" + px(a) + "' y='" + px(y + 1) + "' width='" + px(std::max(w, 0.5)) + "' height='" + px(bar_h - 2) + "' fill='" +
           col + "'/>";
      const double l = at(b.lower, k, g), u = at(b.upper, k, g);
      if (std::isfinite(l) && std::isfinite(u)) {
        const double ym = y + bar_h / 2;
        s += "<path d='M" + px(X(l)) + "," + px(ym) + "L" + px(X(u)) + "," + px(ym) + "M" + px(X(l)) + "," + px(ym - 3) + "L" + px(X(l)) +
             "," + px(ym + 3) + "M" + px(X(u)) + "," + px(ym - 3) + "L" + px(X(u)) + "," + px(ym + 3) +
             "' stroke='#222' stroke-width='1.2'/>";
      }
    }
    s += "\n";
  }
  for (std::size_t k = 0; k < b.series.size(); ++k) {
    const std::string col = k < b.colors.size() && !b.colors[k].empty() ? b.colors[k] : kPalette[k % 8];
    const double ly = mt + 14 + 16 * static_cast<double>(k);
    s += "<rect x='" + px(W - mr + 10) + "' y='" + px(ly - 8) + "' width='12' height='8' fill='" + col + "'/>" +
         legend_text(W - mr + 26, ly, b.series[k], mr - 30) + "\n";
  }
  s += "</svg>\n";
  return s;
}

std::string svg_timeline(const std::vector<Span>& spans, const PlotOptions& o) {
  const double W = o.width, ml = 20, mr = 20, mt = 30, row_h = 54, mb = 42, H = mt + row_h + mb;
  double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
  for (const auto& sp : spans) t0 = std::min(t0, sp.start), t1 = std::max(t1, sp.end);
  if (!(t1 > t0)) t0 = 0, t1 = 1;
  auto X = [&](double t) { return ml + (t - t0) / (t1 - t0) * (W - ml - mr); };
  std::vector<std::string> labels;  // distinct labels, first-seen order: their colours
  std::string s = svg_open(W, H);
  if (!o.title.empty()) s += text_at(ml, 18, o.title, "start", " font-weight='bold'") + "\n";
  for (double t : ticks(t0, t1, false)) {
    s += "<line x1='" + px(X(t)) + "' x2='" + px(X(t)) + "' y1='" + px(mt + row_h) + "' y2='" + px(mt + row_h + 5) + "' stroke='#888'/>";
    s += text_at(X(t), mt + row_h + 18, fmt(t), "middle");
  }
  s += text_at((ml + W - mr) / 2, H - 8, o.xlabel, "middle") + "\n";
  for (const auto& sp : spans) {
    std::string col;
    if (sp.label == "none") col = "#b7dfb0";
    else if (sp.label == "not diagnosed") col = "#e4e4e4";
    else {
      auto it = std::find(labels.begin(), labels.end(), sp.label);
      if (it == labels.end()) it = labels.insert(labels.end(), sp.label);
      col = kPalette[static_cast<std::size_t>(it - labels.begin()) % 8];
    }
    const double a = X(sp.start), b = X(sp.end), w = std::max(b - a - 2, 1.0);
    s += "<rect x='" + px(a + 1) + "' y='" + px(mt) + "' width='" + px(w) + "' height='" + px(row_h) + "' fill='" + col +
         "' stroke='#666'/>";
    const bool dark = sp.label != "none" && sp.label != "not diagnosed";
    const std::string fill = dark ? " fill='white'" : "";
    const std::string fit = 6.6 * static_cast<double>(sp.label.size()) > w - 8
                                ? " textLength='" + px(std::max(w - 8, 4.0)) + "' lengthAdjust='spacingAndGlyphs'"
                                : "";
    s += text_at(a + 5, mt + 22, sp.label, "start", (" font-weight='bold'" + fill + fit).c_str());
    if (!sp.detail.empty()) {
      const std::string fit2 = 6.0 * static_cast<double>(sp.detail.size()) > w - 8
                                   ? " textLength='" + px(std::max(w - 8, 4.0)) + "' lengthAdjust='spacingAndGlyphs'"
                                   : "";
      s += text_at(a + 5, mt + 40, sp.detail, "start", (fill + fit2).c_str());
    }
    s += "\n";
  }
  s += "</svg>\n";
  return s;
}

Page::Page(std::string title) : title_(std::move(title)) {}

void Page::end_figures() {
  if (!in_figures_) return;
  body_ += "</div>\n";
  in_figures_ = false;
}

void Page::figure(std::string svg, std::string csv, const std::string& title, bool wide) {
  if (!in_figures_) body_ += "<div class='figs'>\n";
  in_figures_ = true;
  char n[8];
  std::snprintf(n, sizeof n, "%02zu-", figures_.size() + 1);
  body_ += std::string("<figure class='fig") + (wide ? " wide" : "") + "' id='fig-" + std::to_string(figures_.size() + 1) + "'>" + svg +
           "</figure>\n";
  figures_.push_back({n + slug(title), std::move(svg), std::move(csv)});
}

void Page::verdict(const Verdict& v) {
  std::string h = "<section id='verdict' class='verdict " + escape(v.kind) + "'>\n<p class='headline'>" + escape(v.headline) + "</p>\n";
  if (!v.facts.empty()) {
    h += "<dl>";
    for (const auto& [k, x] : v.facts) h += "<dt>" + escape(k) + "</dt><dd>" + escape(x) + "</dd>";
    h += "</dl>\n";
  }
  if (!v.next.empty()) h += "<p class='next'><b>Next:</b> " + escape(v.next) + "</p>\n";
  verdict_ = h + "</section>\n";
}

void Page::heading(const std::string& text, int level) {
  end_figures();
  const int lv = std::clamp(level, 1, 6);
  const auto l = std::to_string(lv);
  std::string id;
  if (lv == 2) {
    id = "s" + std::to_string(toc_.size() + 1) + "-" + slug(text);
    toc_.emplace_back(id, text);
  }
  body_ += "<h" + l + (id.empty() ? "" : " id='" + id + "'") + ">" + escape(text) + "</h" + l + ">\n";
}
void Page::paragraph(const std::string& text) {
  end_figures();
  body_ += "<p>" + escape(text) + "</p>\n";
}
void Page::preformatted(const std::string& text) {
  end_figures();
  body_ += "<pre>" + escape(text) + "</pre>\n";
}
void Page::table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                 const std::vector<std::size_t>& emphasised) {
  end_figures();
  body_ += "<div class='tablewrap'><table><thead><tr>";
  for (const auto& h : header) body_ += "<th>" + escape(h) + "</th>";
  body_ += "</tr></thead><tbody>\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const bool em = std::find(emphasised.begin(), emphasised.end(), i) != emphasised.end();
    body_ += em ? "<tr class='em'>" : "<tr>";
    for (const auto& c : rows[i]) body_ += "<td>" + escape(c) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</tbody></table></div>\n";
}
void Page::plot(const std::vector<Series>& series, const PlotOptions& options) {
  figure(svg_plot(series, options), csv_table(series, options), options.title, options.wide);
}
void Page::forest(const std::vector<Interval>& rows, const std::string& title, const std::string& reference_label) {
  std::string csv = "parameter,unit,value,lower,upper," + csv_cell(reference_label) + ",truth\n";
  for (const auto& r : rows)
    csv += csv_cell(r.name) + "," + csv_cell(r.unit) + "," + exact(r.value) + "," + exact(r.lower) + "," + exact(r.upper) + "," +
           exact(r.reference) + "," + exact(r.truth) + "\n";
  figure(svg_forest(rows, title, reference_label), std::move(csv), title, false);
}
void Page::bars(const Bars& b, const PlotOptions& options) {
  std::string csv = "group";
  for (const auto& n : b.series) csv += "," + csv_cell(n) + "," + csv_cell(n + ": lower") + "," + csv_cell(n + ": upper");
  csv += "\n";
  auto at = [](const std::vector<std::vector<double>>& v, std::size_t k, std::size_t g) {
    return k < v.size() && g < v[k].size() ? v[k][g] : kNoValue;
  };
  for (std::size_t g = 0; g < b.groups.size(); ++g) {
    csv += csv_cell(b.groups[g]);
    for (std::size_t k = 0; k < b.series.size(); ++k)
      csv += "," + exact(at(b.value, k, g)) + "," + exact(at(b.lower, k, g)) + "," + exact(at(b.upper, k, g));
    csv += "\n";
  }
  figure(svg_bars(b, options), std::move(csv), options.title, options.wide);
}
void Page::timeline(const std::vector<Span>& spans, const PlotOptions& options) {
  std::string csv = "start,end,label,detail\n";
  for (const auto& sp : spans) csv += exact(sp.start) + "," + exact(sp.end) + "," + csv_cell(sp.label) + "," + csv_cell(sp.detail) + "\n";
  figure(svg_timeline(spans, options), std::move(csv), options.title, options.wide);
}
void Page::text_download(const std::string& label, const std::string& file_name, const std::string& text) {
  end_figures();
  body_ += "<details><summary>" + escape(label) + "</summary>\n<p><a download='" + escape(file_name) +
           "' href='data:text/plain;charset=utf-8," + url_encode(text) + "'>Save as " + escape(file_name) + "</a></p>\n<pre>" +
           escape(text) + "</pre></details>\n";
}

// The page's style: the verdict first in colour, figures in a grid two columns wide where the
// screen allows (one below ~1,250 px), every SVG scaled to its column, long text wrapped rather
// than cut, wide tables scrolled within their box, and print (Chromium's PDF) one figure per
// width without splitting a figure or a table row.
static const char* kStyle =
    "body{font-family:system-ui,'DejaVu Sans',sans-serif;max-width:1500px;margin:0 auto;padding:0 24px 40px;color:#222;line-height:1.4}"
    "h1{font-size:1.6em;margin:18px 0 10px}h2{margin-top:1.6em;border-bottom:1px solid #ddd;padding-bottom:3px}"
    ".verdict{border-left:8px solid #1f77b4;background:#f2f7fc;padding:12px 18px;margin:0 0 14px}"
    ".verdict.none{border-color:#2ca02c;background:#f2faf2}.verdict.unexplained{border-color:#d62728;background:#fcf2f2}"
    ".verdict.identified{border-color:#9467bd;background:#f7f4fb}"
    ".verdict .headline{font-size:1.3em;font-weight:600;margin:0 0 8px}"
    ".verdict dl{display:grid;grid-template-columns:max-content 1fr;gap:3px 18px;margin:0}"
    ".verdict dt{color:#555}.verdict dd{margin:0;font-variant-numeric:tabular-nums}.verdict .next{margin:10px 0 0}"
    "nav.toc ol{columns:2 280px;margin:4px 0;padding-left:22px}nav.toc a{color:#1f5f99}"
    ".figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(min(100%,600px),1fr));gap:14px 22px;margin:10px 0}"
    ".fig{margin:0;min-width:0}.fig.wide{grid-column:1/-1}.fig svg{display:block;width:100%;height:auto}"
    ".tablewrap{max-width:100%;overflow-x:auto;margin:8px 0}"
    "table{border-collapse:collapse;font-variant-numeric:tabular-nums}td,th{border:1px solid #ccc;padding:3px 9px;text-align:right;"
    "vertical-align:top}td:first-child,th:first-child{text-align:left}th{background:#f2f2f2}tr.em td{font-weight:600;background:#eef5fb}"
    "td{white-space:nowrap}td:last-child{text-align:left;white-space:normal}th:last-child{text-align:left}"
    "@media (max-width:1200px){td{white-space:normal}td,th{padding:3px 5px;overflow-wrap:anywhere}}"
    "pre{background:#f7f7f7;padding:8px;white-space:pre-wrap;overflow-wrap:anywhere}details{margin:10px 0}summary{cursor:pointer}"
    "@media print{body{max-width:none;padding:0}.figs{display:block}.fig{break-inside:avoid;margin:0 0 10px}"
    "h2,h3{break-after:avoid}tr{break-inside:avoid}.tablewrap{overflow:visible}details pre{display:none}}";

std::string Page::html() const {
  std::string toc;
  if (!toc_.empty()) {
    toc = "<nav class='toc'><b>Contents</b><ol>";
    for (const auto& [id, text] : toc_) toc += "<li><a href='#" + id + "'>" + escape(text) + "</a></li>";
    toc += "</ol></nav>\n";
  }
  return "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'><meta name='viewport' content='width=device-width,initial-scale=1'>"
         "<title>" +
         escape(title_) + "</title>\n<style>" + kStyle + "</style>\n</head><body>\n<h1>" + escape(title_) + "</h1>\n" + verdict_ + toc +
         body_ + (in_figures_ ? "</div>\n" : "") + "</body></html>\n";
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
