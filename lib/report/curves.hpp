// Learning curves from CSV tables: rows grouped into curves by a column's value, and the rows
// of a curve at the same x (several seeds, say) averaged into one point with a band around it.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "report/csv.hpp"

namespace qte::report {

// The band around each mean: the rows' sample standard deviation, a 95 % interval (the mean of
// the rows' ci95_low / ci95_high columns where the table has them, else 1.96 std / sqrt(n)), or
// none.
enum class Band { std_dev, ci, none };

struct CurvePoint {
  double x = 0, mean = 0, low = 0, high = 0;  // low == high == mean without a band
};

struct Curve {
  std::string name;  // the group's value, or the y column without grouping
  std::vector<CurvePoint> points;  // in increasing x
};

// The curves of one panel of a picture of small multiples (plot-curves --panel: one task each).
struct CurvePanel {
  std::string name;  // the panel column's value; empty without one
  std::vector<Curve> curves;
};

struct CurveColumns {
  std::string x, y;
  std::string group;  // empty: all rows form one curve
  std::string panel = {};  // empty: one panel; else one panel per distinct value of this column
};

class CurveBuilder {
 public:
  CurveBuilder(CurveColumns columns, Band band);

  // The rows of one table; tables may order their columns differently. Error naming the table
  // when a column is missing, or its line and column when a cell is not a finite number.
  void add(const CsvTable& table);

  // The curves in the order in which their groups first appeared, of every panel in turn. Error
  // when no rows were added.
  std::vector<Curve> curves() const;
  // The panels in the order in which their values first appeared, each with its curves in that
  // order. Error when no rows were added.
  std::vector<CurvePanel> panels() const;

 private:
  struct Row {
    double y = 0;
    bool has_interval = false;
    double low = 0, high = 0;
  };
  struct Group {
    std::string panel, name;
    std::map<double, std::vector<Row>> rows_at_x;
  };
  CurvePoint summarise(double x, const std::vector<Row>& rows) const;

  CurveColumns columns_;
  Band band_;
  std::vector<Group> groups_;
  std::map<std::pair<std::string, std::string>, std::size_t> group_index_;  // by (panel, group)
};

}  // namespace qte::report
