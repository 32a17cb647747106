#include "report/curve_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <opencv2/imgproc.hpp>

#include "common/png_file.hpp"
#include "common/error.hpp"

namespace qte::report {
namespace {

// ---------------------------------------------------------------------------------------------
// Axes: round tick values within the data range

// A picture's bound: 100 megapixels are 300 MB of colour before encoding.
constexpr double kMaxPicturePixels = 100e6;

struct Axis {
  double lo = 0, hi = 1;
  double step = 0.2;
  std::vector<double> ticks;

  double fraction(double v) const { return (v - lo) / (hi - lo); }
};

// A round step near `raw`: 1, 2 or 5 times a power of ten.
double round_step(double raw) {
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / power;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * power;
}

// An axis whose extent is not finite (values near the ends of the double range), or is below
// what doubles resolve at its values, has no round ticks to count up to its end.
void check_axis(const char* name, const Axis& axis) {
  const double extent = axis.hi - axis.lo, size = std::max(std::fabs(axis.lo), std::fabs(axis.hi));
  if (!std::isfinite(extent) || !(extent > 1e-9 * size)) {
    std::ostringstream text;
    text << "the " << name << " axis from " << axis.lo << " to " << axis.hi
         << " cannot be drawn (expected finite values spanning more than 1e-9 of their size)";
    throw Error(text.str());
  }
}

void set_ticks(Axis& axis, int target) {
  axis.step = round_step((axis.hi - axis.lo) / std::max(1, target));
  axis.ticks.clear();
  const double first = std::ceil(axis.lo / axis.step - 1e-9);
  for (double k = first; axis.ticks.size() < 1000; ++k) {  // a round step over a checked extent: a few dozen
    double v = k * axis.step;
    if (v > axis.hi + 1e-9 * axis.step) break;
    if (std::fabs(v) < 1e-12 * axis.step) v = 0;  // no "-0"
    axis.ticks.push_back(v);
  }
}

// The data range with a margin; a flat range is widened so it has an extent.
Axis data_axis(double lo, double hi) {
  const bool flat = hi - lo <= 1e-12 * std::max(1.0, std::max(std::fabs(lo), std::fabs(hi)));
  const double margin = flat ? (lo == 0 ? 0.5 : std::fabs(lo) * 0.1) : 0.04 * (hi - lo);
  Axis axis;
  axis.lo = lo - margin;
  axis.hi = hi + margin;
  return axis;
}

std::string tick_text(double v, double step) {
  char text[32];
  if (std::fabs(v) >= 1e6 || (v != 0 && std::fabs(v) < 1e-4)) {
    std::snprintf(text, sizeof text, "%g", v);
  } else {
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    std::snprintf(text, sizeof text, "%.*f", decimals, v);
  }
  return text;
}

// ---------------------------------------------------------------------------------------------
// Drawing

// Tableau 10 (matplotlib's default cycle), as BGR: ten well-separated hues.
const cv::Scalar kPalette[] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44},  {40, 39, 214},
                               {189, 103, 148}, {75, 86, 140}, {194, 119, 227}, {127, 127, 127},
                               {34, 189, 188}, {207, 190, 23}};
constexpr int kPaletteSize = sizeof kPalette / sizeof kPalette[0];
const cv::Scalar kInk{40, 40, 40}, kGrid{232, 232, 232}, kFrame{120, 120, 120};
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // sub-pixel coordinates: 1/16 pixel
constexpr double kSubPixel = 1 << kShift;

struct Style {
  double scale;  // 1 at 800x500
  double tick_scale, label_scale, title_scale;
  int thickness, line_thickness, marker_radius;
};

// Text and lines in proportion to the picture, as at 800x500.
Style style_for(cv::Size size) {
  const double scale = std::clamp(std::min(size.width / 800.0, size.height / 500.0), 0.6, 3.0);
  return Style{scale, 0.42 * scale, 0.5 * scale, 0.62 * scale, std::max(1, static_cast<int>(std::lround(scale))),
               std::max(1, static_cast<int>(std::lround(2 * scale))),
               std::max(2, static_cast<int>(std::lround(3 * scale)))};
}

