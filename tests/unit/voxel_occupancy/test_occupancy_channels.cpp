#include <gtest/gtest.h>

#include "sim_step/simulator.hpp"
#include "voxel_occupancy/occupancy_channels.hpp"

using namespace qte;

TEST(OccupancyChannels, FreeInViewUnknownUnderTheTable) {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  sim_step::SimulatorOptions options;
  options.render_threads = 1;
  sim_step::Simulator sim(robot, options);
  stream::Record obs("obs");
  sim.handle(sim_step::plan_reset({"reach_target", 0, 1, 2}, 0), [&](const stream::Record& r) { obs = r; });
  const voxel_occupancy::ObservedSpace space(obs);
  voxels::GridBounds bounds;  // the scene cube, 16^3
  std::vector<float> channels(16 * 16 * 16 * voxel_occupancy::kOccupancyChannels);
  space.channels(bounds, channels.data());
  auto at = [&](const Eigen::Vector3d& p, int channel) {
    const Eigen::Vector3i i = bounds.index_of(p);
    return channels[((i.x() * 16 + i.y()) * 16 + i.z()) * voxel_occupancy::kOccupancyChannels + channel];
  };
  const double table = sim.world()->layout().table_height_m;
  EXPECT_EQ(at({0.3, 0.0, table + 0.45}, 0), 1.0f);   // in front of the camera, above the table: free
  EXPECT_EQ(at({0.3, 0.0, table + 0.45}, 1), 0.0f);
  EXPECT_EQ(at({0.2, 0.0, table - 0.1}, 1), 1.0f);    // under the table top: never seen
  EXPECT_EQ(at({0.2, 0.0, table - 0.1}, 0), 0.0f);
  int free = 0, unknown = 0;
  for (std::size_t i = 0; i < channels.size(); i += 2) free += channels[i] > 0, unknown += channels[i + 1] > 0;
  EXPECT_GT(free, 500);
  EXPECT_GT(unknown, 500);
}
