#include "planning/occupancy_scene.hpp"

#include <octomap/OcTree.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <climits>
#include <cmath>
#include <sstream>

#include "common/atomic_file.hpp"
#include "common/error.hpp"
#include "planning/distance_transform.hpp"

namespace qte::planning {

// Cameras up to which the endpoints alone give the map's occupied voxels (see occupied_keys).
constexpr std::size_t kCamerasWithoutRays = 3;

struct OccupancyScene::Impl {
  SceneOptions options;
  // The OctoMap: every camera's points inserted as rays. Tracing the rays is most of a
  // scene's cost and only free space needs them, so the map is built when something asks
  // about free space (occupancy_at, write_binary), not for planning.
  mutable octomap::OcTree tree;
  mutable bool tree_current = true;
  struct Scan {
    octomap::Pointcloud points;  // filtered, world frame
    octomap::point3d origin;
  };
  std::vector<Scan> scans;
  // The map's occupied voxels as octree keys (repeats included: one per point that hit).
  std::vector<octomap::OcTreeKey> endpoint_keys;

  // The distance field, one flat array (z fastest): a query is a few multiplications and one
  // load. It covers the occupied voxels' bounding box grown by max_distance_m (within the
  // map box); everywhere else is at least that far from anything.
  bool built = false;
  std::vector<float> distance;
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  Eigen::Vector3i first_cell = Eigen::Vector3i::Zero();  // cell index of the field's first cell
  double cells_per_m = 0;

  explicit Impl(const SceneOptions& o) : options(o), tree(o.resolution_m), cells_per_m(1.0 / o.resolution_m) {
    // Rays are traced only inside the box: free space outside it is never asked about.
    octomap::point3d lo(o.min_corner.x(), o.min_corner.y(), o.min_corner.z());
    octomap::point3d hi(o.max_corner.x(), o.max_corner.y(), o.max_corner.z());
    tree.setBBXMin(lo);
    tree.setBBXMax(hi);
    tree.useBBXLimit(true);
  }

  const octomap::OcTree& map() const {
    if (!tree_current) {
      tree.clear();
      // discretize: one ray per endpoint voxel rather than per point (a quarter faster).
      // lazy_eval, then inner nodes and pruning once: the same tree (the same .bt bytes) as
      // updating them at every voxel, in about three quarters of the time.
      for (const Scan& scan : scans)
        tree.insertPointCloud(scan.points, scan.origin, -1.0, /*lazy_eval=*/true, /*discretize=*/true);
      tree.updateInnerOccupancy();
      tree.prune();
      tree_current = true;
    }
    return tree;
  }

  // The map's occupied voxels without tracing a ray. Within one camera OctoMap lets a hit win
  // over a miss, so a voxel's log-odds after n cameras is 0.85 h - 0.41 m for h hits and m
  // misses, h + m <= n: once hit it stays occupied (>= 0) while m <= 2, i.e. for up to three
  // cameras. More cameras: read the traced map. (test_occupancy_scene compares the two.)
  std::vector<octomap::OcTreeKey> occupied_keys() const {
    return scans.size() <= kCamerasWithoutRays ? endpoint_keys : traced_occupied_keys();
  }

  // The traced map's occupied voxels, each of them (a pruned node stands for a cube of them).
  std::vector<octomap::OcTreeKey> traced_occupied_keys() const {
    std::vector<octomap::OcTreeKey> keys;
    const octomap::OcTree& t = map();
    const unsigned depth = t.getTreeDepth();
    for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
      if (!t.isNodeOccupied(*it)) continue;
      const int side = 1 << (depth - it.getDepth());
      const octomap::OcTreeKey corner = it.getIndexKey();
      for (int dx = 0; dx < side; ++dx)
        for (int dy = 0; dy < side; ++dy)
          for (int dz = 0; dz < side; ++dz) keys.emplace_back(corner[0] + dx, corner[1] + dy, corner[2] + dz);
    }
    return keys;
  }

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
  // The endpoints' voxels, as OctoMap's discretised insertion takes them: the voxel of each
  // point, kept when its centre lies in the box.
  Impl& m = *impl_;
  for (const octomap::point3d& p : cloud) {
    const octomap::OcTreeKey key = m.tree.coordToKey(p);
    if (m.tree.inBBX(m.tree.keyToCoord(key))) m.endpoint_keys.push_back(key);
  }
  m.scans.push_back({std::move(cloud), octomap::point3d(sensor_origin.x(), sensor_origin.y(), sensor_origin.z())});
  m.tree_current = false;
  m.built = false;  // stale now
}

