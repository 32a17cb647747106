// The occupancy scene on a real observation: the simulator's front camera over a
// pick_and_lift scene, the robot filtered out by its own spheres.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <dirent.h>
#include <fstream>
#include <random>
#include <set>
#include <tuple>
#include <sstream>

#include "planning/occupancy_scene.hpp"
#include "sim_step/simulator.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::planning;

namespace {

using test_support::xarm;

// One observation of pick_and_lift (variation 0, seed 3) and what the world knew then.
struct Observation {
  stream::Record obs{"obs"};
  Eigen::Vector3d camera_origin;
  std::vector<Sphere> robot;  // placed at the observed joint state
  std::vector<Eigen::Vector3d> blocks;
  Eigen::Vector3d zone;
  double table_z = 0;
};

const Observation& observation() {
  static const Observation o = [] {
    sim_step::SimulatorOptions options;
    options.cameras = {{"front", {}}};
    options.cameras[0].intrinsics.width = options.cameras[0].intrinsics.height = 128;
    options.render_threads = 1;
    sim_step::Simulator simulator(xarm(), options);
    stream::Record reset("reset");
    reset.set_string("task", "pick_and_lift");
    reset.set_scalar<int32_t>("variation", 0);
    reset.set_scalar<int64_t>("seed", 3);
    Observation out;
    simulator.handle(reset, [&](const stream::Record& obs) { out.obs = obs; });
    const auto extrinsics = out.obs.array<double>("front.extrinsics");  // row-major 4x4
    out.camera_origin << extrinsics[3], extrinsics[7], extrinsics[11];
    robot::JointVector q;
    for (int k = 0; k < robot::kArmJoints; ++k) q[k] = out.obs.array<double>("joint_positions")[k];
    const world::World& world = *simulator.world();
    static const RobotSpheres spheres(xarm());
    spheres.place(q, out.obs.scalar<double>("gripper_opening_m"), world.robot_base_pose(), out.robot);
    for (const char* name : {"target", "distractor1", "distractor2"})
      out.blocks.push_back(world.object_pose(world.object_id(name)).translation());
    out.zone = world.object_pose(world.object_id("success_zone")).translation();
    out.table_z = world.layout().table_height_m;
    return out;
  }();
  return o;
}

OccupancyScene build(const std::vector<Sphere>& robot, const Sphere& held = {}) {
  const Observation& o = observation();
  const auto points = o.obs.array<float>("front.points");
  OccupancyScene scene;
  scene.insert_camera(points.data, static_cast<std::size_t>(points.size() / 3), o.camera_origin, robot, std::vector<Sphere>{held});
  scene.build_distance_field();
  return scene;
}

const OccupancyScene& scene() {
  static const OccupancyScene s = build(observation().robot);
  return s;
}

std::string temp_dir() {
  char tmpl[] = "/tmp/qte_scene_XXXXXX";
  return ::mkdtemp(tmpl);
}

std::vector<std::string> files_in(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  while (dirent* e = ::readdir(d))
    if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") names.push_back(e->d_name);
  ::closedir(d);
  return names;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

constexpr double kResolution = 0.01;
const double kHalfVoxelDiagonal = std::sqrt(3.0) / 2 * kResolution;

}  // namespace

TEST(OccupancyScene, BlocksAreOccupiedAndOpenSpaceIsFree) {
  const Observation& o = observation();
  ASSERT_GT(scene().occupied_voxels(), 1000u);
  for (const Eigen::Vector3d& centre : o.blocks) {
    // The camera sees the faces of a 5 cm block, 2.5 cm from its centre (the inside is
    // unknown), give or take the voxels' half diagonal; 2 cm up, the top face is near.
    EXPECT_LT(scene().distance_m(centre), 0.025 + kHalfVoxelDiagonal) << centre.transpose();
    EXPECT_LE(scene().distance_m(centre + Eigen::Vector3d(0, 0, 0.02)), 0.01 + 1e-6) << centre.transpose();
  }
  // 30 cm above the table, well clear of the success zone (seen, though it does not collide)
  // and of the robot (filtered out).
  const Eigen::Vector3d open(0.5, -0.35, o.table_z + 0.3);
  ASSERT_GT((open - o.zone).norm(), 0.2);
  EXPECT_GE(scene().distance_m(open), 0.1);
  // Outside the mapped box: free at the saturation distance.
  EXPECT_EQ(scene().distance_m(Eigen::Vector3d(5, 5, 5)), SceneOptions{}.max_distance_m);
}

TEST(OccupancyScene, SpheresOnTheTableCollideSpheresInTheAirDoNot) {
  const double z = observation().table_z;
  auto sphere_at = [](double x, double y, double z, double r) { return Sphere{Eigen::Vector3d(x, y, z), r, -1}; };
  EXPECT_TRUE(scene().collides({sphere_at(0.45, 0.3, z, 0.03)}));
  EXPECT_TRUE(scene().collides({sphere_at(0.45, 0.3, z + 0.05, 0.03)}, 0.03));  // with clearance
  EXPECT_FALSE(scene().collides({sphere_at(0.45, 0.3, z + 0.07, 0.03)}));
  EXPECT_FALSE(scene().collides({sphere_at(0.5, -0.35, z + 0.3, 0.05)}));
  // One sphere among many decides.
  EXPECT_TRUE(scene().collides({sphere_at(0.5, -0.35, z + 0.3, 0.05), sphere_at(0.45, 0.3, z, 0.03)}));
}

TEST(OccupancyScene, TheRobotIsFilteredOutOfItsOwnScene) {
  const Observation& o = observation();
  auto voxels_near_robot = [&](const OccupancyScene& s, double within_m) {
    int n = 0;
    for (const Eigen::Vector3d& c : s.occupied_voxel_centres())
      for (const Sphere& sphere : o.robot)
        if ((c - sphere.centre).norm() < sphere.radius_m + within_m) {
          ++n;
          break;
        }
    return n;
  };
  // Unfiltered, the camera sees the arm; filtered, nothing is left within 1 cm of it.
  EXPECT_GT(voxels_near_robot(build({}), 0.01), 50);
  EXPECT_EQ(voxels_near_robot(scene(), 0.01), 0);
  // So the robot at the observed state does not collide with the scene it saw.
  EXPECT_FALSE(scene().collides(o.robot));
}

TEST(OccupancyScene, PointsInsideTheHeldObjectSphereAreDropped) {
  const Observation& o = observation();
  const Sphere held{o.blocks[0], 0.05, -1};
  auto voxels_inside = [&](const OccupancyScene& s) {
    int n = 0;
    for (const Eigen::Vector3d& c : s.occupied_voxel_centres())
      n += (c - held.centre).norm() < held.radius_m - kHalfVoxelDiagonal;
    return n;
  };
  EXPECT_GT(voxels_inside(scene()), 10);
  const OccupancyScene holding = build(o.robot, held);
  EXPECT_EQ(voxels_inside(holding), 0);
  EXPECT_GT(holding.distance_m(held.centre), 0.03);
}

TEST(OccupancyScene, WritesOctomapBinaryFilesAtomicallyAndReproducibly) {
  const std::string dir = temp_dir(), path = dir + "/scene.bt", again = dir + "/again.bt";
  scene().write_binary(path);
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"scene.bt"});  // no temporary left

  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  EXPECT_DOUBLE_EQ(tree.getResolution(), kResolution);
  std::size_t occupied = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) occupied += std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
  EXPECT_EQ(occupied, scene().occupied_voxels());
  // Written back out, the tree read in gives the file again: the same nodes and leaves.
  std::ostringstream round_trip;
  ASSERT_TRUE(tree.writeBinaryConst(round_trip));
  EXPECT_EQ(round_trip.str(), read_bytes(path));
  std::printf("front 128x128: %zu occupied voxels, %zu octree leaves, %zu bytes of .bt\n", occupied,
              tree.getNumLeafNodes(), read_bytes(path).size());

  // The same observation again: the same bytes.
  build(observation().robot).write_binary(again);
  EXPECT_EQ(read_bytes(path), read_bytes(again));
  EXPECT_GT(read_bytes(path).size(), 1000u);
  std::remove(path.c_str());
  std::remove(again.c_str());
  ::rmdir(dir.c_str());
}

