// Point clouds as PCL's .pcd files (binary, XYZRGB), the form pcl_viewer and PCL programs open.
#pragma once

#include <string>

#include "voxels/observation_cloud.hpp"

namespace qte::point_clouds {

// Writes the camera's cloud organized (width x height, NaN where a pixel has no return),
// atomically: a killed or failed write leaves no file under `path`.
void write_pcd(const std::string& path, const voxels::CameraCloud& cloud);

// Reads a .pcd with x, y, z (and rgb or rgba when present; white otherwise). An organized
// file keeps its width and height; an unorganized one is 1 x N. Throws Error naming the file.
voxels::CameraCloud read_pcd(const std::string& path);

}  // namespace qte::point_clouds
