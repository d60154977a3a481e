#pragma once
/// \file Strict reader for the project's numeric CSV files (samples.csv, stiffness tables, imports).
///
/// Why our own reader: every bad cell must be reported with file, line, column name and what was
/// expected, and NaN/Inf, truncated lines or ragged rows must be refused rather than guessed at.
/// General CSV libraries either accept such input silently or lose the location. The format is
/// deliberately small: comma separated, one header line, no quoting, `#` starts a comment line.
#include <cstddef>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

namespace hil::format {

struct CsvOptions {
  /// Columns that must be present and hold finite numbers in every row.
  std::vector<std::string> required;
  /// Other columns that must hold finite numbers when present (e.g. `j1`, `j2`, ...).
  std::function<bool(const std::string&)> numeric_if_present;
  /// Name shown in messages; defaults to the path.
  std::string display_name;
};

/// A parsed table. Numeric columns are stored column-wise; the rest are kept as text so that a
/// reader can pass them through untouched, and are otherwise ignored.
class CsvTable {
 public:
  std::string file;
  std::vector<std::string> header;
  /// 1-based line in the file of each data row, for messages raised after parsing.
  std::vector<std::size_t> row_line;

  std::size_t rows() const { return row_line.size(); }
  bool has(const std::string& column) const { return numeric_.count(column) || text_.count(column); }
  bool is_numeric(const std::string& column) const { return numeric_.count(column) != 0; }
  /// \throws FormatError if the column is absent or not numeric.
  const std::vector<double>& numeric(const std::string& column) const;
  const std::vector<std::string>& text(const std::string& column) const;
  /// Names of the columns kept as text (unknown extras).
  std::vector<std::string> text_columns() const;

  std::unordered_map<std::string, std::vector<double>> numeric_;
  std::unordered_map<std::string, std::vector<std::string>> text_;
};

/// Reads a CSV file. \throws FormatError naming file, line and column on any bad input.
CsvTable read_csv(const std::string& path, const CsvOptions& options);
/// Same on text already in memory (`display_name` names it in messages).
CsvTable parse_csv(const std::string& text, const CsvOptions& options);

}  // namespace hil::format
