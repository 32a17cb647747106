// Prints occupancy scene figures on a pick_and_lift observation, per front camera frame
// (128x128 and 256x256): the planning scene (occupied voxels from the endpoints and the
// distance transform, 1 and 2 threads), the traced OctoMap, the former scene (traced map and
// dynamicEDT3D) side by side with how far its field is from today's, plain OctoMap with and
// without discretize and the box limit; then distance queries and robot sphere-set checks per
// second.
// Medians of several runs.
#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>

#include "planning/occupancy_scene.hpp"
#include "sim_step/simulator.hpp"

using namespace qte;
using namespace qte::planning;
using Clock = std::chrono::steady_clock;

namespace {

// Median seconds of `runs` calls of `f`.
double median_s(int runs, const std::function<void()>& f) {
  std::vector<double> s;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = Clock::now();
    f();
    s.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::nth_element(s.begin(), s.begin() + runs / 2, s.end());
  return s[runs / 2];
}

struct Frame {
  std::vector<float> points;
  Eigen::Vector3d origin;
  std::vector<Sphere> robot;
};

Frame observe(const robot::RobotModel& robot, const RobotSpheres& spheres, int size) {
  sim_step::SimulatorOptions options;
  options.cameras[0].intrinsics.width = options.cameras[0].intrinsics.height = size;
  sim_step::Simulator simulator(robot, options);
  Frame frame;
  stream::Record reset("reset");
  reset.set_string("task", "pick_and_lift");
  reset.set_scalar<int32_t>("variation", 0);
  reset.set_scalar<int64_t>("seed", 3);
  simulator.handle(reset, [&](const stream::Record& obs) {
    const auto points = obs.array<float>("front.points");
    frame.points.assign(points.begin(), points.end());
    const auto extrinsics = obs.array<double>("front.extrinsics");
    frame.origin << extrinsics[3], extrinsics[7], extrinsics[11];
  });
  spheres.place(simulator.world()->joint_positions(), simulator.world()->finger_opening_m(),
                simulator.world()->robot_base_pose(), frame.robot);
  return frame;
}

// Plain OctoMap on the same points (NaN and out-of-box dropped), to compare its options.
double plain_octomap_ms(const Frame& frame, bool discretize, bool lazy_eval, bool box_limit, std::size_t* leaves) {
  const SceneOptions o;
  octomap::Pointcloud cloud;
  for (std::size_t i = 0; i + 2 < frame.points.size(); i += 3) {
    const Eigen::Vector3d p(frame.points[i], frame.points[i + 1], frame.points[i + 2]);
    if (p.allFinite() && (p.array() >= o.min_corner.array()).all() && (p.array() <= o.max_corner.array()).all())
      cloud.push_back(p.x(), p.y(), p.z());
  }
  const octomap::point3d origin(frame.origin.x(), frame.origin.y(), frame.origin.z());
  return 1e3 * median_s(5, [&] {
    octomap::OcTree tree(o.resolution_m);
    if (box_limit) {
      octomap::point3d lo(o.min_corner.x(), o.min_corner.y(), o.min_corner.z());
      octomap::point3d hi(o.max_corner.x(), o.max_corner.y(), o.max_corner.z());
      tree.setBBXMin(lo);
      tree.setBBXMax(hi);
      tree.useBBXLimit(true);
    }
    tree.insertPointCloud(cloud, origin, -1.0, lazy_eval, discretize);
    if (lazy_eval) {
      tree.updateInnerOccupancy();
      tree.prune();
    }
    *leaves = tree.getNumLeafNodes();
  });
}

// The former scene, measured beside today's as the peer: the traced OctoMap and
// dynamicEDT3D's field over its occupied voxels' box grown by the saturation distance.
// Returns its milliseconds; counts the cells where its field differs from `scene`'s.
double former_scene_ms(const Frame& frame, const OccupancyScene& scene, std::size_t* cells, std::size_t* differing,
                       double* largest_difference) {
  const SceneOptions o;
  octomap::OcTree tree(o.resolution_m);
  std::unique_ptr<DynamicEDTOctomap> edt;
  octomap::OcTreeKey lo, hi;
  const double ms = 1e3 * median_s(3, [&] {
    OccupancyScene traced;
    traced.insert_camera(frame.points.data(), frame.points.size() / 3, frame.origin, frame.robot, {});
    traced.occupancy_at(frame.origin);  // traces the rays
    tree.clear();
    octomap::point3d bmin(o.min_corner.x(), o.min_corner.y(), o.min_corner.z());
    octomap::point3d bmax(o.max_corner.x(), o.max_corner.y(), o.max_corner.z());
    const std::vector<Eigen::Vector3d> occupied = traced.occupied_voxel_centres();
    for (const Eigen::Vector3d& c : occupied) tree.updateNode(c.x(), c.y(), c.z(), true, true);
    tree.updateInnerOccupancy();
    const int pad = static_cast<int>(std::ceil(o.max_distance_m / o.resolution_m)) + 1;
    lo = hi = tree.coordToKey(occupied.front().x(), occupied.front().y(), occupied.front().z());
    for (const Eigen::Vector3d& c : occupied) {
      const octomap::OcTreeKey k = tree.coordToKey(c.x(), c.y(), c.z());
      for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], k[i]), hi[i] = std::max(hi[i], k[i]);
    }
    const octomap::OcTreeKey box_lo = tree.coordToKey(bmin), box_hi = tree.coordToKey(bmax);
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::max<int>(lo[i] - pad, box_lo[i]);
      hi[i] = std::min<int>(hi[i] + pad, box_hi[i]);
    }
    edt = std::make_unique<DynamicEDTOctomap>(static_cast<float>(o.max_distance_m), &tree, tree.keyToCoord(lo),
                                              tree.keyToCoord(hi), false);
    edt->update();
  });
  *cells = *differing = 0;
  *largest_difference = 0;
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z) {
        const octomap::OcTreeKey key(x, y, z);
        const octomap::point3d c = tree.keyToCoord(key);
        const double former = std::min<double>(edt->getDistance_unsafe(key), o.max_distance_m);
        const double d = std::abs(former - scene.distance_m(Eigen::Vector3d(c.x(), c.y(), c.z())));
        ++*cells;
        *differing += d > 1e-5;
        *largest_difference = std::max(*largest_difference, d);
      }
  return ms;
}

}  // namespace

