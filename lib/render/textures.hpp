// Procedural textures drawn with OpenCV, e.g. the digits on lift_numbered_block's blocks.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>

namespace qte::render {

// A square RGB image (CV_8UC3) of `size_px` with `text` (e.g. "2") drawn large and centred
// in `ink` on `paper` (colours RGB in [0, 1]): its larger side spans 70% of the square.
// Throws Error for empty text or a size outside 8..8192.
cv::Mat text_texture(const std::string& text, int size_px, const Eigen::Vector3f& paper,
                     const Eigen::Vector3f& ink);

// A board of `squares` x `squares` (RGB, CV_8UC3, one pixel a square: faces are sampled
// nearest-neighbour), `dark` where row + column is even, counted from the image's bottom
// left (the face's -x, -y corner, see Appearance). Throws Error for squares outside 1..1024.
cv::Mat checkerboard_texture(int squares, const Eigen::Vector3f& light, const Eigen::Vector3f& dark);

}  // namespace qte::render
