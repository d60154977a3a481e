#include <hil/format/csv.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_set>

#include <hil/format/edit_distance.hpp>
#include <hil/error/error.hpp>

namespace hil::format {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line, char delimiter) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t d = line.find(delimiter, start);
    if (d == std::string_view::npos) {
      cells.push_back(trim(line.substr(start)));
      return cells;
    }
    cells.push_back(trim(line.substr(start, d - start)));
    start = d + 1;
  }
}

/// `nan` in any case with an optional sign (what from_chars reads as NaN, without a payload).
bool is_nan_text(std::string_view s) {
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) s.remove_prefix(1);
  if (s.size() != 3) return false;
  const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  return lower(s[0]) == 'n' && lower(s[1]) == 'a' && lower(s[2]) == 'n';
}

bool blank_or_comment(std::string_view line) {
  const auto t = trim(line);
  return t.empty() || t.front() == '#';
}

}  // namespace

double read_number(std::string_view cell, const error::Location& where, MissingCells missing) {
  cell = trim(cell);
  if (missing == MissingCells::nan && (cell.empty() || is_nan_text(cell))) return std::numeric_limits<double>::quiet_NaN();
  if (cell.empty()) throw error::FormatError(where, "empty cell, expected a number");
  double v = 0.0;
  const char* first = cell.data();
  if (*first == '+') ++first;  // from_chars refuses a leading '+', which people do write
  const auto [ptr, ec] = std::from_chars(first, cell.data() + cell.size(), v);
  if (ec != std::errc() || ptr != cell.data() + cell.size())
    throw error::FormatError(where, "expected a number, found '" + std::string(cell) + "'");
  if (!std::isfinite(v)) throw error::FormatError(where, "expected a finite number, found '" + std::string(cell) + "'");
  return v;
}

const std::vector<double>& CsvTable::numeric(const std::string& column) const {
  const auto it = numeric_.find(column);
  if (it == numeric_.end()) throw error::FormatError({file, 0, 0, column}, "no such numeric column");
  return it->second;
}

const std::vector<std::string>& CsvTable::text(const std::string& column) const {
  const auto it = text_.find(column);
  if (it == text_.end()) throw error::FormatError({file, 0, 0, column}, "no such text column");
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
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open file");
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
  const char delim = options.delimiter;

  // Split into lines, remembering whether the final line was terminated.
  std::vector<std::string_view> lines;
  std::string_view rest(text);
  if (options.skip_byte_order_mark && rest.substr(0, 3) == "\xEF\xBB\xBF") rest.remove_prefix(3);
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
  std::size_t header_line = 0;  // the line the names come from, 0 when given in the options
  if (!options.column_names.empty()) {
    table.header = options.column_names;  // no header line: the data starts at line i + 1
  } else {
    if (i == lines.size()) throw error::FormatError({file, 0, 0, ""}, "empty file: expected a header line");
    header_line = i + 1;
    for (auto cell : split(lines[i++], delim)) table.header.emplace_back(cell);
  }
  table.header_line = header_line;
  const std::size_t ncol = table.header.size();
  const std::string names_from = header_line ? "in header" : "in the given column names";
  std::unordered_set<std::string> seen;
  for (std::size_t c = 0; c < ncol; ++c) {
    const auto& h = table.header[c];
    if (h.empty()) throw error::FormatError({file, header_line, c + 1, ""}, "empty column name " + names_from);
    if (!seen.insert(h).second) throw error::FormatError({file, header_line, c + 1, h}, "column name appears twice " + names_from);
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
    throw error::FormatError({file, header_line, 0, req}, "required column is missing from the header" + hint);
  }
  const std::string expected = header_line ? "header has " + std::to_string(ncol)
                                           : "expected " + std::to_string(ncol) + " (one per given column name)";

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

  for (; i < lines.size(); ++i) {
    const std::size_t line_no = i + 1;
    if (blank_or_comment(lines[i])) {
      if (!options.skip_blank_lines && trim(lines[i]).empty() && i + 1 < lines.size() && !blank_or_comment(lines[i + 1]))
        throw error::FormatError({file, line_no, 0, ""}, "empty line inside the data");
      continue;
    }
    const auto cells = split(lines[i], delim);
    const bool is_last = (i + 1 == lines.size());
    if (cells.size() < ncol) {
      if (is_last && !last_terminated)
        throw error::FormatError({file, line_no, cells.size(), table.header[cells.size() - 1]},
                                 "truncated last line: " + std::to_string(cells.size()) + " of " + std::to_string(ncol) +
                                     " cells and no line end (file cut while writing?)");
      throw error::FormatError({file, line_no, cells.size() + 1, table.header[cells.size()]},
                               "row has " + std::to_string(cells.size()) + " cells, " + expected);
    }
    if (cells.size() > ncol)
      throw error::FormatError({file, line_no, ncol + 1, ""}, "row has " + std::to_string(cells.size()) + " cells, " + expected);
    for (std::size_t c = 0; c < ncol; ++c) {
      if (numeric[c]) num_col[c]->push_back(read_number(cells[c], {file, line_no, c + 1, table.header[c]}, options.missing));
      else txt_col[c]->emplace_back(cells[c]);
    }
    table.row_line.push_back(line_no);
  }
  return table;
}

}  // namespace hil::format
