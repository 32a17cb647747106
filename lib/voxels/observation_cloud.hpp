// The coloured point cloud of an observation record, from every camera: the stored world
// points (<camera>.points), or points rebuilt from depth and the camera's intrinsics and
// extrinsics when only depth is stored (<camera>.depth in metres, or <camera>.depth_mm as
// uint16 millimetres, the compact form of the replay).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stream/record.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxels {

struct ObservationCloud {
  std::vector<float> xyz;    // count * 3, world frame; NaN where a pixel has no return
  std::vector<uint8_t> rgb;  // count * 3
  PointCloud view() const { return {xyz.data(), rgb.data(), rgb.size() / 3}; }
};

// Throws StreamError naming the record when it holds no camera with rgb and points or depth.
ObservationCloud observation_cloud(const stream::Record& obs);

// The same points one camera at a time, in the record's camera order, with the image size
// (a camera's cloud is organized: pixel (row, col) is point row * width + col).
struct CameraCloud {
  std::string camera;  // "front"
  int height = 0, width = 0;
  ObservationCloud cloud;
};
std::vector<CameraCloud> camera_clouds(const stream::Record& obs);

// What is wrong with a camera's matrices, or "" when they are usable. Intrinsics (row-major
// 3x3, pixels): finite, positive focal lengths, last row 0 0 1. Extrinsics (row-major 4x4,
// camera to world): finite, a proper rotation (orthonormal, determinant +1, within 1e-3),
// last row 0 0 0 1. A camera failing these sees nothing, or a mirror image of the scene.
std::string intrinsics_problem(const double* k);
std::string extrinsics_problem(const double* e);
// The record's <camera>.intrinsics (when present) and <camera>.extrinsics, checked as above:
// fails naming the record and the field. Every reader of camera matrices calls this.
void check_camera_matrices(const stream::Record& obs, const std::string& camera);

// How many points of `cloud` lie inside `bounds` (NaN points never do).
std::size_t points_inside(const PointCloud& cloud, const GridBounds& bounds);
// Fails naming the record when no point of its cloud lies inside the scene bounds: nothing
// was seen, so nothing may be chosen or learnt from it.
void require_points_in_scene(const stream::Record& obs, const ObservationCloud& cloud, const GridBounds& scene);

// Depth in metres as uint16 millimetres (the replay's and depth cameras' form): rounded to the
// nearest, 0 (no return) stays 0, beyond 65.535 m saturates.
std::vector<uint16_t> depth_in_mm(const float* depth_m, std::size_t count);

// World points of a depth image (metres along the optical axis, 0 = none -> NaN).
void points_from_depth(const float* depth_m, int width, int height, const double* intrinsics_3x3,
                       const double* extrinsics_4x4, float* xyz_out);

}  // namespace qte::voxels