TEST(OccupancyScene, QueriesNeedTheDistanceField) {
  OccupancyScene s;
  EXPECT_THROW(s.distance_m(Eigen::Vector3d(0, 0, 1)), Error);
  s.build_distance_field();
  EXPECT_EQ(s.distance_m(Eigen::Vector3d(0, 0, 1)), SceneOptions{}.max_distance_m);  // empty: all free
  EXPECT_THROW(OccupancyScene(SceneOptions{0.0}), Error);
}

namespace {

// The scene of one pick_and_lift observation seen by `cameras`, and the traced map's occupied
// voxel centres as cell indices.
struct SeenScene {
  OccupancyScene scene;
  std::vector<Eigen::Vector3i> occupied_cells;
};

SeenScene seen_by(const std::vector<std::string>& cameras) {
  sim_step::SimulatorOptions options;
  options.cameras.clear();
  for (const auto& name : cameras) {
    options.cameras.push_back({name, {}});
    options.cameras.back().intrinsics.width = options.cameras.back().intrinsics.height = 96;
  }
  sim_step::Simulator simulator(xarm(), options);
  stream::Record reset("reset"), obs("obs");
  reset.set_string("task", "pick_and_lift");
  reset.set_scalar<int32_t>("variation", 0);
  reset.set_scalar<int64_t>("seed", 5);
  simulator.handle(reset, [&](const stream::Record& o) { obs = o; });
  SeenScene seen;
  std::vector<Sphere> robot;
  static const RobotSpheres spheres(xarm());
  spheres.place(simulator.world()->joint_positions(), simulator.world()->finger_opening_m(),
                simulator.world()->robot_base_pose(), robot);
  for (const auto& name : cameras) {
    const auto points = obs.array<float>(name + ".points");
    const auto e = obs.array<double>(name + ".extrinsics");
    seen.scene.insert_camera(points.data, static_cast<std::size_t>(points.size() / 3),
                             Eigen::Vector3d(e[3], e[7], e[11]), robot, {});
  }
  seen.scene.build_distance_field();
  for (const Eigen::Vector3d& c : seen.scene.occupied_voxel_centres())
    seen.occupied_cells.push_back((c / kResolution).array().floor().cast<int>());
  return seen;
}

}  // namespace

