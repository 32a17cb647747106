// Procedural text textures: size, colour order, and a large centred glyph.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "common/error.hpp"
#include "render/textures.hpp"

using qte::Error;
using namespace qte::render;

namespace {

// Pixels that are exactly the ink colour, as a mask.
cv::Mat ink_mask(const cv::Mat& image, const cv::Vec3b& ink) {
  cv::Mat mask;
  cv::inRange(image, cv::Scalar(ink[0], ink[1], ink[2]), cv::Scalar(ink[0], ink[1], ink[2]), mask);
  return mask;
}

}  // namespace

TEST(TextureText, IsASquareRgbImageOnPaper) {
  const cv::Mat image = text_texture("2", 96, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f});
  ASSERT_EQ(image.type(), CV_8UC3);
  EXPECT_EQ(image.size(), cv::Size(96, 96));
  // RGB order: red paper is channel 0, blue ink channel 2.
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 0, 0));
  EXPECT_EQ(image.at<cv::Vec3b>(95, 95), cv::Vec3b(255, 0, 0));
  EXPECT_GT(cv::countNonZero(ink_mask(image, {0, 0, 255})), 96 * 96 / 20);
}

TEST(TextureText, GlyphIsLargeAndCentred) {
  for (int size : {32, 64, 256}) {
    const cv::Mat image = text_texture("2", size, {1, 1, 1}, {0, 0, 0});
    cv::Mat grey, inked;
    cv::cvtColor(image, grey, cv::COLOR_RGB2GRAY);
    cv::threshold(grey, inked, 128, 255, cv::THRESH_BINARY_INV);
    const cv::Rect box = cv::boundingRect(inked);
    EXPECT_GT(box.height, 0.6 * size) << size;
    EXPECT_LT(box.height, 0.8 * size) << size;
    EXPECT_NEAR(box.x + box.width / 2.0, size / 2.0, 0.08 * size) << size;
    EXPECT_NEAR(box.y + box.height / 2.0, size / 2.0, 0.08 * size) << size;
    // Thick strokes: ink covers a fair share of its bounding box.
    EXPECT_GT(cv::countNonZero(inked(box)), 0.2 * box.area()) << size;
  }
}

TEST(TextureText, WideTextFitsInside) {
  const cv::Mat image = text_texture("12", 64, {1, 1, 1}, {0, 0, 0});
  cv::Mat grey, inked;
  cv::cvtColor(image, grey, cv::COLOR_RGB2GRAY);
  cv::threshold(grey, inked, 128, 255, cv::THRESH_BINARY_INV);
  const cv::Rect box = cv::boundingRect(inked);
  EXPECT_GT(box.x, 0);
  EXPECT_LT(box.x + box.width, 64);
  EXPECT_GT(box.width, 0.5 * 64);  // getTextSize counts side bearings, the ink is narrower
}

TEST(TextureText, DifferentDigitsDiffer) {
  const cv::Mat two = text_texture("2", 64, {1, 1, 1}, {0, 0, 0});
  const cv::Mat five = text_texture("5", 64, {1, 1, 1}, {0, 0, 0});
  EXPECT_GT(cv::norm(two, five, cv::NORM_L1), 0);
}

TEST(TextureText, RejectsEmptyTextAndSillySizes) {
  EXPECT_THROW(text_texture("", 64, {1, 1, 1}, {0, 0, 0}), Error);
  EXPECT_THROW(text_texture("2", 0, {1, 1, 1}, {0, 0, 0}), Error);
  EXPECT_THROW(text_texture("2", 100000, {1, 1, 1}, {0, 0, 0}), Error);
}

TEST(TextureCheckerboard, DarkWhereRowPlusColumnIsEvenFromTheBottomLeft) {
  const cv::Mat board = checkerboard_texture(8, {1.0f, 1.0f, 1.0f}, {0.0f, 0.5f, 0.0f});
  ASSERT_EQ(board.rows, 8);
  ASSERT_EQ(board.cols, 8);
  for (int row = 0; row < 8; ++row)
    for (int column = 0; column < 8; ++column) {
      const cv::Vec3b pixel = board.at<cv::Vec3b>(7 - row, column);
      const bool dark = (row + column) % 2 == 0;
      EXPECT_EQ(pixel, dark ? cv::Vec3b(0, 128, 0) : cv::Vec3b(255, 255, 255)) << row << " " << column;
    }
  EXPECT_THROW(checkerboard_texture(0, {1, 1, 1}, {0, 0, 0}), Error);
}
