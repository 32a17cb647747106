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

}  // namespace qte::render
