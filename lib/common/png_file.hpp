// Pictures as PNG files, the one way every program saves them: encoded with OpenCV (BGR colour,
// or 16-bit grey), written atomically.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace qte {

// Error naming `what` when OpenCV cannot encode `image`.
std::vector<uint8_t> encode_png(const cv::Mat& image, const std::string& what);
void write_png(const std::string& path, const cv::Mat& image);

}  // namespace qte