cv::Size text_size(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  cv::Size s = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  return {s.width, s.height + baseline};
}

// `origin` is the top-left corner of the text's box.
void draw_text(cv::Mat& image, const std::string& text, cv::Point origin, double scale, int thickness,
               const cv::Scalar& colour) {
  int baseline = 0;
  const cv::Size s = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::putText(image, text, {origin.x, origin.y + s.height}, kFont, scale, colour, thickness, cv::LINE_AA);
}

// Text turned 90 degrees counter-clockwise (reading upwards), centred on `centre`.
void draw_text_upwards(cv::Mat& image, const std::string& text, cv::Point centre, double scale,
                       int thickness, const cv::Scalar& colour) {
  const cv::Size s = text_size(text, scale, thickness);
  cv::Mat mask(s.height + 2, s.width + 2, CV_8UC1, cv::Scalar(0));
  draw_text(mask, text, {1, 1}, scale, thickness, cv::Scalar(255));
  cv::rotate(mask, mask, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect where = cv::Rect(centre.x - mask.cols / 2, centre.y - mask.rows / 2, mask.cols, mask.rows) &
                         cv::Rect(0, 0, image.cols, image.rows);
  for (int r = 0; r < where.height; ++r)
    for (int c = 0; c < where.width; ++c) {
      const double a = mask.at<uint8_t>(r + where.y - (centre.y - mask.rows / 2),
                                        c + where.x - (centre.x - mask.cols / 2)) / 255.0;
      auto& pixel = image.at<cv::Vec3b>(where.y + r, where.x + c);
      for (int k = 0; k < 3; ++k)
        pixel[k] = cv::saturate_cast<uint8_t>(pixel[k] * (1 - a) + colour[k] * a);
    }
}

struct Plot {
  cv::Rect area;  // the data area, inside the axes
  Axis x, y;

  cv::Point2d at(double vx, double vy) const {  // relative to `area`
    return {x.fraction(vx) * (area.width - 1), (1 - y.fraction(vy)) * (area.height - 1)};
  }
  static cv::Point fixed(const cv::Point2d& p) {
    return {static_cast<int>(std::lround(p.x * kSubPixel)), static_cast<int>(std::lround(p.y * kSubPixel))};
  }
};

// Blends a filled polygon into `image` at `alpha`: a light band that lets lines show through.
void fill_translucent(cv::Mat& image, const std::vector<cv::Point>& polygon, const cv::Scalar& colour,
                      double alpha) {
  cv::Mat overlay = image.clone();
  std::vector<std::vector<cv::Point>> polygons{polygon};
  cv::fillPoly(overlay, polygons, colour, cv::LINE_AA, kShift);
  cv::addWeighted(overlay, alpha, image, 1 - alpha, 0, image);
}

void draw_bands(cv::Mat& data_area, const Plot& plot, const std::vector<Curve>& curves,
                const std::vector<cv::Scalar>& colours, const Style& style) {
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const auto& points = curves[i].points;
    const cv::Scalar& colour = colours[i];
    if (points.size() == 1) {  // one x: a translucent bar instead of an area
      const CurvePoint& p = points[0];
      const cv::Point2d low = plot.at(p.x, p.low), high = plot.at(p.x, p.high);
      const cv::Point2d half_width(style.marker_radius * 1.5, 0);
      if (p.high > p.low)
        fill_translucent(data_area, {Plot::fixed(high - half_width), Plot::fixed(high + half_width),
                                     Plot::fixed(low + half_width), Plot::fixed(low - half_width)},
                         colour, 0.25);
      continue;
    }
    std::vector<cv::Point> polygon;
    for (const CurvePoint& p : points) polygon.push_back(Plot::fixed(plot.at(p.x, p.high)));
    for (auto p = points.rbegin(); p != points.rend(); ++p) polygon.push_back(Plot::fixed(plot.at(p->x, p->low)));
    fill_translucent(data_area, polygon, colour, 0.18);
  }
}