void OccupancyScene::build_distance_field() {
  Impl& m = *impl_;
  const SceneOptions& o = m.options;
  m.built = true;
  m.distance.clear();
  m.size.setZero();
  const std::vector<octomap::OcTreeKey> occupied = m.occupied_keys();
  if (occupied.empty()) return;  // nothing occupied: free everywhere

  // The occupied voxels' key bounds, grown by the saturation distance, within the map box.
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(INT_MAX), hi = Eigen::Vector3i::Constant(INT_MIN);
  for (const octomap::OcTreeKey& key : occupied)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], static_cast<int>(key[k]));
      hi[k] = std::max(hi[k], static_cast<int>(key[k]));
    }
  const int pad = static_cast<int>(std::ceil(o.max_distance_m * m.cells_per_m)) + 1;
  const octomap::OcTreeKey box_lo = m.tree.coordToKey(octomap::point3d(o.min_corner.x(), o.min_corner.y(), o.min_corner.z()));
  const octomap::OcTreeKey box_hi = m.tree.coordToKey(octomap::point3d(o.max_corner.x(), o.max_corner.y(), o.max_corner.z()));
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::max(lo[k] - pad, static_cast<int>(box_lo[k]));
    hi[k] = std::min(hi[k] + pad, static_cast<int>(box_hi[k]));
  }

  m.size = hi - lo + Eigen::Vector3i::Ones();
  m.first_cell = lo - Eigen::Vector3i::Constant(m.tree.coordToKey(0.0));
  std::vector<uint8_t> grid(static_cast<std::size_t>(m.size.prod()), 0);
  for (const octomap::OcTreeKey& key : occupied)
    grid[(static_cast<std::size_t>(key[0] - lo.x()) * m.size.y() + (key[1] - lo.y())) * m.size.z() + (key[2] - lo.z())] = 1;
  m.distance = squared_distance_transform(grid, m.size, o.threads);
  const float max_distance = static_cast<float>(o.max_distance_m), metres_per_cell = static_cast<float>(o.resolution_m);
  for (float& d : m.distance) d = std::min(std::sqrt(d) * metres_per_cell, max_distance);
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
  const octomap::OcTreeNode* node = impl_->map().search(p.x(), p.y(), p.z());
  if (!node) return Occupancy::unknown;
  return impl_->map().isNodeOccupied(node) ? Occupancy::occupied : Occupancy::free;
}

std::size_t OccupancyScene::occupied_voxels() const { return impl_->traced_occupied_keys().size(); }

std::vector<Eigen::Vector3d> OccupancyScene::occupied_voxel_centres() const {
  std::vector<Eigen::Vector3d> centres;
  for (const octomap::OcTreeKey& key : impl_->traced_occupied_keys()) {
    const octomap::point3d c = impl_->tree.keyToCoord(key);
    centres.emplace_back(c.x(), c.y(), c.z());
  }
  return centres;
}

void OccupancyScene::write_binary(const std::string& path) const {
  // writeBinaryConst: the same format as writeBinary, without thresholding our own tree.
  const octomap::OcTree& map = impl_->map();
  std::ostringstream bytes;
  bool written = false;
  {
    // Debian's OctoMap reports " done." on standard error after serialising; what a program
    // prints there is its own one-line errors.
    std::fflush(stderr);
    std::cerr.flush();
    const int saved = ::dup(STDERR_FILENO), null = ::open("/dev/null", O_WRONLY);
    if (saved >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    written = map.writeBinaryConst(bytes);
    std::fflush(stderr);
    std::cerr.flush();
    if (saved >= 0) ::dup2(saved, STDERR_FILENO), ::close(saved);
    if (null >= 0) ::close(null);
  }
  if (!written) throw Error(path + ": could not serialise the octree");
  const std::string data = bytes.str();
  write_file_atomically(path, data.data(), data.size());
}

}  // namespace qte::planning
