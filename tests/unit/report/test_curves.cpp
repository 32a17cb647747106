// Learning curves: rows grouped by a column in order of appearance, averaged per x with std or
// interval bands, over tables with differently ordered columns; and the picture's bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.hpp"
#include "report/curve_plot.hpp"
#include "report/curves.hpp"

using namespace qte;
using namespace qte::report;

namespace {

// Two methods, three seeds each, at two steps.
const char* kRuns =
    "label,seed,step,success_rate,ci95_low,ci95_high\n"
    "qte,1,0,0.2,0.1,0.3\n"
    "qte,2,0,0.4,0.3,0.5\n"
    "c2farm,1,0,0.1,0.0,0.2\n"
    "qte,3,0,0.6,0.5,0.7\n"
    "qte,1,1000,0.8,0.7,0.9\n"
    "qte,2,1000,1.0,0.9,1.0\n";

// The curves of kRuns with interval bands, and a 400x300 picture's options.
std::vector<Curve> run_curves() {
  CurveBuilder builder({"step", "success_rate", "label"}, Band::ci);
  builder.add(parse_csv("runs.csv", kRuns));
  return builder.curves();
}

CurvePlotOptions small_picture(const std::string& title) {
  CurvePlotOptions options;
  options.width_px = 400;
  options.height_px = 300;
  options.title = title;
  return options;
}

}  // namespace

TEST(CurveBuilder, GroupsInOrderOfAppearanceWithMeanAndStdOverSeeds) {
  CurveBuilder builder({"step", "success_rate", "label"}, Band::std_dev);
  builder.add(parse_csv("runs.csv", kRuns));
  // A second table with its columns in another order adds to the same curves.
  builder.add(parse_csv("more.csv", "success_rate,step,label\n0.3,0,c2farm\n0.5,2000,c2farm\n"));
  const std::vector<Curve> curves = builder.curves();
  ASSERT_EQ(curves.size(), 2u);
  EXPECT_EQ(curves[0].name, "qte");
  EXPECT_EQ(curves[1].name, "c2farm");

  ASSERT_EQ(curves[0].points.size(), 2u);
  const CurvePoint& p0 = curves[0].points[0];
  EXPECT_EQ(p0.x, 0);
  EXPECT_NEAR(p0.mean, 0.4, 1e-12);
  EXPECT_NEAR(p0.high - p0.mean, 0.2, 1e-12);  // sample std (n-1) of 0.2, 0.4, 0.6
  EXPECT_NEAR(p0.mean - p0.low, 0.2, 1e-12);
  const CurvePoint& p1 = curves[0].points[1];
  EXPECT_EQ(p1.x, 1000);
  EXPECT_NEAR(p1.mean, 0.9, 1e-12);
  EXPECT_NEAR(p1.high - p1.mean, std::sqrt(0.02), 1e-12);

  // c2farm: 0.1 and 0.3 at step 0, then one row at 2000 (no spread: no band).
  ASSERT_EQ(curves[1].points.size(), 2u);
  EXPECT_NEAR(curves[1].points[0].mean, 0.2, 1e-12);
  EXPECT_EQ(curves[1].points[1].x, 2000);
  EXPECT_EQ(curves[1].points[1].low, curves[1].points[1].mean);
  EXPECT_EQ(curves[1].points[1].high, curves[1].points[1].mean);
}

TEST(CurveBuilder, PointsInIncreasingXWithoutGrouping) {
  CurveBuilder builder({"step", "success_rate", ""}, Band::none);
  builder.add(parse_csv("t.csv", "step,success_rate\n200,1\n100,0\n150,0.5\n100,1\n"));
  const std::vector<Curve> curves = builder.curves();
  ASSERT_EQ(curves.size(), 1u);
  EXPECT_EQ(curves[0].name, "success_rate");
  std::vector<double> xs, means;
  for (const CurvePoint& p : curves[0].points) {
    xs.push_back(p.x);
    means.push_back(p.mean);
    EXPECT_EQ(p.low, p.mean);
    EXPECT_EQ(p.high, p.mean);
  }
  EXPECT_EQ(xs, (std::vector<double>{100, 150, 200}));
  EXPECT_EQ(means, (std::vector<double>{0.5, 0.5, 1}));
}

TEST(CurveBuilder, IntervalBandsFromTheTableOrFromTheSpread) {
  CurveBuilder with_columns({"step", "success_rate", "label"}, Band::ci);
  with_columns.add(parse_csv("runs.csv", kRuns));
  const CurvePoint p = with_columns.curves()[0].points[0];
  EXPECT_NEAR(p.low, 0.3, 1e-12);  // the mean of ci95_low over the seeds
  EXPECT_NEAR(p.high, 0.5, 1e-12);

  CurveBuilder from_spread({"step", "success_rate", ""}, Band::ci);
  from_spread.add(parse_csv("t.csv", "step,success_rate\n0,0.2\n0,0.4\n0,0.6\n"));
  const CurvePoint q = from_spread.curves()[0].points[0];
  EXPECT_NEAR(q.high - q.mean, 1.959963984540054 * 0.2 / std::sqrt(3.0), 1e-12);
}

