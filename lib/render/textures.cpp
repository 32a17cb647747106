#include "render/textures.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/error.hpp"

namespace qte::render {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_DUPLEX;
constexpr double kInkShare = 0.7;  // the text's larger side, as a share of the square

// The drawing functions write channels in the order given, so RGB in gives RGB out.
cv::Scalar rgb_scalar(const Eigen::Vector3f& rgb) {
  auto level = [](float c) { return std::round(std::clamp(c, 0.0f, 1.0f) * 255.0f); };
  return cv::Scalar(level(rgb.x()), level(rgb.y()), level(rgb.z()));
}

}  // namespace

cv::Mat text_texture(const std::string& text, int size_px, const Eigen::Vector3f& paper,
                     const Eigen::Vector3f& ink) {
  if (text.empty()) throw Error("text_texture: the text is empty");
  if (size_px < 8 || size_px > 8192)
    throw Error("text_texture: size must be 8 to 8192 pixels, got " + std::to_string(size_px));

  cv::Mat image(size_px, size_px, CV_8UC3, rgb_scalar(paper));
  const int thickness = std::max(1, static_cast<int>(std::lround(size_px / 16.0)));
  // Text size grows with the scale apart from the stroke width, so one correction suffices.
  int baseline = 0;
  const cv::Size unit = cv::getTextSize(text, kFont, 1.0, thickness, &baseline);
  double scale = kInkShare * size_px / std::max(unit.width, unit.height);
  const cv::Size scaled = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  scale *= kInkShare * size_px / std::max(scaled.width, scaled.height);
  const cv::Size drawn = cv::getTextSize(text, kFont, scale, thickness, &baseline);

  // putText's origin is the baseline's left end; digits and capitals sit on the baseline.
  const cv::Point origin((size_px - drawn.width) / 2, (size_px + drawn.height) / 2);
  cv::putText(image, text, origin, kFont, scale, rgb_scalar(ink), thickness, cv::LINE_AA);
  return image;
}

cv::Mat checkerboard_texture(int squares, const Eigen::Vector3f& light, const Eigen::Vector3f& dark) {
  if (squares < 1 || squares > 1024)
    throw Error("checkerboard_texture: squares must be 1 to 1024, got " + std::to_string(squares));
  cv::Mat image(squares, squares, CV_8UC3, rgb_scalar(light));
  for (int row = 0; row < squares; ++row)      // from the bottom (image rows run down)
    for (int column = 0; column < squares; ++column)
      if ((row + column) % 2 == 0) image(cv::Rect(column, squares - 1 - row, 1, 1)).setTo(rgb_scalar(dark));
  return image;
}

}  // namespace qte::render
