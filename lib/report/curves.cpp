#include "report/curves.hpp"

#include <cmath>
#include <utility>

#include "common/error.hpp"
#include "report/episode_stats.hpp"

namespace qte::report {

CurveBuilder::CurveBuilder(CurveColumns columns, Band band) : columns_(std::move(columns)), band_(band) {}

void CurveBuilder::add(const CsvTable& table) {
  const int x = table.column(columns_.x, true), y = table.column(columns_.y, true);
  const int group = columns_.group.empty() ? -1 : table.column(columns_.group, true);
  const int panel = columns_.panel.empty() ? -1 : table.column(columns_.panel, true);
  const int low = band_ == Band::ci ? table.column("ci95_low", false) : -1;
  const int high = band_ == Band::ci ? table.column("ci95_high", false) : -1;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::string name = group < 0 ? columns_.y : table.rows[r][group];
    const std::string panel_name = panel < 0 ? std::string() : table.rows[r][panel];
    auto [it, added] = group_index_.emplace(std::make_pair(panel_name, name), groups_.size());
    if (added) groups_.push_back(Group{panel_name, name, {}});
    Row row{table.number(r, y)};
    if (low >= 0 && high >= 0) {
      row.has_interval = true;
      row.low = table.number(r, low);
      row.high = table.number(r, high);
    }
    groups_[it->second].rows_at_x[table.number(r, x)].push_back(row);
  }
}

CurvePoint CurveBuilder::summarise(double x, const std::vector<Row>& rows) const {
  const double n = static_cast<double>(rows.size());
  double sum = 0, squares = 0, low = 0, high = 0;
  bool intervals = true;
  for (const Row& r : rows) {
    sum += r.y;
    low += r.low;
    high += r.high;
    intervals &= r.has_interval;
  }
  const double mean = sum / n;
  for (const Row& r : rows) squares += (r.y - mean) * (r.y - mean);
  const double std_dev = rows.size() > 1 ? std::sqrt(squares / (n - 1)) : 0.0;
  CurvePoint p{x, mean, mean, mean};
  if (band_ == Band::std_dev) {
    p.low = mean - std_dev;
    p.high = mean + std_dev;
  } else if (band_ == Band::ci && intervals) {
    p.low = low / n;
    p.high = high / n;
  } else if (band_ == Band::ci) {
    p.low = mean - kZ95 * std_dev / std::sqrt(n);
    p.high = mean + kZ95 * std_dev / std::sqrt(n);
  }
  return p;
}

std::vector<Curve> CurveBuilder::curves() const {
  std::vector<Curve> curves;
  for (CurvePanel& panel : panels())
    for (Curve& curve : panel.curves) curves.push_back(std::move(curve));
  return curves;
}

std::vector<CurvePanel> CurveBuilder::panels() const {
  if (groups_.empty()) throw Error("no rows to plot in the input tables");
  std::vector<CurvePanel> panels;
  std::map<std::string, std::size_t> panel_index;
  for (const Group& group : groups_) {
    auto [it, added] = panel_index.emplace(group.panel, panels.size());
    if (added) panels.push_back(CurvePanel{group.panel, {}});
    Curve curve{group.name, {}};
    for (const auto& [x, rows] : group.rows_at_x) curve.points.push_back(summarise(x, rows));
    panels[it->second].curves.push_back(std::move(curve));
  }
  return panels;
}

}  // namespace qte::report