void draw_lines(cv::Mat& data_area, const Plot& plot, const std::vector<Curve>& curves,
                const std::vector<cv::Scalar>& colours, const Style& style) {
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const auto& points = curves[i].points;
    const cv::Scalar& colour = colours[i];
    for (std::size_t k = 1; k < points.size(); ++k)
      cv::line(data_area, Plot::fixed(plot.at(points[k - 1].x, points[k - 1].mean)),
               Plot::fixed(plot.at(points[k].x, points[k].mean)), colour, style.line_thickness, cv::LINE_AA,
               kShift);
    for (const CurvePoint& p : points)
      cv::circle(data_area, Plot::fixed(plot.at(p.x, p.mean)), style.marker_radius * static_cast<int>(kSubPixel),
                 colour, cv::FILLED, cv::LINE_AA, kShift);
  }
}

// How much of the curves' lines lies inside `box` (relative to the data area).
int64_t ink_inside(const cv::Rect& box, const Plot& plot, const std::vector<Curve>& curves) {
  int64_t count = 0;
  for (const Curve& curve : curves)
    for (std::size_t k = 0; k < curve.points.size(); ++k) {
      const cv::Point2d b = plot.at(curve.points[k].x, curve.points[k].mean);
      const cv::Point2d a = k ? plot.at(curve.points[k - 1].x, curve.points[k - 1].mean) : b;
      const int samples = 1 + static_cast<int>(cv::norm(b - a) / 2);
      for (int s = 0; s <= samples; ++s) {
        const cv::Point2d p = a + (b - a) * (static_cast<double>(s) / samples);
        count += box.contains(cv::Point(static_cast<int>(p.x), static_cast<int>(p.y)));
      }
    }
  return count;
}

void draw_legend(cv::Mat& image, const Plot& plot, const std::vector<Curve>& curves,
                 const std::vector<cv::Scalar>& colours, const Style& style) {
  const int pad = 8, swatch = 24, row_height = text_size("Ag", style.label_scale, style.thickness).height + 6;
  int text_width = 0;
  for (const Curve& c : curves)
    text_width = std::max(text_width, text_size(c.name, style.label_scale, style.thickness).width);
  const cv::Size box(pad * 3 + swatch + text_width, pad * 2 + row_height * static_cast<int>(curves.size()));
  const int inset = 10;
  const int right = plot.area.width - box.width - inset, bottom = plot.area.height - box.height - inset;
  // Corners in order of preference; the one crossing the fewest line pixels wins.
  const cv::Point corners[] = {{inset, inset}, {right, inset}, {right, bottom}, {inset, bottom}};
  cv::Point best = corners[0];
  int64_t least = -1;
  for (const cv::Point& c : corners) {
    const int64_t ink = ink_inside(cv::Rect(c, box), plot, curves);
    if (least < 0 || ink < least) least = ink, best = c;
  }
  const cv::Rect frame(plot.area.tl() + best, box);
  cv::Mat region = image(frame & cv::Rect(0, 0, image.cols, image.rows));
  cv::addWeighted(region, 0.15, cv::Mat(region.size(), region.type(), cv::Scalar(255, 255, 255)), 0.85, 0, region);
  cv::rectangle(image, frame, cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const int top = frame.y + pad + row_height * static_cast<int>(i);
    const int middle = top + row_height / 2;
    const cv::Scalar& colour = colours[i];
    cv::line(image, {frame.x + pad, middle}, {frame.x + pad + swatch, middle}, colour, style.line_thickness,
             cv::LINE_AA);
    cv::circle(image, {frame.x + pad + swatch / 2, middle}, style.marker_radius, colour, cv::FILLED, cv::LINE_AA);
    const cv::Size s = text_size(curves[i].name, style.label_scale, style.thickness);
    draw_text(image, curves[i].name, {frame.x + pad * 2 + swatch, middle - s.height / 2}, style.label_scale,
              style.thickness, kInk);
  }
}

