// The one CSV reader's options (issue 14 item 2): delimiter, column names instead of a header
// line, missing cells kept as NaN, blank lines and a byte-order mark skipped; each default refusal
// still names file, line and column.
#include <gtest/gtest.h>

#include <cmath>

#include <hil/format/csv.hpp>
#include <hil/test/files.hpp>

using hil::format::CsvOptions;
using hil::format::MissingCells;
using hil::format::parse_csv;
using hil::test::fails_with;

namespace {
CsvOptions numeric(const std::vector<std::string>& required) {
  CsvOptions o;
  o.required = required;
  o.display_name = "t.csv";
  return o;
}
auto parse(const std::string& text, const CsvOptions& o) {
  return [text, o] { parse_csv(text, o); };
}
}  // namespace

TEST(Csv, DelimiterOption) {
  auto o = numeric({"a"});
  o.delimiter = ';';
  const auto t = parse_csv("a;b;note\n1;2,5;x y\n", o);
  ASSERT_EQ(t.rows(), 1u);
  EXPECT_EQ(t.numeric("a")[0], 1.0);
  EXPECT_EQ(t.text("b")[0], "2,5");  // a comma is an ordinary character under ';'
  EXPECT_EQ(t.text("note")[0], "x y");
  o.required = {"a", "b"};
  // A wrong delimiter shows as a number that is not one, at its cell.
  EXPECT_TRUE(fails_with(parse("a;b\n1;2,5\n", o), 2, "b", "expected a number, found '2,5'"));
  o.delimiter = '\t';
  EXPECT_EQ(parse_csv("a\tb\n1\t2\n", o).numeric("b")[0], 2.0);
  // The default stays a comma: a semicolon file is one column named "a;b", so `a` is missing.
  EXPECT_TRUE(fails_with(parse("a;b\n1;2\n", numeric({"a"})), 1, "a", "required column is missing from the header"));
}

TEST(Csv, ColumnNamesInsteadOfHeader) {
  auto o = numeric({"a", "b"});
  o.column_names = {"a", "b", "c"};
  const auto t = parse_csv("# no header\n1,2,x\n3,4,y\n", o);
  EXPECT_EQ(t.header, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(t.header_line, 0u);
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.row_line[0], 2u);
  EXPECT_EQ(t.numeric("b")[1], 4.0);
  EXPECT_EQ(t.text("c")[0], "x");
  // With a header line the reader records where it was.
  EXPECT_EQ(parse_csv("\na,b\n1,2\n", numeric({"a", "b"})).header_line, 2u);
  // Refusals: ragged rows against the given names, a cut last line, a missing required name.
  EXPECT_TRUE(fails_with(parse("1,2,x\n3,4\n", o), 2, "c", "row has 2 cells, expected 3 (one per given column name)"));
  EXPECT_TRUE(fails_with(parse("1,2,x,9\n", o), 1, "", "row has 4 cells, expected 3 (one per given column name)"));
  EXPECT_TRUE(fails_with(parse("1,2,x\n3,4", o), 2, "b", "truncated last line: 2 of 3 cells"));
  o.column_names = {"a", "c"};
  EXPECT_TRUE(fails_with(parse("1,2\n", o), 0, "b", "required column is missing"));
  o.column_names = {"a", "b", "a"};
  EXPECT_TRUE(fails_with(parse("1,2,3\n", o), 0, "a", "column name appears twice in the given column names"));
  o.column_names = {"a", "", "b"};
  EXPECT_TRUE(fails_with(parse("1,2,3\n", o), 0, "", "empty column name in the given column names"));
  // Only comments: an empty table (the caller decides whether that is an error), not "no header".
  o.column_names = {"a", "b"};
  EXPECT_EQ(parse_csv("# nothing yet\n", o).rows(), 0u);
}

TEST(Csv, MissingCellsRefusedByDefault) {
  const auto o = numeric({"a", "b"});
  EXPECT_TRUE(fails_with(parse("a,b\n1,\n", o), 2, "b", "empty cell, expected a number"));
  EXPECT_TRUE(fails_with(parse("a,b\n1,NaN\n", o), 2, "b", "expected a finite number, found 'NaN'"));
  EXPECT_TRUE(fails_with(parse("a,b\n-nan,1\n", o), 2, "a", "expected a finite number, found '-nan'"));
}

TEST(Csv, MissingCellsKeptAsNaN) {
  auto o = numeric({"a", "b"});
  o.missing = MissingCells::nan;
  const auto t = parse_csv("a,b\n1,\nNaN,+2\n-nan,1.5e-3\n", o);
  ASSERT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.numeric("a")[0], 1.0);
  EXPECT_TRUE(std::isnan(t.numeric("b")[0]));
  EXPECT_TRUE(std::isnan(t.numeric("a")[1]));
  EXPECT_EQ(t.numeric("b")[1], 2.0);
  EXPECT_TRUE(std::isnan(t.numeric("a")[2]));
  EXPECT_EQ(t.numeric("b")[2], 1.5e-3);
  // Still refused: Inf and text.
  EXPECT_TRUE(fails_with(parse("a,b\n1,inf\n", o), 2, "b", "expected a finite number, found 'inf'"));
  EXPECT_TRUE(fails_with(parse("a,b\n1,x\n", o), 2, "b", "expected a number, found 'x'"));
  EXPECT_TRUE(fails_with(parse("a,b\n1,-inf\n", o), 2, "b", "expected a finite number, found '-inf'"));
}

TEST(Csv, ReadNumberNamesTheGivenPlace) {
  const hil::error::Location at{"d.csv", 7, 3, "fz"};
  EXPECT_EQ(hil::format::read_number(" +2 ", at, MissingCells::refuse), 2.0);
  EXPECT_TRUE(std::isnan(hil::format::read_number(" ", at, MissingCells::nan)));
  EXPECT_TRUE(fails_with([&] { hil::format::read_number("", at, MissingCells::refuse); }, 7, "fz", "empty cell"));
  EXPECT_TRUE(fails_with([&] { hil::format::read_number("1x", at, MissingCells::nan); }, 7, "fz",
                         "d.csv:7:3: field 'fz': expected a number, found '1x'"));
}

TEST(Csv, BlankLinesInsideDataRefusedUnlessSkipped) {
  auto o = numeric({"a"});
  EXPECT_TRUE(fails_with(parse("a\n1\n\n2\n", o), 3, "", "empty line inside the data"));
  EXPECT_EQ(parse_csv("a\n1\n2\n\n\n", o).rows(), 2u);  // trailing blank lines were always fine
  o.skip_blank_lines = true;
  const auto t = parse_csv("a\n1\n\n \n2\n", o);
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.row_line[1], 5u);
}

TEST(Csv, ByteOrderMarkOnlySkippedWhenAsked) {
  auto o = numeric({"a"});
  const std::string text = "\xEF\xBB\xBF"
                           "a,b\n1,2\n";
  // By default the mark is part of the first name, so `a` is missing (the project writes no mark).
  EXPECT_TRUE(fails_with(parse(text, o), 1, "a", "required column is missing from the header"));
  o.skip_byte_order_mark = true;
  const auto t = parse_csv(text, o);
  EXPECT_EQ(t.header[0], "a");
  EXPECT_EQ(t.numeric("a")[0], 1.0);
  EXPECT_EQ(t.row_line[0], 2u);
}