TEST(CurveBuilder, ErrorsNameTheTableLineAndColumn) {
  CurveBuilder builder({"step", "reward", ""}, Band::std_dev);
  try {
    builder.add(parse_csv("runs.csv", kRuns));
    FAIL() << "a missing column was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "runs.csv: no column 'reward' (its header: label,seed,step,success_rate,ci95_low,ci95_high)");
  }
  CurveBuilder numbers({"step", "success_rate", ""}, Band::std_dev);
  try {
    numbers.add(parse_csv("text.csv", "step,success_rate\n0,0.5\n1000,half\n"));
    FAIL() << "a cell that is no number was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "text.csv: line 3, column 'success_rate': 'half' is not a finite number");
  }
  CurveBuilder empty({"step", "success_rate", ""}, Band::std_dev);
  empty.add(parse_csv("empty.csv", "step,success_rate\n"));
  EXPECT_THROW(empty.curves(), Error);
}

TEST(CurvePlot, PngOfTheAskedSizeAndTheSameBytesEveryTime) {
  CurvePlotOptions options = small_picture("reach_target");
  options.x_label = "step";
  options.y_label = "success_rate";
  options.legend = true;
  options.fixed_y = true;
  const std::vector<uint8_t> png = curve_plot_png(run_curves(), options);
  ASSERT_GT(png.size(), 24u);
  EXPECT_EQ(std::string(png.begin() + 1, png.begin() + 4), "PNG");
  auto big_endian = [&](std::size_t at) {
    return (uint32_t{png[at]} << 24) | (uint32_t{png[at + 1]} << 16) | (uint32_t{png[at + 2]} << 8) | png[at + 3];
  };
  EXPECT_EQ(big_endian(16), 400u);  // IHDR width, height
  EXPECT_EQ(big_endian(20), 300u);
  EXPECT_EQ(curve_plot_png(run_curves(), options), png);
}

// Values at the ends of the double range: an error, not a plot whose ticks never end.
TEST(CurvePlot, ARangeBeyondWhatADoubleHoldsIsAnError) {
  for (const char* table : {"step,success_rate\n-1e308,0.5\n1e308,0.5\n", "step,success_rate\n0,-1e308\n1,1e308\n"}) {
    CurveBuilder builder({"step", "success_rate", ""}, Band::std_dev);
    builder.add(parse_csv("huge.csv", table));
    CurvePlotOptions options;
    options.width_px = 200;
    options.height_px = 150;
    try {
      curve_plot_png(builder.curves(), options);
      ADD_FAILURE() << "plotted " << table;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("axis from"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("cannot be drawn"), std::string::npos) << e.what();
    }
  }
}

