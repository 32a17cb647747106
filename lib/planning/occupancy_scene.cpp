#include "planning/occupancy_scene.hpp"

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "common/atomic_file.hpp"
#include "common/error.hpp"

namespace qte::planning {

struct OccupancyScene::Impl {
  SceneOptions options;
  octomap::OcTree tree;
  // The distance field, copied out of DynamicEDTOctomap into one flat array (z fastest): a
  // query is then a few multiplications and one load, not bounds checks and three levels of
  // pointers. It covers the occupied voxels' bounding box grown by max_distance_m (within the
  // map box); everywhere else is at least that far from anything.
  bool built = false;
  std::vector<float> distance;
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  Eigen::Vector3i first_cell = Eigen::Vector3i::Zero();  // cell index of the field's first cell
  double cells_per_m = 0;

  explicit Impl(const SceneOptions& o) : options(o), tree(o.resolution_m), cells_per_m(1.0 / o.resolution_m) {}

  // The cell containing `v`, as octomap's coordToKey computes it (less its key offset).
  int cell(double v) const { return static_cast<int>(std::floor(cells_per_m * v)); }

  double lookup(const Eigen::Vector3d& p) const {
    const int x = cell(p.x()) - first_cell.x(), y = cell(p.y()) - first_cell.y(), z = cell(p.z()) - first_cell.z();
    if (x < 0 || y < 0 || z < 0 || x >= size.x() || y >= size.y() || z >= size.z())
      return options.max_distance_m;
    // (The field holds floats; saturated ones come back as exactly max_distance_m.)
    return std::min<double>(distance[(static_cast<std::size_t>(x) * size.y() + y) * size.z() + z],
                            options.max_distance_m);
  }

  void require_field() const {
    if (!built)
      throw Error("occupancy scene: no distance field (call build_distance_field() after inserting cameras)");
  }
};

OccupancyScene::OccupancyScene(const SceneOptions& options) {
  if (!(options.resolution_m > 0) || !(options.max_distance_m > 0) || !(options.robot_filter_margin_m >= 0))
    throw Error("occupancy scene: resolution, max distance must be > 0 and the robot filter margin >= 0");
  if (!(options.max_corner.array() > options.min_corner.array()).all())
    throw Error("occupancy scene: max_corner must lie above min_corner on every axis");
  impl_ = std::make_unique<Impl>(options);
  // Rays are traced only inside the box: free space outside it is never asked about.
  octomap::point3d lo(options.min_corner.x(), options.min_corner.y(), options.min_corner.z());
  octomap::point3d hi(options.max_corner.x(), options.max_corner.y(), options.max_corner.z());
  impl_->tree.setBBXMin(lo);
  impl_->tree.setBBXMax(hi);
  impl_->tree.useBBXLimit(true);
}

OccupancyScene::~OccupancyScene() = default;
OccupancyScene::OccupancyScene(OccupancyScene&&) noexcept = default;
OccupancyScene& OccupancyScene::operator=(OccupancyScene&&) noexcept = default;

void OccupancyScene::insert_camera(const float* points_xyz, std::size_t count, const Eigen::Vector3d& sensor_origin,
                                   const std::vector<Sphere>& robot, const std::vector<Sphere>& free_regions) {
  const SceneOptions& o = impl_->options;
  const Eigen::Vector3f lo = o.min_corner.cast<float>(), hi = o.max_corner.cast<float>();

  // The robot's spheres grown by the margin, with their bounding box as a quick first test:
  // most points (table, objects) are nowhere near the arm.
  std::vector<std::pair<Eigen::Vector3f, float>> grown;  // centre, squared radius
  Eigen::Vector3f robot_lo = Eigen::Vector3f::Constant(INFINITY), robot_hi = -robot_lo;
  for (const Sphere& s : robot) {
    const float r = static_cast<float>(s.radius_m + o.robot_filter_margin_m);
    grown.emplace_back(s.centre.cast<float>(), r * r);
    robot_lo = robot_lo.cwiseMin(s.centre.cast<float>() - Eigen::Vector3f::Constant(r));
    robot_hi = robot_hi.cwiseMax(s.centre.cast<float>() + Eigen::Vector3f::Constant(r));
  }
  auto in_free_region = [&](const Eigen::Vector3f& p) {
    for (const Sphere& s : free_regions)
      if ((p.cast<double>() - s.centre).squaredNorm() < s.radius_m * s.radius_m) return true;
    return false;
  };

  auto on_robot = [&](const Eigen::Vector3f& p) {
    if ((p.array() < robot_lo.array()).any() || (p.array() > robot_hi.array()).any()) return false;
    for (const auto& [centre, r2] : grown)
      if ((p - centre).squaredNorm() < r2) return true;
    return false;
  };

  octomap::Pointcloud cloud;
  cloud.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3f p(points_xyz[3 * i], points_xyz[3 * i + 1], points_xyz[3 * i + 2]);
    if (!p.allFinite()) continue;  // no return
    if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
    if (in_free_region(p)) continue;
    if (on_robot(p)) continue;
    cloud.push_back(p.x(), p.y(), p.z());
  }
  // discretize: one ray per endpoint voxel rather than per point (a quarter faster at 256x256,
  // even at 128x128). lazy_eval, then inner nodes and pruning once: the same tree (the same
  // .bt bytes) as updating them at every voxel, in about three quarters of the time.
  // bench_scene measures both.
  octomap::OcTree& tree = impl_->tree;
  tree.insertPointCloud(cloud, octomap::point3d(sensor_origin.x(), sensor_origin.y(), sensor_origin.z()), -1.0,
                        /*lazy_eval=*/true, /*discretize=*/true);
  tree.updateInnerOccupancy();
  tree.prune();
  impl_->built = false;  // stale now
}

