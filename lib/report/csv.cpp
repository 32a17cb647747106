#include "report/csv.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>

#include "common/error.hpp"

namespace qte::report {

int CsvTable::column(const std::string& name, bool required) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  if (!required) return -1;
  std::string have;
  for (const auto& h : header) have += (have.empty() ? "" : ",") + h;
  throw Error(source + ": no column '" + name + "' (its header: " + have + ")");
}

double CsvTable::number(std::size_t row, int column) const {
  const std::string& text = rows[row][column];
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value))
    throw Error(source + ": line " + std::to_string(row_lines[row]) + ", column '" + header[column] + "': '" +
                text + "' is not a finite number");
  return value;
}

CsvTable parse_csv(const std::string& source, const std::string& text) {
  CsvTable table;
  table.source = source;
  std::vector<std::string> record;
  std::string cell;
  bool quoted = false, any = false;
  int64_t line = 1, record_line = 1;
  auto end_record = [&] {
    record.push_back(cell);
    cell.clear();
    const bool blank = record.size() == 1 && record[0].empty() && !any;
    if (!blank) {
      if (table.header.empty()) table.header = record;
      else if (record != table.header) {
        table.rows.push_back(record);
        table.row_lines.push_back(record_line);
      }
    }
    record.clear();
    any = false;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') cell += text[++i];
      else if (c == '"') quoted = false;
      else {
        if (c == '\n') ++line;
        cell += c;
      }
    } else if (c == '"') {
      quoted = any = true;
    } else if (c == ',') {
      record.push_back(cell);
      cell.clear();
      any = true;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      end_record();
      record_line = ++line;
    } else {
      cell += c;
      any = true;
    }
  }
  if (quoted) throw Error(source + ": line " + std::to_string(record_line) + ": unterminated quoted cell");
  if (any || !cell.empty()) end_record();
  if (table.header.empty()) throw Error(source + ": empty table (no header line)");
  for (std::size_t r = 0; r < table.rows.size(); ++r)
    if (table.rows[r].size() != table.header.size())
      throw Error(source + ": line " + std::to_string(table.row_lines[r]) + ": " +
                  std::to_string(table.rows[r].size()) + " cells, the header has " +
                  std::to_string(table.header.size()));
  return table;
}

CsvTable read_csv(const std::string& path) {
  std::ostringstream text;
  if (path == "-") {
    text << std::cin.rdbuf();
    return parse_csv("<stdin>", text.str());
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_system_error("cannot open " + path);
  text << in.rdbuf();
  if (in.bad()) throw_system_error("cannot read " + path);
  return parse_csv(path, text.str());
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

}  // namespace qte::report