struct Labels {
  std::string title, x, y;
  bool legend = false;
  std::vector<cv::Scalar> colours;  // one per curve
};

int y_tick_target(int height, const Style& style) {
  return std::max(2, static_cast<int>(height / (60 * style.scale)));
}

// Picks ticks for the axes so that their numbers do not collide.
void choose_ticks(Plot& plot, const Style& style) {
  for (int target = std::max(2, static_cast<int>(plot.area.width / (90 * style.scale))); target >= 2; --target) {
    set_ticks(plot.x, target);
    int widest = 0;
    for (double v : plot.x.ticks)
      widest = std::max(widest, text_size(tick_text(v, plot.x.step), style.tick_scale, style.thickness).width);
    const double spacing = plot.x.step / (plot.x.hi - plot.x.lo) * plot.area.width;
    if (widest + 16 <= spacing) break;
  }
  set_ticks(plot.y, y_tick_target(plot.area.height, style));
}

// A title wider than the picture is drawn smaller, never cut off; it is centred on the data
// area as far as the picture's edges allow.
void draw_title(cv::Mat& image, const std::string& title, const Plot& plot, const Style& style, int gap) {
  const int room = image.cols - 2 * gap;
  double title_scale = style.title_scale;
  cv::Size s = text_size(title, title_scale, style.thickness);
  if (s.width > room) {
    title_scale *= 0.98 * room / s.width;
    s = text_size(title, title_scale, style.thickness);
  }
  const int centre = std::max(gap + s.width / 2, std::min(plot.area.x + plot.area.width / 2, image.cols - gap - s.width / 2));
  draw_text(image, title, {centre - s.width / 2, gap * 2}, title_scale, style.thickness, kInk);
}