void OccupancyScene::build_distance_field() {
  Impl& m = *impl_;
  const SceneOptions& o = m.options;
  octomap::OcTree& tree = m.tree;
  m.built = true;
  m.distance.clear();
  m.size.setZero();

  // The occupied voxels' key bounds, grown by the saturation distance, within the map box.
  const unsigned depth = tree.getTreeDepth();
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(INT_MAX), hi = Eigen::Vector3i::Constant(INT_MIN);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::OcTreeKey corner = it.getIndexKey();
    const int side = 1 << (depth - it.getDepth());
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], static_cast<int>(corner[k]));
      hi[k] = std::max(hi[k], corner[k] + side - 1);
    }
  }
  if (lo.x() > hi.x()) return;  // nothing occupied: free everywhere
  const int pad = static_cast<int>(std::ceil(o.max_distance_m * m.cells_per_m)) + 1;
  const octomap::OcTreeKey box_lo = tree.coordToKey(octomap::point3d(o.min_corner.x(), o.min_corner.y(), o.min_corner.z()));
  const octomap::OcTreeKey box_hi = tree.coordToKey(octomap::point3d(o.max_corner.x(), o.max_corner.y(), o.max_corner.z()));
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::max(lo[k] - pad, static_cast<int>(box_lo[k]));
    hi[k] = std::min(hi[k] + pad, static_cast<int>(box_hi[k]));
  }
  if ((lo.array() > hi.array()).any()) return;
  const octomap::OcTreeKey key_lo(lo.x(), lo.y(), lo.z()), key_hi(hi.x(), hi.y(), hi.z());

  const float max_distance = static_cast<float>(o.max_distance_m);
  DynamicEDTOctomap edt(max_distance, &tree, tree.keyToCoord(key_lo), tree.keyToCoord(key_hi),
                        /*treatUnknownAsOccupied=*/false);
  edt.update();

  m.size = hi - lo + Eigen::Vector3i::Ones();
  const int key_zero = tree.coordToKey(0.0);
  m.first_cell = lo - Eigen::Vector3i::Constant(key_zero);
  m.distance.resize(static_cast<std::size_t>(m.size.prod()));
  std::size_t i = 0;
  for (int x = lo.x(); x <= hi.x(); ++x)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int z = lo.z(); z <= hi.z(); ++z, ++i)
        m.distance[i] = std::min(edt.getDistance_unsafe(octomap::OcTreeKey(x, y, z)), max_distance);
  // The EDT turned change tracking on for its own incremental updates; it is gone now.
  tree.enableChangeDetection(false);
  tree.resetChangeDetection();
}

double OccupancyScene::distance_m(const Eigen::Vector3d& p) const {
  impl_->require_field();
  return impl_->lookup(p);
}

bool OccupancyScene::collides(const std::vector<Sphere>& spheres, double clearance_m) const {
  impl_->require_field();
  for (const Sphere& s : spheres)
    if (impl_->lookup(s.centre) < s.radius_m + clearance_m) return true;
  return false;
}

OccupancyScene::Occupancy OccupancyScene::occupancy_at(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* node = impl_->tree.search(p.x(), p.y(), p.z());
  if (!node) return Occupancy::unknown;
  return impl_->tree.isNodeOccupied(node) ? Occupancy::occupied : Occupancy::free;
}

std::size_t OccupancyScene::occupied_voxels() const {
  const octomap::OcTree& tree = impl_->tree;
  const unsigned depth = tree.getTreeDepth();
  std::size_t n = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) n += std::size_t{1} << (3 * (depth - it.getDepth()));
  return n;
}

std::vector<Eigen::Vector3d> OccupancyScene::occupied_voxel_centres() const {
  const octomap::OcTree& tree = impl_->tree;
  const unsigned depth = tree.getTreeDepth();
  std::vector<Eigen::Vector3d> centres;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // A pruned node stands for a cube of voxels; list each of them.
    const int side = 1 << (depth - it.getDepth());
    const octomap::OcTreeKey corner = it.getIndexKey();
    for (int dx = 0; dx < side; ++dx)
      for (int dy = 0; dy < side; ++dy)
        for (int dz = 0; dz < side; ++dz) {
          const octomap::point3d c = tree.keyToCoord(octomap::OcTreeKey(corner[0] + dx, corner[1] + dy, corner[2] + dz));
          centres.emplace_back(c.x(), c.y(), c.z());
        }
  }
  return centres;
}

void OccupancyScene::write_binary(const std::string& path) const {
  // writeBinaryConst: the same format as writeBinary, without thresholding our own tree.
  std::ostringstream bytes;
  if (!impl_->tree.writeBinaryConst(bytes)) throw Error(path + ": could not serialise the octree");
  const std::string data = bytes.str();
  write_file_atomically(path, data.data(), data.size());
}

}  // namespace qte::planning
