// Point-cloud filters for real sensors, with PCL: crop to a box, statistical outlier removal,
// voxel-grid downsampling, applied to each camera's cloud in that order before an observation
// is voxelized or planned on. One option group for voxelize, qte-select and plan-path; off by
// default, since simulated clouds are clean.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <vector>

#include "cli/command.hpp"
#include "stream/record.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::point_clouds {

struct CloudFilters {
  std::optional<Eigen::AlignedBox3f> crop;  // keep points inside (world frame)
  int outlier_neighbours = 0;               // 0: no outlier removal
  double outlier_stddevs = 2.0;
  double downsample_m = 0;                  // voxel-grid leaf edge; 0: none
  bool any() const { return crop || outlier_neighbours > 0 || downsample_m > 0; }
};

std::vector<cli::OptionSpec> cloud_filter_options();  // --crop, --outliers, --downsample
CloudFilters parse_cloud_filters(const cli::Arguments& args);

// One camera's points (NaN = no return, dropped) through the filters: an unorganized cloud.
// Throws Error when the downsampling leaf is too small for the cloud's extent (PCL would
// silently return the cloud unfiltered).
voxels::ObservationCloud filter_cloud(const voxels::ObservationCloud& cloud, const CloudFilters& filters);

// The observation with each camera's cloud replaced by its filtered form: <camera>.points and
// <camera>.rgb of shape [1, M, 3] (an unorganized cloud, as PCL stores one), depth images
// dropped since they no longer match it; intrinsics, extrinsics and everything else kept.
// Tools use it in place of the record and pass the original on.
stream::Record filter_observation(const stream::Record& obs, const CloudFilters& filters);

// What the stages that read observations (voxelize, qte-select, plan-path) make of each one
// before using it: filter_observation with `filters`; nothing (use it as it is) without any.
using ObservationFilter = std::function<stream::Record(const stream::Record&)>;
ObservationFilter observation_filter(const CloudFilters& filters);

}  // namespace qte::point_clouds
