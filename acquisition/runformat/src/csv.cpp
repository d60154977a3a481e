#include "hil/format/csv.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <unordered_set>

#include "hil/format/edit_distance.hpp"
#include "hil/format/error.hpp"

namespace hil::format {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      cells.push_back(trim(line.substr(start)));
      return cells;
    }
    cells.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

bool blank_or_comment(std::string_view line) {
  const auto t = trim(line);
  return t.empty() || t.front() == '#';
}

}  // namespace

const std::vector<double>& CsvTable::numeric(const std::string& column) const {
  const auto it = numeric_.find(column);
  if (it == numeric_.end()) throw FormatError({file, 0, 0, column}, "no such numeric column");
  return it->second;
}

const std::vector<std::string>& CsvTable::text(const std::string& column) const {
  const auto it = text_.find(column);
  if (it == text_.end()) throw FormatError({file, 0, 0, column}, "no such text column");
  return it->second;
}

std::vector<std::string> CsvTable::text_columns() const {
  std::vector<std::string> names;
  for (const auto& h : header)
    if (text_.count(h)) names.push_back(h);
  return names;
}

CsvTable read_csv(const std::string& path, const CsvOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  CsvOptions o = options;
  if (o.display_name.empty()) o.display_name = path;
  return parse_csv(ss.str(), o);
}

CsvTable parse_csv(const std::string& text, const CsvOptions& options) {
  CsvTable table;
  table.file = options.display_name;
  const std::string& file = table.file;

  // Split into lines, remembering whether the final line was terminated.
  std::vector<std::string_view> lines;
  std::string_view rest(text);
  while (!rest.empty()) {
    const std::size_t nl = rest.find('\n');
    if (nl == std::string_view::npos) {
      lines.push_back(rest);
      rest = {};
    } else {
      lines.push_back(rest.substr(0, nl));
      rest.remove_prefix(nl + 1);
    }
  }
  const bool last_terminated = !text.empty() && text.back() == '\n';

  std::size_t i = 0;
  while (i < lines.size() && blank_or_comment(lines[i])) ++i;
  if (i == lines.size()) throw FormatError({file, 0, 0, ""}, "empty file: expected a header line");

  const std::size_t header_line = i + 1;
  for (auto cell : split(lines[i])) table.header.emplace_back(cell);
  const std::size_t ncol = table.header.size();
  std::unordered_set<std::string> seen;
  for (std::size_t c = 0; c < ncol; ++c) {
    const auto& h = table.header[c];
    if (h.empty()) throw FormatError({file, header_line, c + 1, ""}, "empty column name in header");
    if (!seen.insert(h).second) throw FormatError({file, header_line, c + 1, h}, "column name appears twice in header");
  }
  for (const auto& req : options.required) {
    if (seen.count(req)) continue;
    std::string hint;
    std::size_t best = 3;
    for (std::size_t c = 0; c < ncol; ++c) {
      const auto d = edit_distance(req, table.header[c]);
      if (d < best && !std::count(options.required.begin(), options.required.end(), table.header[c])) {
        best = d;
        hint = " (column " + std::to_string(c + 1) + " is '" + table.header[c] + "': misspelt?)";
      }
    }
    throw FormatError({file, header_line, 0, req}, "required column is missing from the header" + hint);
  }

  std::vector<bool> numeric(ncol);
  std::vector<std::vector<double>*> num_col(ncol, nullptr);
  std::vector<std::vector<std::string>*> txt_col(ncol, nullptr);
  for (std::size_t c = 0; c < ncol; ++c) {
    const auto& h = table.header[c];
    numeric[c] = std::count(options.required.begin(), options.required.end(), h) ||
                 (options.numeric_if_present && options.numeric_if_present(h));
    if (numeric[c]) num_col[c] = &table.numeric_[h];
    else txt_col[c] = &table.text_[h];
  }

  for (++i; i < lines.size(); ++i) {
    const std::size_t line_no = i + 1;
    if (blank_or_comment(lines[i])) {
      if (trim(lines[i]).empty() && i + 1 < lines.size() && !blank_or_comment(lines[i + 1]))
        throw FormatError({file, line_no, 0, ""}, "empty line inside the data");
      continue;
    }
    const auto cells = split(lines[i]);
    const bool is_last = (i + 1 == lines.size());
    if (cells.size() < ncol) {
      if (is_last && !last_terminated)
        throw FormatError({file, line_no, cells.size(), table.header[cells.size() - 1]},
                          "truncated last line: " + std::to_string(cells.size()) + " of " +
                              std::to_string(ncol) + " cells and no line end (file cut while writing?)");
      throw FormatError({file, line_no, cells.size() + 1, table.header[cells.size()]},
                        "row has " + std::to_string(cells.size()) + " cells, header has " + std::to_string(ncol));
    }
    if (cells.size() > ncol)
      throw FormatError({file, line_no, ncol + 1, ""},
                        "row has " + std::to_string(cells.size()) + " cells, header has " + std::to_string(ncol));
    for (std::size_t c = 0; c < ncol; ++c) {
      const auto cell = cells[c];
      if (!numeric[c]) {
        txt_col[c]->emplace_back(cell);
        continue;
      }
      if (cell.empty()) throw FormatError({file, line_no, c + 1, table.header[c]}, "empty cell, expected a number");
      double v = 0.0;
      const char* first = cell.data();
      if (*first == '+') ++first;  // from_chars refuses a leading '+', which people do write
      const auto [ptr, ec] = std::from_chars(first, cell.data() + cell.size(), v);
      if (ec != std::errc() || ptr != cell.data() + cell.size())
        throw FormatError({file, line_no, c + 1, table.header[c]},
                          "expected a number, found '" + std::string(cell) + "'");
      if (!std::isfinite(v))
        throw FormatError({file, line_no, c + 1, table.header[c]},
                          "expected a finite number, found '" + std::string(cell) + "'");
      num_col[c]->push_back(v);
    }
    table.row_line.push_back(line_no);
  }
  return table;
}

}  // namespace hil::format
