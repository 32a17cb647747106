#include "point_clouds/pcd_file.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "common/error.hpp"

namespace qte::point_clouds {

void write_pcd(const std::string& path, const voxels::CameraCloud& camera) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud(static_cast<uint32_t>(camera.width), static_cast<uint32_t>(camera.height));
  cloud.is_dense = true;
  const auto& in = camera.cloud;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    auto& p = cloud[i];
    p.x = in.xyz[3 * i], p.y = in.xyz[3 * i + 1], p.z = in.xyz[3 * i + 2];
    p.r = in.rgb[3 * i], p.g = in.rgb[3 * i + 1], p.b = in.rgb[3 * i + 2];
    if (!std::isfinite(p.x)) cloud.is_dense = false;
  }
  // PCL writes to a path; write beside it under the temporary name AtomicOutputFile uses (so a
  // killed writer's leftover is recognised and removed), then rename.
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  if (pcl::io::savePCDFileBinary(temp, cloud) != 0) {
    std::remove(temp.c_str());
    throw Error("cannot write " + path);
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw_system_error("cannot rename " + temp + " to " + path);
  }
}

voxels::CameraCloud read_pcd(const std::string& path) {
  // PCL's own warnings would go to stderr beside ours, which name the file and what was expected.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  // The header first: PCL's reader crashes on some files that are not point clouds at all.
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_start = 0;
  if (reader.readHeader(path, blob, origin, orientation, version, data_type, data_start) != 0 || blob.fields.empty() ||
      uint64_t(blob.width) * blob.height == 0)
    throw Error(path + ": not a .pcd point cloud (expected a PCD header with FIELDS, WIDTH, HEIGHT and POINTS)");
  if (reader.read(path, blob) != 0) throw Error(path + ": not a readable .pcd file");
  bool has_x = false, has_rgb = false;
  for (const auto& f : blob.fields) {
    has_x = has_x || f.name == "x";
    has_rgb = has_rgb || f.name == "rgb" || f.name == "rgba";
  }
  if (!has_x) throw Error(path + ": expected a point cloud with x, y, z fields");
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  voxels::CameraCloud out;
  out.width = static_cast<int>(cloud.width);
  out.height = static_cast<int>(cloud.height);
  if (static_cast<std::size_t>(out.width) * out.height != cloud.size()) out.width = static_cast<int>(cloud.size()), out.height = 1;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const auto& p : cloud) {
    const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    out.cloud.xyz.insert(out.cloud.xyz.end(), {finite ? p.x : nan, finite ? p.y : nan, finite ? p.z : nan});
    if (has_rgb) out.cloud.rgb.insert(out.cloud.rgb.end(), {p.r, p.g, p.b});
    else out.cloud.rgb.insert(out.cloud.rgb.end(), {255, 255, 255});
  }
  return out;
}

}  // namespace qte::point_clouds