// A title wider than the picture is drawn smaller: its ink stays inside the picture's margins.
TEST(CurvePlot, ALongTitleIsShrunkNotCutOff) {
  const std::vector<uint8_t> png = curve_plot_png(
      run_curves(), small_picture("lift_numbered_block: qte-k10-t10 against c2farm-k1-t0, mean and std over seeds 0, 1 and 2"));
  const cv::Mat image = cv::imdecode(png, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(image.cols, 400);
  int left = image.cols, right = -1;
  for (int y = 0; y < 30; ++y)  // the title's band, above the data area
    for (int x = 0; x < image.cols; ++x)
      if (image.at<uint8_t>(y, x) < 128) left = std::min(left, x), right = std::max(right, x);
  ASSERT_GE(right, 0) << "no title drawn";
  EXPECT_GE(left, 3);
  EXPECT_LE(right, image.cols - 4);
  EXPECT_GT(right - left, image.cols / 2);  // shrunk to fit, not to nothing
}

// Small multiples: rows split by the panel column in order of appearance, each panel with its
// own curves in order of appearance; without a panel column, one unnamed panel.
TEST(CurveBuilder, PanelsSplitRowsByTheirColumnInOrderOfAppearance) {
  const char* table =
      "task,label,step,success_rate\n"
      "reach,qte,0,0.5\n"
      "lift,c2farm,0,0.1\n"
      "reach,c2farm,0,0.3\n"
      "lift,qte,0,0.2\n"
      "lift,qte,0,0.4\n";
  CurveBuilder builder({"step", "success_rate", "label", "task"}, Band::std_dev);
  builder.add(parse_csv("tasks.csv", table));
  const std::vector<CurvePanel> panels = builder.panels();
  ASSERT_EQ(panels.size(), 2u);
  EXPECT_EQ(panels[0].name, "reach");
  EXPECT_EQ(panels[1].name, "lift");
  ASSERT_EQ(panels[1].curves.size(), 2u);
  EXPECT_EQ(panels[1].curves[0].name, "c2farm");
  EXPECT_EQ(panels[1].curves[1].name, "qte");
  EXPECT_NEAR(panels[1].curves[1].points.at(0).mean, 0.3, 1e-12);  // lift's qte rows only
  EXPECT_NEAR(panels[0].curves[0].points.at(0).mean, 0.5, 1e-12);

  CurveBuilder one({"step", "success_rate", "label"}, Band::std_dev);
  one.add(parse_csv("tasks.csv", table));
  ASSERT_EQ(one.panels().size(), 1u);
  EXPECT_EQ(one.panels()[0].name, "");
  EXPECT_EQ(one.panels()[0].curves.size(), 2u);  // every task's rows in the same two curves
}

namespace {

// Pixels within `tolerance` of a BGR colour in a rectangle of a picture.
int count_near(const cv::Mat& image, const cv::Rect& where, const cv::Vec3b& colour, int tolerance = 30) {
  int count = 0;
  for (int y = where.y; y < where.br().y; ++y)
    for (int x = where.x; x < where.br().x; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      count += std::abs(p[0] - colour[0]) + std::abs(p[1] - colour[1]) + std::abs(p[2] - colour[2]) < tolerance;
    }
  return count;
}

// The first row (from the top) of a rectangle holding a pixel near `colour`; -1 if none.
int first_row_near(const cv::Mat& image, const cv::Rect& where, const cv::Vec3b& colour) {
  for (int y = where.y; y < where.br().y; ++y)
    if (count_near(image, cv::Rect(where.x, y, where.width, 1), colour, 12)) return y;
  return -1;
}

}  // namespace

// Panels laid out `columns` to a row under the title, each of the asked size; a curve keeps the
// colour of its name in every panel (c2farm is second in the first panel, first alone in the
// second: orange in both), and the panels share one vertical axis, so equal values are drawn at
// equal heights whatever else a panel holds.
TEST(CurvePlot, PanelsShareTheVerticalAxisAndEachCurveKeepsItsColour) {
  const char* table =
      "task,label,step,success_rate\n"
      "reach,qte,0,0.9\nreach,qte,100,0.9\n"
      "reach,c2farm,0,0.3\nreach,c2farm,100,0.3\n"
      "lift,c2farm,0,0.3\nlift,c2farm,5000,0.3\n"
      "stack,qte,0,0.1\nstack,qte,10,0.1\n";
  CurveBuilder builder({"step", "success_rate", "label", "task"}, Band::none);
  builder.add(parse_csv("tasks.csv", table));
  CurvePlotOptions options;  // 800x500 a panel: lines 2 pixels wide
  options.title = "three tasks";
  const std::vector<uint8_t> png = panel_plot_png(builder.panels(), options, 2);
  EXPECT_EQ(panel_plot_png(builder.panels(), options, 2), png);
  const cv::Mat image = cv::imdecode(png, cv::IMREAD_COLOR);
  ASSERT_EQ(image.cols, 1600);                  // 2 panels to a row
  ASSERT_GT(image.rows, 1000);                  // 2 rows, and a title band above them
  const int band = image.rows - 1000;
  const cv::Rect reach(0, band, 800, 500), lift(800, band, 800, 500), stack(0, band + 500, 800, 500),
      empty(800, band + 500, 800, 500);
  const cv::Vec3b blue(180, 119, 31), orange(14, 127, 255);
  EXPECT_GT(count_near(image, reach, blue), 100);
  EXPECT_GT(count_near(image, reach, orange), 100);
  EXPECT_EQ(count_near(image, lift, blue), 0);
  EXPECT_GT(count_near(image, lift, orange), 100);   // c2farm, orange as in the first panel
  EXPECT_GT(count_near(image, stack, blue), 100);    // qte, blue as in the first panel
  EXPECT_EQ(count_near(image, stack, orange), 0);
  EXPECT_EQ(count_near(image, empty, cv::Vec3b(255, 255, 255), 1), 800 * 500);  // nothing drawn
  // c2farm's 0.3 at the same height in both panels (the y axis spans 0.1 to 0.9 in each).
  const int in_reach = first_row_near(image, reach, orange), in_lift = first_row_near(image, lift, orange);
  ASSERT_GE(in_reach, 0);
  EXPECT_NEAR(in_reach, in_lift, 1);
  // The picture's title is inked in the band above the panels.
  cv::Mat gray;
  cv::cvtColor(image(cv::Rect(0, 0, image.cols, band)), gray, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(gray < 128), 50);
}
