#pragma once
/// \file The one reader for the project's delimited text files: samples.csv, stiffness tables, and
/// the marker + force-plate exports `hil import` reads.
///
/// Why our own reader: every bad cell must be reported with file, line, column name and what was
/// expected, and NaN/Inf, truncated lines or ragged rows must be refused rather than guessed at.
/// General CSV libraries either accept such input silently or lose the location. The format is
/// deliberately small: no quoting, `#` starts a comment line. By default (the project's own files)
/// it is comma separated with one header line, and every numeric cell must hold a finite number;
/// the options below relax exactly what lab software exports need (another delimiter, no header
/// line, a byte-order mark, blank lines, empty or NaN cells), each still checked with its location.
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace hil::error {
struct Location;
}  // namespace hil::error

namespace hil::format {

/// What an empty or NaN cell in a numeric column means.
enum class MissingCells {
  refuse,  ///< an error naming file, line and column (the project's own files)
  nan,     ///< kept as NaN, for the reader to drop or fill the row (lab exports)
};

struct CsvOptions {
  /// Columns that must be present and hold finite numbers in every row.
  std::vector<std::string> required;
  /// Other columns that must hold finite numbers when present (e.g. `j1`, `j2`, ...).
  std::function<bool(const std::string&)> numeric_if_present;
  /// Name shown in messages; defaults to the path.
  std::string display_name;
  /// The cell separator (`,`, `;`, `\t`, ...).
  char delimiter = ',';
  /// Empty: the first line that is not blank or a comment names the columns. Otherwise the file has
  /// no header line and these name its columns in order; every non-comment line is data.
  std::vector<std::string> column_names;
  /// Empty and NaN (any case, any sign) cells in numeric columns; Inf and text are always refused.
  MissingCells missing = MissingCells::refuse;
  /// Skip blank lines between data rows instead of refusing them.
  bool skip_blank_lines = false;
  /// Skip a UTF-8 byte-order mark at the start instead of taking it into the first column name.
  bool skip_byte_order_mark = false;
};

/// A parsed table. Numeric columns are stored column-wise; the rest are kept as text so that a
/// reader can pass them through untouched, and are otherwise ignored.
class CsvTable {
 public:
  std::string file;
  std::vector<std::string> header;
  /// 1-based line of the header, 0 when the names were given in the options.
  std::size_t header_line = 0;
  /// 1-based line in the file of each data row, for messages raised after parsing.
  std::vector<std::size_t> row_line;

  std::size_t rows() const { return row_line.size(); }
  bool has(const std::string& column) const { return numeric_.count(column) || text_.count(column); }
  bool is_numeric(const std::string& column) const { return numeric_.count(column) != 0; }
  /// \throws error::FormatError if the column is absent or not numeric.
  const std::vector<double>& numeric(const std::string& column) const;
  const std::vector<std::string>& text(const std::string& column) const;
  /// Names of the columns kept as text (unknown extras).
  std::vector<std::string> text_columns() const;

  std::unordered_map<std::string, std::vector<double>> numeric_;
  std::unordered_map<std::string, std::vector<std::string>> text_;
};

/// Reads one numeric cell as parse_csv does (trimmed; a leading `+` accepted) and returns it, or
/// NaN for an empty or NaN cell under MissingCells::nan. \throws error::FormatError at `where` (with the
/// column's name as field) for text, Inf, and under MissingCells::refuse for empty or NaN cells.
double read_number(std::string_view cell, const error::Location& where, MissingCells missing);

/// Reads a CSV file. \throws error::FormatError naming file, line and column on any bad input.
CsvTable read_csv(const std::string& path, const CsvOptions& options);
/// Same on text already in memory (`display_name` names it in messages).
CsvTable parse_csv(const std::string& text, const CsvOptions& options);

}  // namespace hil::format
