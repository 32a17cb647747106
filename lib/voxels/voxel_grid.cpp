#include "voxels/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "common/error.hpp"
#include "common/number_list.hpp"

namespace qte::voxels {
namespace {

// "A,B,C" as numbers; throws Error naming `what` and the item that is not one.
std::vector<double> parse_numbers(const std::string& text, const char* what) {
  std::vector<double> values;
  std::string bad;
  if (!parse_number_list(text, values, bad))
    throw Error(std::string(what) + " '" + text + "': '" + bad + "' is not a finite number");
  return values;
}

}  // namespace

Eigen::Vector3i GridBounds::index_of(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d scaled = (point - min_corner) / voxel_size_m();
  return Eigen::Vector3i(static_cast<int>(std::floor(scaled.x())), static_cast<int>(std::floor(scaled.y())),
                         static_cast<int>(std::floor(scaled.z())));
}

Eigen::Vector3d GridBounds::centre_of(const Eigen::Vector3i& index) const {
  return min_corner + (index.cast<double>() + Eigen::Vector3d::Constant(0.5)) * voxel_size_m();
}

bool GridBounds::contains(const Eigen::Vector3i& index) const {
  return (index.array() >= 0).all() && (index.array() < voxels).all();
}

GridBounds GridBounds::around(const Eigen::Vector3d& centre, double half_extent_m, int voxels) {
  GridBounds b;
  b.min_corner = centre - Eigen::Vector3d::Constant(half_extent_m);
  b.size_m = 2 * half_extent_m;
  b.voxels = voxels;
  return b;
}

GridBounds GridBounds::parse(const std::string& text, int voxels) {
  const std::vector<double> v = parse_numbers(text, "bounds");
  if (v.size() != 4 || !(v[3] > 0) || !std::isfinite(v[0] + v[1] + v[2] + v[3]))
    throw Error("bounds '" + text + "': expected X,Y,Z,S (minimum corner and a positive edge length, metres)");
  if (voxels < 2) throw Error("a grid needs at least 2 voxels per side");
  GridBounds b;
  b.min_corner = Eigen::Vector3d(v[0], v[1], v[2]);
  b.size_m = v[3];
  b.voxels = voxels;
  return b;
}

void CoarseToFine::validate() const {
  if (static_cast<int>(offsets_m.size()) != std::max(depths - 1, 0) && !(depths == 1 && offsets_m.size() == 1))
    throw Error("the hierarchy has " + std::to_string(depths) + " depths and " + std::to_string(offsets_m.size()) +
                " offsets: give one per depth below 0 (--offset 0.15,0.05 for 3 depths)");
  for (double o : offsets_m)
    if (!(o > 0) || !std::isfinite(o)) throw Error("offsets must be positive (metres)");
}

GridBounds CoarseToFine::bounds_at(int depth, const Eigen::Vector3d& previous_centre) const {
  if (depth == 0) return scene;
  return GridBounds::around(previous_centre, offset_at(depth), scene.voxels);
}

CoarseToFine CoarseToFine::below(int depth, const Eigen::Vector3d& centre) const {
  CoarseToFine h;
  h.scene = bounds_at(depth + 1, centre);
  h.depths = depths - depth - 1;
  h.offsets_m.assign(offsets_m.begin() + std::min<std::size_t>(depth + 1, offsets_m.size()), offsets_m.end());
  return h;
}

std::vector<double> CoarseToFine::parse_offsets(const std::string& text, int depths) {
  const std::vector<double> offsets = parse_numbers(text, "offset");
  CoarseToFine check;
  check.depths = depths;
  check.offsets_m = offsets;
  check.validate();
  return offsets;
}

std::vector<Eigen::Vector3i> CoarseToFine::indices_of(const Eigen::Vector3d& target,
                                                      const std::vector<Eigen::Vector3d>& centre_shifts) const {
  std::vector<Eigen::Vector3i> indices;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int d = 0; d < depths; ++d) {
    if (d > 0 && d < static_cast<int>(centre_shifts.size())) centre += centre_shifts[d];
    const GridBounds bounds = bounds_at(d, centre);
    Eigen::Vector3i index = bounds.index_of(target);
    index = index.cwiseMax(0).cwiseMin(bounds.voxels - 1);  // on the far face: the last voxel
    indices.push_back(index);
    centre = bounds.centre_of(index);
  }
  return indices;
}

