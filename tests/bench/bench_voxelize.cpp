// Prints voxelization speed: a 128x128 cloud into 16^3 (the figure to compare with PyTorch's
// scatter-mean in torch_voxelize.py), and K crops of one cloud in one pass.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "voxels/voxel_grid.hpp"

using namespace qte::voxels;
using Clock = std::chrono::steady_clock;

int main() {
  const std::size_t n = 128 * 128;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> xyz(3 * n);
  std::vector<uint8_t> rgb(3 * n);
  for (auto& c : xyz) c = u(rng);
  for (auto& c : rgb) c = static_cast<uint8_t>(rng());
  const PointCloud cloud{xyz.data(), rgb.data(), n};
  GridBounds bounds;
  bounds.min_corner.setZero();
  bounds.size_m = 1.0;
  for (int k : {1, 10}) {
    std::vector<GridBounds> grids;
    for (int i = 0; i < k; ++i) grids.push_back(k == 1 ? bounds : GridBounds::around({0.1 + 0.08 * i, 0.5, 0.5}, 0.15, 16));
    std::vector<float> out(grids.size() * 16 * 16 * 16 * kChannels);
    std::vector<double> times;
    for (int rep = 0; rep < 200; ++rep) {
      const auto t0 = Clock::now();
      voxelize_many(cloud, grids, out.data());
      times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    std::sort(times.begin(), times.end());
    const double t = times[times.size() / 2];
    std::printf("voxelize 128x128 cloud -> %d grid%s of 16^3, one thread: %.3f ms (%.0f Mpoints/s)\n", k,
                k > 1 ? "s" : "", t * 1e3, n / t / 1e6);
  }
}
