// Learning curves as a picture: axes with ticks at round values, light grid lines, a
// translucent band and an anti-aliased line with dots per curve (ten colours, then repeated),
// a legend in the emptiest corner, as PNG. The same curves and options give the same bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "report/curves.hpp"

namespace qte::report {

struct CurvePlotOptions {
  int width_px = 800, height_px = 500;
  std::string title, x_label, y_label;  // empty: left out
  bool legend = false;                  // the curves' names
  // The vertical axis: LO..HI when fixed (what lies outside is clipped), else the data and
  // bands with a small margin, as the horizontal axis always is.
  bool fixed_y = false;
  double y_min = 0, y_max = 1;
};

// The picture as PNG bytes. UsageError when the size leaves no room for the axes and labels.
std::vector<uint8_t> curve_plot_png(const std::vector<Curve>& curves, const CurvePlotOptions& options);

// curve_plot_png written atomically to `path`.
void save_curve_plot(const std::string& path, const std::vector<Curve>& curves, const CurvePlotOptions& options);

// Small multiples as PNG bytes: one plot of options' size per panel, titled with the panel's
// name, `columns` panels to a row under options.title. The panels share the vertical axis (the
// fixed range, or all their data and bands) and each spans its own horizontal extent; a curve
// has the colour of its name in every panel.
std::vector<uint8_t> panel_plot_png(const std::vector<CurvePanel>& panels, const CurvePlotOptions& options,
                                    int columns);

// panel_plot_png written atomically to `path`.
void save_panel_plot(const std::string& path, const std::vector<CurvePanel>& panels, const CurvePlotOptions& options,
                     int columns);

}  // namespace qte::report
