// Point clouds as PCL's .pcd files (binary, XYZRGB), the form pcl_viewer and PCL programs open.
#pragma once

#include <cstdint>
#include <string>

#include "voxels/observation_cloud.hpp"

namespace qte::point_clouds {

// Writes the camera's cloud organized (width x height, NaN where a pixel has no return),
// atomically: a killed or failed write leaves no file under `path`.
void write_pcd(const std::string& path, const voxels::CameraCloud& cloud);

// The most points read_pcd takes from one file: a camera frame's, with room to spare.
constexpr uint64_t kMaxPcdPoints = 50'000'000;

// Reads a .pcd (DATA ascii, binary or binary_compressed) with x, y, z as 4-byte floats (TYPE F
// SIZE 4 COUNT 1) and, when present, rgb or rgba as 4 packed bytes (TYPE F or U; white
// otherwise). An organized file keeps its width and height; an unorganized one is 1 x N. The
// header is checked against the data and the file's size before anything is allocated: WIDTH x
// HEIGHT = POINTS (1 to kMaxPcdPoints), one SIZE, TYPE and COUNT per field, binary data as long
// as POINTS x the point's bytes, compressed sizes that agree, ASCII with exactly POINTS lines of
// one whole number per value. Throws Error naming the file and what was expected.
voxels::CameraCloud read_pcd(const std::string& path);

}  // namespace qte::point_clouds
