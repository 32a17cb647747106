// CSV tables: RFC 4180 quoting both ways, skipped blank and repeated header lines, and errors
// that name the source, line and column.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "report/csv.hpp"

using namespace qte;
using namespace qte::report;

namespace {

// The message of the Error that `f` throws, or "" when it throws none.
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CsvTable, ParsesQuotedCellsWithCommasQuotesAndLineBreaks) {
  const CsvTable t = parse_csv("t.csv", "name,note\r\n\"a,b\",\"say \"\"hi\"\"\"\nc,\"two\nlines\"\n\"\",x\n");
  ASSERT_EQ(t.header, (std::vector<std::string>{"name", "note"}));
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0], (std::vector<std::string>{"a,b", "say \"hi\""}));
  EXPECT_EQ(t.rows[1], (std::vector<std::string>{"c", "two\nlines"}));
  EXPECT_EQ(t.rows[2], (std::vector<std::string>{"", "x"}));
  // Rows start on lines 2, 3 and 5: the quoted line break counts.
  EXPECT_EQ(t.row_lines, (std::vector<int64_t>{2, 3, 5}));
}

TEST(CsvTable, SkipsBlankLinesAndRepeatedHeaders) {
  const CsvTable t = parse_csv("t.csv", "x,y\n1,2\n\nx,y\n3,4");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1], (std::vector<std::string>{"3", "4"}));
  EXPECT_EQ(t.row_lines, (std::vector<int64_t>{2, 5}));
}

TEST(CsvTable, WrongCellCountNamesSourceAndLine) {
  EXPECT_EQ(error_of([] { parse_csv("runs.csv", "x,y\n1,2\n\n3,4,5\n"); }),
            "runs.csv: line 4: 3 cells, the header has 2");
  EXPECT_EQ(error_of([] { parse_csv("runs.csv", "x,y\n1\n"); }), "runs.csv: line 2: 1 cells, the header has 2");
  EXPECT_EQ(error_of([] { parse_csv("runs.csv", "x,y\n1,\"open\n"); }), "runs.csv: line 2: unterminated quoted cell");
  EXPECT_EQ(error_of([] { parse_csv("runs.csv", "\n\n"); }), "runs.csv: empty table (no header line)");
}

TEST(CsvTable, NumbersAndColumnsNameLineAndColumn) {
  const CsvTable t = parse_csv("runs.csv", "step,success_rate\n0,0.5\n1000,half\n2000,inf\n");
  EXPECT_EQ(t.column("success_rate", true), 1);
  EXPECT_EQ(t.column("ci95_low", false), -1);
  EXPECT_EQ(error_of([&] { t.column("reward", true); }), "runs.csv: no column 'reward' (its header: step,success_rate)");
  EXPECT_DOUBLE_EQ(t.number(0, 1), 0.5);
  EXPECT_DOUBLE_EQ(t.number(1, 0), 1000);
  EXPECT_EQ(error_of([&] { t.number(1, 1); }), "runs.csv: line 3, column 'success_rate': 'half' is not a finite number");
  EXPECT_EQ(error_of([&] { t.number(2, 1); }), "runs.csv: line 4, column 'success_rate': 'inf' is not a finite number");
}

TEST(CsvCell, QuotesOnlyWhatNeedsIt) {
  EXPECT_EQ(csv_cell("qte"), "qte");
  EXPECT_EQ(csv_cell("a,\"b\""), "\"a,\"\"b\"\"\"");
  EXPECT_EQ(csv_cell("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_number(2.0 / 7), "0.285714");
  EXPECT_EQ(csv_number(20000), "20000");
  // What csv_cell writes, parse_csv reads back.
  const std::string text = "label\n" + csv_cell("a,\"b\"\r\nc") + "\n";
  EXPECT_EQ(parse_csv("t", text).rows.at(0).at(0), "a,\"b\"\r\nc");
}
