// Prints what each point-cloud filter (lib/point_clouds: crop, statistical outlier removal,
// voxel-grid downsampling, all three) costs per observation, beside what voxelizing that
// observation costs, for sim-step's pick_and_lift scene at 128x128 and 256x256. The filters are
// off by default; these are the figures to weigh before turning them on for a real camera.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "point_clouds/cloud_filters.hpp"
#include "sim_step/simulator.hpp"
#include "voxel_occupancy/voxels_record.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

template <class F>
static double median_ms(F&& f, int reps) {
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

int main() {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  for (const int side : {128, 256}) {
    sim_step::SimulatorOptions options = sim_step::options_for_cameras({"front"}, side, side);
    options.render_threads = 1;
    sim_step::Simulator sim(robot, options);
    stream::Record obs("obs");
    sim.handle(sim_step::plan_reset({"pick_and_lift", 0, 1, 2}, 0), [&](const stream::Record& r) { obs = r; });
    const std::size_t points = voxels::observation_cloud(obs).view().count;
    voxel_occupancy::VoxelsRecordOptions grid;
    const double voxelize = median_ms([&] { (void)voxel_occupancy::voxels_of(obs, grid); }, 30);
    std::printf("%dx%d front camera, %zu pixels: voxelize (16^3, no filter) %.2f ms\n", side, side, points, voxelize);
    point_clouds::CloudFilters crop, outliers, downsample, all;
    crop.crop = all.crop = Eigen::AlignedBox3f(Eigen::Vector3f(-0.3f, -0.5f, 0.6f), Eigen::Vector3f(0.7f, 0.5f, 1.6f));
    outliers.outlier_neighbours = all.outlier_neighbours = 20;
    outliers.outlier_stddevs = all.outlier_stddevs = 2.0;
    downsample.downsample_m = all.downsample_m = 0.005;
    const std::pair<const char*, const point_clouds::CloudFilters*> cases[] = {
        {"--crop (scene bounds)", &crop}, {"--outliers 20,2", &outliers}, {"--downsample 0.005", &downsample}, {"all three", &all}};
    for (const auto& [name, filters] : cases) {
      std::size_t kept = 0;
      const double ms = median_ms([&] { kept = voxels::observation_cloud(point_clouds::filter_observation(obs, *filters)).view().count; }, 15);
      std::printf("  %-22s %7.2f ms per observation (%.1fx voxelize), %zu points kept\n", name, ms, ms / voxelize, kept);
    }
  }
}