int main() {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  const RobotSpheres spheres(robot);
  std::printf("robot: %zu spheres\n", spheres.model().size());

  OccupancyScene scene;  // the 128x128 one, for the queries below
  for (int size : {128, 256}) {
    const Frame frame = observe(robot, spheres, size);
    const std::size_t count = frame.points.size() / 3;
    auto planning_scene = [&](int threads) {
      SceneOptions o;
      o.threads = threads;
      OccupancyScene s(o);
      s.insert_camera(frame.points.data(), count, frame.origin, frame.robot, {});
      s.build_distance_field();
      return s;
    };
    std::printf("front %dx%d:\n", size, size);
    for (int threads : {1, 2})
      std::printf("  planning scene (endpoints + distance field), %d thread%s: %.1f ms\n", threads,
                  threads > 1 ? "s" : "", 1e3 * median_s(9, [&] { planning_scene(threads); }));
    OccupancyScene s = planning_scene(1);
    const double traced_ms = 1e3 * median_s(5, [&] {
      OccupancyScene t;
      t.insert_camera(frame.points.data(), count, frame.origin, frame.robot, {});
      t.occupancy_at(frame.origin);
    });
    std::printf("  traced OctoMap (rays; what --octomap and occupancy queries cost): %.1f ms, %zu occupied voxels\n",
                traced_ms, s.occupied_voxels());
    std::size_t cells = 0, differing = 0;
    double largest = 0;
    const double former_ms = former_scene_ms(frame, s, &cells, &differing, &largest);
    std::printf("  former scene (traced OctoMap + dynamicEDT3D): %.1f ms; its field differs from today's in %zu of %zu "
                "cells (largest difference %.4f m)\n",
                former_ms, differing, cells, largest);
    for (bool box_limit : {false, true})
      for (bool discretize : {false, true})
        for (bool lazy_eval : {false, true}) {
          std::size_t leaves = 0;
          const double ms = plain_octomap_ms(frame, discretize, lazy_eval, box_limit, &leaves);
          std::printf("  plain insertPointCloud box_limit=%d discretize=%d lazy_eval=%d: %.1f ms (%zu leaves)\n",
                      box_limit, discretize, lazy_eval, ms, leaves);
        }
    if (size == 128) scene = std::move(s);
  }

  // Distance queries at random points in the box.
  std::mt19937 rng(1);
  const SceneOptions o;
  std::vector<Eigen::Vector3d> points(1 << 16);
  for (auto& p : points)
    for (int k = 0; k < 3; ++k) p[k] = std::uniform_real_distribution<double>(o.min_corner[k], o.max_corner[k])(rng);
  double sink = 0;
  const int rounds = 50;
  const double query_s = median_s(5, [&] {
    for (int r = 0; r < rounds; ++r)
      for (const auto& p : points) sink += scene.distance_m(p);
  });
  std::printf("distance queries: %.1f M/s\n", rounds * points.size() / query_s / 1e6);

  // Whole-robot checks at random joint states (placed beforehand; placing is timed apart).
  const robot::JointVector lo = robot.lower_limits(), hi = robot.upper_limits();
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = world::SceneLayout{}.robot_base;
  std::vector<robot::JointVector> states(2000);
  for (auto& q : states)
    for (int k = 0; k < robot::kArmJoints; ++k) q[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
  std::vector<std::vector<Sphere>> placed(states.size());
  const double place_s = median_s(5, [&] {
    for (std::size_t i = 0; i < states.size(); ++i) spheres.place(states[i], 0.085, base, placed[i]);
  });
  int collisions = 0, self = 0;
  const double check_s = median_s(5, [&] {
    collisions = 0;
    for (int r = 0; r < 10; ++r)
      for (const auto& set : placed) collisions += scene.collides(set);
  });
  const int colliding = collisions / 10;
  const double self_s = median_s(5, [&] {
    self = 0;
    for (const auto& set : placed) self += spheres.self_collision(set, 0.01);
  });
  // Colliding states stop at their first sphere; free ones check them all.
  std::size_t free_index = 0;
  while (free_index < placed.size() && scene.collides(placed[free_index])) ++free_index;
  double free_s = 0;
  if (free_index < placed.size())
    free_s = median_s(5, [&] {
      for (int r = 0; r < 20000; ++r) sink += scene.collides(placed[free_index]);
    });
  std::printf("place(): %.0f k/s; scene sphere-set checks: %.0f k/s (random states, %d of %zu collide)",
              states.size() / place_s / 1e3, 10 * states.size() / check_s / 1e3, colliding, states.size());
  if (free_s > 0) std::printf(", %.0f k/s for a free state (all spheres)", 20000 / free_s / 1e3);
  std::printf("\nself_collision (margin 1 cm): %.0f k/s (%d of %zu collide)\n", states.size() / self_s / 1e3, self,
              states.size());
  return sink == 42.0;  // keeps the queries from being optimised away
}
