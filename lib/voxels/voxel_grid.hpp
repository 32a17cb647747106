// Coarse-to-fine voxel grids (C2F-ARM): depth 0 covers the scene bounds; depth d > 0 covers
// centre +- offset[d-1] around the voxel chosen at depth d-1. Index <-> coordinate conversions
// live here and only here: a voxel's coordinate is always its centre.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace qte::voxels {

// An axis-aligned cube split into voxels^3 voxels.
struct GridBounds {
  Eigen::Vector3d min_corner = Eigen::Vector3d(-0.3, -0.5, 0.6);
  double size_m = 1.0;
  int voxels = 16;

  double voxel_size_m() const { return size_m / voxels; }
  Eigen::Vector3d max_corner() const { return min_corner + Eigen::Vector3d::Constant(size_m); }
  // The voxel holding `point` (may lie outside 0..voxels-1 for points outside the cube).
  Eigen::Vector3i index_of(const Eigen::Vector3d& point) const;
  Eigen::Vector3d centre_of(const Eigen::Vector3i& index) const;
  bool contains(const Eigen::Vector3i& index) const;
  // The cube of half-size `half_extent_m` centred on `centre`.
  static GridBounds around(const Eigen::Vector3d& centre, double half_extent_m, int voxels);
  // From "X,Y,Z,S" (minimum corner and edge length, metres), as the tools' --bounds give it.
  // Throws Error on anything else.
  static GridBounds parse(const std::string& text, int voxels);
};

// A voxel's place in a grid's flat array (index order x, y, z: z varies fastest), and back.
inline int flat_index(const Eigen::Vector3i& index, int voxels) {
  return (index.x() * voxels + index.y()) * voxels + index.z();
}
inline Eigen::Vector3i index_from_flat(int flat, int voxels) {
  return Eigen::Vector3i(flat / (voxels * voxels), (flat / voxels) % voxels, flat % voxels);
}

// The hierarchy: scene bounds at depth 0, `depths` levels of `voxels`^3, and one offset (half
// edge) per depth below 0: published 0.15 m for the 2-depth C2F-ARM.
struct CoarseToFine {
  GridBounds scene;
  int depths = 2;
  std::vector<double> offsets_m = {0.15};  // offsets_m[d - 1] is depth d's half edge

  int voxels() const { return scene.voxels; }
  double offset_at(int depth) const { return offsets_m.at(depth - 1); }
  // Throws Error unless there is one positive offset per depth below 0.
  void validate() const;
  // Bounds at `depth` given the centre chosen at depth-1 (ignored at depth 0).
  GridBounds bounds_at(int depth, const Eigen::Vector3d& previous_centre) const;
  // The hierarchy below `depth`: depth+1's grid around `centre` as its scene, the deeper offsets.
  CoarseToFine below(int depth, const Eigen::Vector3d& centre) const;
  // "0.15" or "0.15,0.05" (the tools' --offset), checked against `depths`.
  static std::vector<double> parse_offsets(const std::string& text, int depths);
  // The voxel index at every depth leading to `target` (each depth centred on the previous
  // depth's voxel centre, optionally shifted by `centre_shifts[d]` for crop augmentation).
  std::vector<Eigen::Vector3i> indices_of(const Eigen::Vector3d& target,
                                          const std::vector<Eigen::Vector3d>& centre_shifts = {}) const;
};

// Per-voxel channels, channels last: mean x, y, z of the voxel's points (world frame, m);
// mean r, g, b scaled to [-1, 1]; the voxel's index / voxels for x, y, z; occupancy (1 when
// the voxel holds a point). Empty voxels have zeros except their index channels.
constexpr int kChannels = 10;

// One point cloud: `count` xyz float triples (NaN = no point) with RGB bytes per point.
struct PointCloud {
  const float* xyz = nullptr;
  const uint8_t* rgb = nullptr;
  std::size_t count = 0;
};

// Fills `out` (voxels^3 * kChannels floats, index order x, y, z, channel) for one grid.
void voxelize(const PointCloud& cloud, const GridBounds& bounds, float* out);

// Several grids of the same cloud in one pass over its points (tree expansion's K branches).
// `out` holds grids.size() consecutive grids.
void voxelize_many(const PointCloud& cloud, const std::vector<GridBounds>& grids, float* out);

}  // namespace qte::voxels