cv::Mat draw(const std::vector<Curve>& curves, Axis x_axis, Axis y_axis, const Labels& labels, cv::Size size) {
  const Style style = style_for(size);
  const double scale = style.scale;
  cv::Mat image(size, CV_8UC3, cv::Scalar(255, 255, 255));

  // Margins from the text they hold; the y tick numbers are measured once ticks are known, so
  // lay out twice (the y ticks depend only on the height).
  const int tick_height = text_size("0", style.tick_scale, style.thickness).height;
  const int label_height = text_size("Ag", style.label_scale, style.thickness).height;
  const int title_height = labels.title.empty() ? 0 : text_size("Ag", style.title_scale, style.thickness).height;
  const int gap = static_cast<int>(8 * scale), tick_length = static_cast<int>(5 * scale);
  const int top = gap * 2 + (title_height ? title_height + gap : 0);
  const int bottom = tick_length + gap + tick_height + (labels.x.empty() ? 0 : gap + label_height) + gap * 2;
  Plot plot{cv::Rect(0, top, size.width, size.height - top - bottom), x_axis, y_axis};
  set_ticks(plot.y, y_tick_target(plot.area.height, style));
  int y_numbers = 0;
  for (double v : plot.y.ticks)
    y_numbers = std::max(y_numbers, text_size(tick_text(v, plot.y.step), style.tick_scale, style.thickness).width);
  const int left = gap + (labels.y.empty() ? 0 : label_height + gap) + y_numbers + gap + tick_length;
  const int right = gap * 3;
  plot.area = cv::Rect(left, top, size.width - left - right, size.height - top - bottom);
  if (plot.area.width < 40 || plot.area.height < 40) throw UsageError("--size is too small for the axes and labels");
  choose_ticks(plot, style);

  // Grid, then bands and lines clipped to the data area, then axes and text on top.
  for (double v : plot.x.ticks) {
    const int px = plot.area.x + static_cast<int>(std::lround(plot.at(v, 0).x));
    cv::line(image, {px, plot.area.y}, {px, plot.area.br().y - 1}, kGrid, 1);
  }
  for (double v : plot.y.ticks) {
    const int py = plot.area.y + static_cast<int>(std::lround(plot.at(0, v).y));
    cv::line(image, {plot.area.x, py}, {plot.area.br().x - 1, py}, kGrid, 1);
  }
  cv::Mat data_area = image(plot.area);
  draw_bands(data_area, plot, curves, labels.colours, style);
  draw_lines(data_area, plot, curves, labels.colours, style);
  cv::rectangle(image, plot.area.tl() - cv::Point(1, 1), plot.area.br(), kFrame, 1);

  for (double v : plot.x.ticks) {
    const int px = plot.area.x + static_cast<int>(std::lround(plot.at(v, 0).x));
    cv::line(image, {px, plot.area.br().y}, {px, plot.area.br().y + tick_length}, kFrame, 1);
    const std::string text = tick_text(v, plot.x.step);
    const cv::Size s = text_size(text, style.tick_scale, style.thickness);
    draw_text(image, text, {px - s.width / 2, plot.area.br().y + tick_length + gap / 2}, style.tick_scale,
              style.thickness, kInk);
  }
  for (double v : plot.y.ticks) {
    const int py = plot.area.y + static_cast<int>(std::lround(plot.at(0, v).y));
    cv::line(image, {plot.area.x - 1 - tick_length, py}, {plot.area.x - 1, py}, kFrame, 1);
    const std::string text = tick_text(v, plot.y.step);
    const cv::Size s = text_size(text, style.tick_scale, style.thickness);
    draw_text(image, text, {plot.area.x - 1 - tick_length - gap / 2 - s.width, py - s.height / 2},
              style.tick_scale, style.thickness, kInk);
  }
  if (!labels.x.empty()) {
    const cv::Size s = text_size(labels.x, style.label_scale, style.thickness);
    draw_text(image, labels.x, {plot.area.x + plot.area.width / 2 - s.width / 2, size.height - gap * 2 - s.height},
              style.label_scale, style.thickness, kInk);
  }
  if (!labels.y.empty())
    draw_text_upwards(image, labels.y, {gap + label_height / 2, plot.area.y + plot.area.height / 2},
                      style.label_scale, style.thickness, kInk);
  if (!labels.title.empty()) draw_title(image, labels.title, plot, style, gap);
  if (labels.legend) draw_legend(image, plot, curves, labels.colours, style);
  return image;
}

// ---------------------------------------------------------------------------------------------
// Pictures of curves, alone or as small multiples

struct Extent {
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;

  void add(const std::vector<Curve>& curves) {
    for (const Curve& curve : curves)
      for (const CurvePoint& p : curve.points) {
        x_lo = std::min(x_lo, p.x), x_hi = std::max(x_hi, p.x);
        y_lo = std::min({y_lo, p.mean, p.low}), y_hi = std::max({y_hi, p.mean, p.high});
      }
  }
};

// The vertical axis of `extent`'s data and bands, or the fixed range.
Axis y_axis_of(const Extent& extent, const CurvePlotOptions& options) {
  Axis y_axis = data_axis(extent.y_lo, extent.y_hi);
  if (options.fixed_y) {
    y_axis.lo = options.y_min;
    y_axis.hi = options.y_max;
  }
  check_axis("y", y_axis);
  return y_axis;
}

// One plot of `curves`, the horizontal axis spanning their points, in the given colours.
cv::Mat draw_curves(const std::vector<Curve>& curves, const std::vector<cv::Scalar>& colours, const Axis& y_axis,
                    const std::string& title, const CurvePlotOptions& options) {
  Extent extent;
  extent.add(curves);
  const Axis x_axis = data_axis(extent.x_lo, extent.x_hi);
  check_axis("x", x_axis);
  const Labels labels{title, options.x_label, options.y_label, options.legend, colours};
  return draw(curves, x_axis, y_axis, labels,
              cv::Size(options.width_px, options.height_px));
}

