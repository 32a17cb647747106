// A camera's saved frames as PNG files: the colour image and the 16-bit depth image. Read with
// libpng itself, so the header is checked before anything is decoded and libpng's own warnings
// and errors never reach stderr: every failure is one Error naming the file.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace qte::camera_recordings {

// The most pixels a frame may have (each side at most kMaxPngSide): a camera's, with room to
// spare. Larger headers are refused before any pixel is decoded.
constexpr uint64_t kMaxPngPixels = 50'000'000;
constexpr uint32_t kMaxPngSide = 32768;

// Any PNG as 8-bit BGR, as OpenCV's imread(IMREAD_COLOR) gives it: grey and palette images
// expanded, alpha dropped, 16 bits reduced to 8.
cv::Mat read_colour_png(const std::string& path);

// A 16-bit single-channel (greyscale) PNG as CV_16UC1; any other PNG is refused.
cv::Mat read_depth_png(const std::string& path);

}  // namespace qte::camera_recordings
