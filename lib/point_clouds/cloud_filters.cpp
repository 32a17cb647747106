#include "point_clouds/cloud_filters.hpp"

#include <pcl/common/common.h>
#include <pcl/filters/crop_box.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>

#include <climits>
#include <cmath>

#include "common/error.hpp"
#include "stream/field_names.hpp"

namespace qte::point_clouds {

using Cloud = pcl::PointCloud<pcl::PointXYZRGB>;

std::vector<cli::OptionSpec> cloud_filter_options() {
  return {
      {"crop", "X0,Y0,Z0,X1,Y1,Z1", "point-cloud filter: keep only points inside this box (world frame, metres)", ""},
      {"outliers", "K,S",
       "point-cloud filter: drop points whose mean distance to their K nearest neighbours is more than S "
       "standard deviations above the cloud's mean (PCL's statistical outlier removal; e.g. 20,2)",
       ""},
      cli::real_option("downsample", "M",
                       "point-cloud filter: replace the points in each M-metre cube by their centroid and mean "
                       "colour (PCL's voxel grid)",
                       "", 1e-4, 1.0),
  };
}

CloudFilters parse_cloud_filters(const cli::Arguments& args) {
  CloudFilters f;
  if (args.has("crop")) {
    const auto v = args.reals("crop", 6);
    const Eigen::Vector3f lo = Eigen::Vector3d(v[0], v[1], v[2]).cast<float>();
    const Eigen::Vector3f hi = Eigen::Vector3d(v[3], v[4], v[5]).cast<float>();
    if (!(lo.array() < hi.array()).all()) throw UsageError("--crop: the first corner must be below the second on every axis");
    f.crop = Eigen::AlignedBox3f(lo, hi);
  }
  if (args.has("outliers")) {
    const auto v = args.reals("outliers", 2);
    if (!(v[0] >= 1 && v[0] <= 1000 && v[0] == std::floor(v[0])))
      throw UsageError("--outliers: K must be a whole number of neighbours, 1..1000");
    if (!(v[1] > 0 && v[1] <= 100)) throw UsageError("--outliers: S must be in (0, 100] standard deviations");
    f.outlier_neighbours = static_cast<int>(v[0]);
    f.outlier_stddevs = v[1];
  }
  if (args.has("downsample")) f.downsample_m = args.real("downsample");
  return f;
}

namespace {

Cloud to_pcl(const voxels::ObservationCloud& in) {
  Cloud cloud;
  const std::size_t n = in.rgb.size() / 3;
  cloud.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = &in.xyz[3 * i];
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) continue;
    pcl::PointXYZRGB q(in.rgb[3 * i], in.rgb[3 * i + 1], in.rgb[3 * i + 2]);
    q.x = p[0], q.y = p[1], q.z = p[2];
    cloud.push_back(q);
  }
  return cloud;
}

voxels::ObservationCloud from_pcl(const Cloud& cloud) {
  voxels::ObservationCloud out;
  out.xyz.reserve(3 * cloud.size());
  out.rgb.reserve(3 * cloud.size());
  for (const auto& p : cloud) {
    out.xyz.insert(out.xyz.end(), {p.x, p.y, p.z});
    out.rgb.insert(out.rgb.end(), {p.r, p.g, p.b});
  }
  return out;
}

// PCL's voxel grid indexes leaves with a 32-bit integer and, when they do not fit, warns and
// returns the cloud as it was: refuse instead.
void check_leaf_fits(const Cloud& cloud, double leaf) {
  if (cloud.empty()) return;
  pcl::PointXYZRGB lo, hi;
  pcl::getMinMax3D(cloud, lo, hi);
  const double leaves = std::floor((hi.x - lo.x) / leaf + 1) * std::floor((hi.y - lo.y) / leaf + 1) *
                        std::floor((hi.z - lo.z) / leaf + 1);
  if (leaves > double(INT_MAX))
    throw Error("--downsample " + std::to_string(leaf) + ": too small a leaf for a cloud this large (" +
                std::to_string(leaves) + " leaves); crop the cloud first (--crop) or use a larger leaf");
}

}  // namespace

voxels::ObservationCloud filter_cloud(const voxels::ObservationCloud& in, const CloudFilters& filters) {
  Cloud::Ptr cloud(new Cloud(to_pcl(in)));
  if (filters.crop) {
    pcl::CropBox<pcl::PointXYZRGB> crop;
    crop.setMin(Eigen::Vector4f(filters.crop->min().x(), filters.crop->min().y(), filters.crop->min().z(), 1));
    crop.setMax(Eigen::Vector4f(filters.crop->max().x(), filters.crop->max().y(), filters.crop->max().z(), 1));
    crop.setInputCloud(cloud);
    Cloud::Ptr kept(new Cloud);
    crop.filter(*kept);
    cloud = kept;
  }
  if (filters.outlier_neighbours > 0 && !cloud->empty()) {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZRGB> outliers;
    outliers.setMeanK(filters.outlier_neighbours);
    outliers.setStddevMulThresh(filters.outlier_stddevs);
    outliers.setInputCloud(cloud);
    Cloud::Ptr kept(new Cloud);
    outliers.filter(*kept);
    cloud = kept;
  }
  if (filters.downsample_m > 0 && !cloud->empty()) {
    check_leaf_fits(*cloud, filters.downsample_m);
    pcl::VoxelGrid<pcl::PointXYZRGB> grid;
    const float leaf = static_cast<float>(filters.downsample_m);
    grid.setLeafSize(leaf, leaf, leaf);
    grid.setInputCloud(cloud);
    Cloud::Ptr kept(new Cloud);
    grid.filter(*kept);
    cloud = kept;
  }
  return from_pcl(*cloud);
}

stream::Record filter_observation(const stream::Record& obs, const CloudFilters& filters) {
  stream::Record out = obs;
  for (const voxels::CameraCloud& camera : voxels::camera_clouds(obs)) {
    const voxels::ObservationCloud kept = filter_cloud(camera.cloud, filters);
    const int64_t m = static_cast<int64_t>(kept.rgb.size() / 3);
    out.set<float>(camera.camera + fields::per_camera::points, {1, m, 3}, kept.xyz);
    out.set<uint8_t>(camera.camera + fields::per_camera::rgb, {1, m, 3}, kept.rgb);
    out.remove(camera.camera + fields::per_camera::depth);
    out.remove(camera.camera + fields::per_camera::depth_mm);
  }
  return out;
}

ObservationFilter observation_filter(const CloudFilters& filters) {
  if (!filters.any()) return nullptr;
  return [filters](const stream::Record& obs) { return filter_observation(obs, filters); };
}

}  // namespace qte::point_clouds