// The picture of `curves` with axes spanning their points and bands (or the fixed y range).
cv::Mat draw_curves(const std::vector<Curve>& curves, const CurvePlotOptions& options) {
  Extent extent;
  extent.add(curves);
  std::vector<cv::Scalar> colours;
  for (std::size_t i = 0; i < curves.size(); ++i) colours.push_back(kPalette[i % kPaletteSize]);
  return draw_curves(curves, colours, y_axis_of(extent, options), options.title, options);
}

// Small multiples: one plot per panel, titled with its name, `columns` to a row under the title;
// one vertical axis for all (so panels compare at a glance), a curve's colour that of its name
// in every panel.
cv::Mat draw_panels(const std::vector<CurvePanel>& panels, const CurvePlotOptions& options, int columns) {
  if (panels.empty()) throw Error("no panels to plot");
  Extent extent;
  std::vector<std::string> names;  // every curve name, in order of first appearance
  for (const CurvePanel& panel : panels) {
    extent.add(panel.curves);
    for (const Curve& curve : panel.curves)
      if (std::find(names.begin(), names.end(), curve.name) == names.end()) names.push_back(curve.name);
  }
  const Axis y_axis = y_axis_of(extent, options);
  const int n = static_cast<int>(panels.size());
  columns = std::clamp(columns, 1, n);
  const int rows = (n + columns - 1) / columns;
  const double pixels = double(rows) * options.height_px * double(columns) * options.width_px;
  if (pixels > kMaxPicturePixels)
    throw Error(std::to_string(n) + " panels of " + std::to_string(options.width_px) + "x" +
                std::to_string(options.height_px) + " make a picture of " + std::to_string(int64_t(pixels / 1e6)) +
                " megapixels (at most " + std::to_string(int64_t(kMaxPicturePixels / 1e6)) +
                "): fewer panels (--panel) or a smaller --size");
  // The picture's title a size above the panels' own.
  const Style style = style_for(cv::Size(options.width_px, options.height_px));
  const double title_scale = style.title_scale * 1.3;
  const int title_band = options.title.empty() ? 0 : text_size("Ag", title_scale, style.thickness).height * 2;
  cv::Mat image(title_band + rows * options.height_px, columns * options.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int i = 0; i < n; ++i) {
    std::vector<cv::Scalar> colours;
    for (const Curve& curve : panels[i].curves) {
      const auto at = std::find(names.begin(), names.end(), curve.name) - names.begin();
      colours.push_back(kPalette[at % kPaletteSize]);
    }
    const cv::Mat plot = draw_curves(panels[i].curves, colours, y_axis, panels[i].name, options);
    plot.copyTo(image(cv::Rect((i % columns) * options.width_px, title_band + (i / columns) * options.height_px,
                               options.width_px, options.height_px)));
  }
  if (title_band) {
    cv::Size s = text_size(options.title, title_scale, style.thickness);
    const double fit = std::min(1.0, 0.98 * image.cols / std::max(1, s.width));  // never cut off
    s = text_size(options.title, title_scale * fit, style.thickness);
    draw_text(image, options.title, {(image.cols - s.width) / 2, (title_band - s.height) / 2}, title_scale * fit,
              style.thickness, kInk);
  }
  return image;
}

}  // namespace

std::vector<uint8_t> curve_plot_png(const std::vector<Curve>& curves, const CurvePlotOptions& options) {
  return encode_png(draw_curves(curves, options), "the curves");
}

void save_curve_plot(const std::string& path, const std::vector<Curve>& curves, const CurvePlotOptions& options) {
  write_png(path, draw_curves(curves, options));
}

std::vector<uint8_t> panel_plot_png(const std::vector<CurvePanel>& panels, const CurvePlotOptions& options,
                                    int columns) {
  return encode_png(draw_panels(panels, options, columns), "the panels");
}

void save_panel_plot(const std::string& path, const std::vector<CurvePanel>& panels, const CurvePlotOptions& options,
                     int columns) {
  write_png(path, draw_panels(panels, options, columns));
}

}  // namespace qte::report
