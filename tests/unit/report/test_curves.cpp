// Learning curves: rows grouped by a column in order of appearance, averaged per x with std or
// interval bands, over tables with differently ordered columns; and the picture's bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>

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
      EXPECT_NE(std::string(e.what()).find("more than a plot can draw"), std::string::npos) << e.what();
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
