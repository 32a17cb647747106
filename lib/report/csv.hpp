// CSV tables as RFC 4180 writes them: reading whole tables with a header line (cells by column
// name, numbers checked) and writing cells and numbers, for the summaries tools print and the
// curves plot-curves draws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace qte::report {

struct CsvTable {
  std::string source;  // file name as given; "<stdin>" for '-'
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int64_t> row_lines;  // line (from 1) where each row starts

  // Index of column `name`; -1 when absent and not `required`, else Error naming the header.
  int column(const std::string& name, bool required) const;
  // The cell at (row, column) as a finite number; Error naming source, line and column if not.
  double number(std::size_t row, int column) const;
};

// Parses `text`: cells separated by commas, quoted cells may hold commas, doubled quotes and
// line breaks; CR LF ends a line as LF does. The first non-empty record is the header; empty
// lines and lines repeating the header (as left by concatenating tables) are skipped. An
// unterminated quote, no header or a row whose cell count differs from the header's throws
// Error naming `source` (and the line).
CsvTable parse_csv(const std::string& source, const std::string& text);

// parse_csv of a whole file; "-" reads standard input (named "<stdin>").
CsvTable read_csv(const std::string& path);

// A cell as RFC 4180 writes it: quoted when it holds a comma, quote, CR or LF, with the quotes
// inside doubled.
std::string csv_cell(const std::string& text);

// A number as a cell: printf's %.6g.
std::string csv_number(double value);

}  // namespace qte::report
