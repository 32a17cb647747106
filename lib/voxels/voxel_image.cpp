#include "voxels/voxel_image.hpp"

#include <algorithm>
#include <array>
#include <opencv2/imgproc.hpp>

#include "common/png_file.hpp"
#include "common/error.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxels {
namespace {

// View from the front-right, above: world x towards the viewer-left, z up.
cv::Point2f project(double x, double y, double z, int voxels, int size_px) {
  const double s = size_px / (2.2 * voxels);
  const double u = (y - x) * 0.866 * s + size_px / 2.0;
  const double v = size_px * 0.62 - (z * 1.0 + (x + y) * 0.5 - voxels * 0.5) * s;
  return cv::Point2f(static_cast<float>(u), static_cast<float>(v));
}

// One voxel's cube: its three visible faces, top (+z), front-left (+x) and front-right (+y),
// shaded differently and outlined.
void draw_cube(cv::Mat& image, const Eigen::Vector3i& at, const cv::Vec3d& bgr, int voxels, int size_px) {
  const std::array<std::array<std::array<int, 3>, 4>, 3> faces = {{
      {{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}},
      {{{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}},
      {{{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}},
  }};
  const double shade[3] = {1.0, 0.8, 0.65};
  for (int f = 0; f < 3; ++f) {
    std::vector<cv::Point> corners;
    for (const auto& c : faces[f]) corners.push_back(project(at.x() + c[0], at.y() + c[1], at.z() + c[2], voxels, size_px));
    cv::fillConvexPoly(image, corners, cv::Scalar(bgr[0] * shade[f], bgr[1] * shade[f], bgr[2] * shade[f]), cv::LINE_AA);
    cv::polylines(image, corners, true, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
}

}  // namespace

void save_voxel_png(const std::string& path, const float* grid, int voxels, const VoxelImageOptions& options) {
  const int n = voxels * voxels * voxels;
  if (!options.values.empty() && static_cast<int>(options.values.size()) != n)
    throw Error("voxel image: " + std::to_string(options.values.size()) + " values for " + std::to_string(n) + " voxels");
  float lo = 1e30f, hi = -1e30f;
  for (float v : options.values)
    if (v > options.min_value) lo = std::min(lo, v), hi = std::max(hi, v);
  cv::Mat colour_map;
  if (!options.values.empty()) {
    cv::Mat ramp(1, 256, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(0, i) = static_cast<uint8_t>(i);
    cv::applyColorMap(ramp, colour_map, cv::COLORMAP_TURBO);  // BGR
  }
  cv::Mat image(options.size_px, options.size_px, CV_8UC3, cv::Scalar(255, 255, 255));  // BGR
  // The bounding cube's floor, for orientation.
  std::vector<cv::Point> floor;
  for (auto [x, y] : std::array<std::pair<int, int>, 4>{{{0, 0}, {voxels, 0}, {voxels, voxels}, {0, voxels}}})
    floor.push_back(project(x, y, 0, voxels, options.size_px));
  cv::fillConvexPoly(image, floor, cv::Scalar(235, 235, 235), cv::LINE_AA);
  // Painter's order: far from the viewer (large x + y) and low z first.
  std::vector<int> order;
  for (int i = 0; i < n; ++i) {
    const bool drawn = options.values.empty() ? grid[i * kChannels + 9] > 0 : options.values[i] > options.min_value;
    if (drawn) order.push_back(i);
  }
  auto depth = [&](int i) {
    const Eigen::Vector3i at = index_from_flat(i, voxels);
    return at.z() - (at.x() + at.y());
  };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth(a) < depth(b); });
  for (int i : order) {
    const Eigen::Vector3i at = index_from_flat(i, voxels);
    cv::Vec3d bgr;
    if (options.values.empty()) {
      const float* c = grid + i * kChannels;
      bgr = cv::Vec3d((c[5] + 1) * 127.5, (c[4] + 1) * 127.5, (c[3] + 1) * 127.5);
    } else {
      const float t = hi > lo ? (options.values[i] - lo) / (hi - lo) : 1.0f;
      const cv::Vec3b m = colour_map.at<cv::Vec3b>(0, std::clamp(static_cast<int>(t * 255), 0, 255));
      bgr = cv::Vec3d(m[0], m[1], m[2]);
    }
    draw_cube(image, at, bgr, voxels, options.size_px);
  }
  // The marked voxel's outline last, all twelve edges, so cubes in front do not hide it.
  if (options.marked_x >= 0 && options.marked_y >= 0 && options.marked_z >= 0) {
    const int x = options.marked_x, y = options.marked_y, z = options.marked_z;
    for (int a = 0; a < 8; ++a)
      for (int bit = 1; bit < 8; bit <<= 1) {
        const int b = a | bit;
        if (b == a) continue;
        cv::line(image, project(x + (a & 1), y + (a >> 1 & 1), z + (a >> 2 & 1), voxels, options.size_px),
                 project(x + (b & 1), y + (b >> 1 & 1), z + (b >> 2 & 1), voxels, options.size_px),
                 cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
      }
  }
  write_png(path, image);
}

}  // namespace qte::voxels