// Planning reads the occupied voxels off the endpoints, without tracing rays: for up to three
// cameras they are exactly the traced map's, and the field is the exact distance to them.
TEST(OccupancyScene, TheDistanceFieldIsExactToTheTracedMapsOccupiedVoxels) {
  for (const std::vector<std::string>& cameras :
       {std::vector<std::string>{"front"}, {"front", "wrist"}, {"front", "wrist", "overhead"}}) {
    const SeenScene seen = seen_by(cameras);
    ASSERT_GT(seen.occupied_cells.size(), 500u);
    Eigen::Vector3i lo = seen.occupied_cells[0], hi = lo;
    for (const auto& c : seen.occupied_cells) lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
    // Every cell of their bounding box (and one beyond): distance 0 exactly on the traced
    // occupied voxels.
    std::set<std::tuple<int, int, int>> traced;
    for (const auto& c : seen.occupied_cells) traced.emplace(c.x(), c.y(), c.z());
    std::size_t zero = 0, mismatched = 0;
    for (int x = lo.x() - 1; x <= hi.x() + 1; ++x)
      for (int y = lo.y() - 1; y <= hi.y() + 1; ++y)
        for (int z = lo.z() - 1; z <= hi.z() + 1; ++z) {
          const bool field_zero = seen.scene.distance_m((Eigen::Vector3d(x, y, z).array() + 0.5) * kResolution) == 0;
          zero += field_zero;
          mismatched += field_zero != traced.count({x, y, z});
        }
    EXPECT_EQ(mismatched, 0u) << cameras.size() << " cameras";
    EXPECT_EQ(zero, traced.size());
    // Elsewhere, the Euclidean distance between voxel centres to the nearest of them.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector3d p = (lo.cast<double>().array() +
                                 (hi - lo).cast<double>().array() * Eigen::Array3d(u(rng), u(rng), u(rng)) + 0.5) *
                                kResolution;
      const Eigen::Vector3d centre = ((p / kResolution).array().floor() + 0.5) * kResolution;
      double nearest = SceneOptions{}.max_distance_m;
      for (const auto& c : seen.occupied_cells)
        nearest = std::min(nearest, (centre - (c.cast<double>().array() + 0.5).matrix() * kResolution).norm());
      EXPECT_NEAR(seen.scene.distance_m(p), nearest, 1e-6) << p.transpose();
    }
  }
}

// Four cameras: a voxel one camera hit and three saw through is free in the map (0.85 - 3 x
// 0.41 < 0), and so in the field; with two of them seeing through it stays occupied.
TEST(OccupancyScene, FromFourCamerasOnTheTracedMapDecides) {
  const Eigen::Vector3d voxel(0.305, 0.005, 1.005), behind(0.105, 0.005, 1.005);
  for (int through : {2, 3}) {
    OccupancyScene s;
    const float hit[] = {float(voxel.x()), float(voxel.y()), float(voxel.z())};
    const float far[] = {float(behind.x()), float(behind.y()), float(behind.z())};
    s.insert_camera(hit, 1, Eigen::Vector3d(-0.2, 0.005, 1.005), {}, {});
    for (int i = 0; i < through; ++i) s.insert_camera(far, 1, Eigen::Vector3d(0.605, 0.005, 1.005), {}, {});
    s.build_distance_field();
    const bool occupied = through == 2;
    EXPECT_EQ(s.occupancy_at(voxel) == OccupancyScene::Occupancy::occupied, occupied) << through;
    // Free, it is as far as the nearest hit behind it: 20 cm.
    EXPECT_NEAR(s.distance_m(voxel), occupied ? 0.0 : 0.2, 1e-6) << through;
    EXPECT_EQ(s.distance_m(behind), 0.0);
  }
}
