// Prints simulator figures: physics steps per second, and the time of full sim-step steps
// (reset; one expert trajectory executed and observed) with the front camera.
#include <chrono>
#include <cstdio>

#include "common/random.hpp"
#include "robot/inverse_kinematics.hpp"
#include "sim_step/simulator.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

static double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int main() {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  {
    sim_step::SimulatorOptions options;
    sim_step::Simulator simulator(robot, options);
    simulator.handle(sim_step::plan_reset({"pick_and_lift", 0, 1, 0}, 0), [](const stream::Record&) {});
    world::World& world = *simulator.world();
    const int steps = 4800;
    const auto t0 = Clock::now();
    world.settle(steps * world::World::kPhysicsStep);
    const double s = seconds_since(t0);
    std::printf("physics pick_and_lift scene: %.0f steps/s (%.1f x real time at 240 Hz)\n", steps / s,
                steps / s / 240.0);
  }
  for (const char* task : {"reach_target", "pick_and_lift", "lift_numbered_block"}) {
    for (int size : {128, 256}) {
      sim_step::SimulatorOptions options;
      options.cameras[0].intrinsics.width = options.cameras[0].intrinsics.height = size;
      sim_step::Simulator simulator(robot, options);
      double reset_s = 0, step_s = 0, trajectory_s = 0;
      const int episodes = 5;
      for (int e = 0; e < episodes; ++e) {
        auto t0 = Clock::now();
        simulator.handle(sim_step::plan_reset({task, 0, episodes, 7}, e), [](const stream::Record&) {});
        reset_s += seconds_since(t0);
        world::World& world = *simulator.world();
        const auto waypoint = simulator.task()->expert_waypoints(world).front();
        const auto q = robot::solve_ik(robot, world.robot_base_pose().inverse() * waypoint.tcp_pose,
                                       world.joint_positions());
        if (!q) continue;
        const double duration = std::max(0.2, (*q - world.joint_positions()).cwiseAbs().maxCoeff() / 1.5);
        stream::Record trajectory("trajectory");
        trajectory.set<double>("time_s", {2}, std::vector<double>{0, duration});
        std::vector<double> joints(world.joint_positions().data(), world.joint_positions().data() + 7);
        joints.insert(joints.end(), q->data(), q->data() + 7);
        trajectory.set<double>("joint_positions", {2, 7}, joints);
        trajectory.set_scalar<uint8_t>("gripper_open", 1);
        t0 = Clock::now();
        simulator.handle(trajectory, [](const stream::Record&) {});
        step_s += seconds_since(t0);
        trajectory_s += duration;
      }
      std::printf("sim-step %s %dx%d: reset %.1f ms, one trajectory step %.1f ms (%.2f s of motion)\n", task,
                  size, size, 1e3 * reset_s / episodes, 1e3 * step_s / episodes, trajectory_s / episodes);
    }
  }
}