namespace {

// Sums per voxel: x, y, z, r, g, b, count.
constexpr int kSums = 7;

// One pass over the points, each tested against every grid (the K branches of a tree
// expansion share one read of the cloud).
void accumulate(const PointCloud& cloud, const std::vector<GridBounds>& grids, float* sums) {
  const int v = grids[0].voxels;
  const std::size_t grid_sums = static_cast<std::size_t>(v) * v * v * kSums;
  struct Frame {
    float lo[3];
    float inv;
  };
  std::vector<Frame> frames;
  for (const auto& b : grids)
    frames.push_back({{static_cast<float>(b.min_corner.x()), static_cast<float>(b.min_corner.y()),
                       static_cast<float>(b.min_corner.z())},
                      static_cast<float>(1.0 / b.voxel_size_m())});
  const float vf = static_cast<float>(v);
  // The box around every grid: most of a scene's points lie outside a tree's finer grids, and
  // one test skips them for all the grids at once (the sums are unchanged: the same points
  // reach each grid in the same order). Widened by a voxel so that rounding never drops a point
  // the per-grid test below would keep.
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const auto& b : grids)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], static_cast<float>(b.min_corner[a] - b.voxel_size_m()));
      hi[a] = std::max(hi[a], static_cast<float>(b.min_corner[a] + b.size_m + b.voxel_size_m()));
    }
  for (std::size_t i = 0; i < cloud.count; ++i) {
    const float* p = cloud.xyz + 3 * i;
    if (!(p[0] >= lo[0] && p[1] >= lo[1] && p[2] >= lo[2] && p[0] <= hi[0] && p[1] <= hi[1] && p[2] <= hi[2]))
      continue;  // outside every grid, or NaN
    const uint8_t* c = cloud.rgb + 3 * i;
    for (std::size_t g = 0; g < frames.size(); ++g) {
      const Frame& f = frames[g];
      const float fx = (p[0] - f.lo[0]) * f.inv, fy = (p[1] - f.lo[1]) * f.inv, fz = (p[2] - f.lo[2]) * f.inv;
      // NaN fails every comparison, so it is skipped with the out-of-bounds points.
      if (!(fx >= 0 && fy >= 0 && fz >= 0 && fx < vf && fy < vf && fz < vf)) continue;
      const int flat = (static_cast<int>(fx) * v + static_cast<int>(fy)) * v + static_cast<int>(fz);
      float* s = sums + g * grid_sums + kSums * flat;
      s[0] += p[0];
      s[1] += p[1];
      s[2] += p[2];
      s[3] += c[0];
      s[4] += c[1];
      s[5] += c[2];
      s[6] += 1;
    }
  }
}

void finish(const float* sums, int v, float* out) {
  const float inv_v = 1.0f / v;
  for (int x = 0, flat = 0; x < v; ++x)
    for (int y = 0; y < v; ++y)
      for (int z = 0; z < v; ++z, ++flat) {
        const float* s = sums + kSums * flat;
        float* o = out + kChannels * flat;
        const float n = s[6];
        if (n > 0) {
          const float inv_n = 1.0f / n;
          o[0] = s[0] * inv_n;
          o[1] = s[1] * inv_n;
          o[2] = s[2] * inv_n;
          // RGB bytes to [-1, 1]: c / 255 * 2 - 1.
          o[3] = s[3] * inv_n * (2.0f / 255.0f) - 1.0f;
          o[4] = s[4] * inv_n * (2.0f / 255.0f) - 1.0f;
          o[5] = s[5] * inv_n * (2.0f / 255.0f) - 1.0f;
          o[9] = 1.0f;
        } else {
          o[0] = o[1] = o[2] = o[3] = o[4] = o[5] = o[9] = 0.0f;
        }
        o[6] = x * inv_v;
        o[7] = y * inv_v;
        o[8] = z * inv_v;
      }
}

}  // namespace

void voxelize(const PointCloud& cloud, const GridBounds& bounds, float* out) {
  voxelize_many(cloud, {bounds}, out);
}

void voxelize_many(const PointCloud& cloud, const std::vector<GridBounds>& grids, float* out) {
  if (grids.empty()) return;
  const int v = grids[0].voxels;
  for (const auto& g : grids)
    if (g.voxels != v || v < 1 || v > 512) throw Error("voxelize_many: every grid needs the same 1-512 voxels per side");
  const std::size_t cells = static_cast<std::size_t>(v) * v * v;
  thread_local std::vector<float> sums;
  sums.assign(cells * kSums * grids.size(), 0.0f);
  accumulate(cloud, grids, sums.data());
  for (std::size_t g = 0; g < grids.size(); ++g)
    finish(sums.data() + g * cells * kSums, v, out + g * cells * kChannels);
}

}  // namespace qte::voxels
