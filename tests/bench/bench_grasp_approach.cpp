// Whether a path to a grasp sweeps through what the gripper is to grasp, task by task: on the
// evaluation's held-out scenes (sim-step --scenes eval with learn.sh's evaluation seed), the
// expert's first grasp (its first waypoint that closes the open gripper) commanded straight from
// the start pose, as an agent that skips the expert's pose above the object does, planned by
// plan-path's planner without and with --approach M (docs/planning.md), the path replayed in the
// Bullet world. Prints per task and way: scenes planned, the planner's refusals, and the paths
// that touched an object or hit the table or the arm itself on the way (the first contact, at the
// physics rate, before the gripper closes, more than 1 cm from the grasp; a contact within 1 cm,
// fingers reaching a board under a flat checker, say, is the grasp's own and counted apart). The
// figures behind examples/Makefile's APPROACH_TASKS.
// Options: --episodes N (default 50), --approach M (default 0.1), --seed S (the scenes' run seed,
// default 1000000 as learn.sh's EVAL_SEED), --image-size WxH (the front camera the planner's map
// is made from, default 128x128: Task Set 1's; Task Set 2's is 256x256), then task names
// (default: every task whose expert grasps).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "planning/motion_planner.hpp"
#include "sim_step/simulator.hpp"
#include "tasks/task.hpp"

using namespace qte;

namespace {

struct Contact {
  std::string what;  // "" if none
  double from_goal_m = 0;  // the tool point's distance from the grasp there
};

// The first contact of the arm (with the table, itself or an object) along the path, replayed at
// 8 samples a waypoint with the fingers as they are.
Contact first_contact(world::World& world, const robot::RobotModel& robot, const planning::PlanResult& plan,
                      const Eigen::Isometry3d& goal) {
  for (std::size_t i = 1; i < plan.joint_positions.size(); ++i)
    for (int s = 1; s <= 8; ++s) {
      const robot::JointVector q =
          plan.joint_positions[i - 1] + (s / 8.0) * (plan.joint_positions[i] - plan.joint_positions[i - 1]);
      world.set_robot_state(q, world.finger_opening_m());
      std::string c = world.robot_collision();
      if (c.empty()) c = world.robot_object_contact();
      if (!c.empty())
        return {c, ((world.robot_base_pose() * robot.tcp_pose(q)).translation() - goal.translation()).norm()};
    }
  return {};
}

struct Tally {
  int scenes = 0, refused = 0, touched = 0, at_grasp = 0;
  std::map<std::string, int> refusals;
};

}  // namespace

int main(int argc, char** argv) {
  int episodes = 50;
  double approach = 0.1;
  uint64_t run_seed = 1000000;
  int width = 128, height = 128;
  std::vector<std::string> tasks;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--episodes" && i + 1 < argc) episodes = std::atoi(argv[++i]);
    else if (a == "--approach" && i + 1 < argc) approach = std::atof(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) run_seed = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--image-size" && i + 1 < argc) {
      if (std::sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 8 || height < 8) {
        std::fprintf(stderr, "bench_grasp_approach: --image-size %s: expected WxH, each at least 8\n", argv[i]);
        return 2;
      }
    } else if (a.rfind("--", 0) == 0) {
      std::fprintf(stderr, "bench_grasp_approach: unknown option %s\n", a.c_str());
      return 2;
    } else tasks.push_back(a);
  }
  if (!(approach > 0) || episodes < 1) {
    std::fprintf(stderr, "bench_grasp_approach: --approach must be above 0 and --episodes at least 1\n");
    return 2;
  }
  if (tasks.empty())
    tasks = {"pick_and_lift", "take_lid_off_saucepan", "pick_up_cup", "put_rubbish_in_bin", "stack_wine",
             "phone_on_base", "take_umbrella_out_of_umbrella_stand", "lift_numbered_block", "pick_and_lift_small",
             "setup_checkers", "stack_blocks"};
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  sim_step::SimulatorOptions sim_options = sim_step::options_for_cameras({"front"}, width, height);
  sim_options.render_threads = 1;
  std::printf("the expert's first grasp commanded from the start pose, %d held-out scenes a task (seed %llu, %dx%d)\n",
              episodes, static_cast<unsigned long long>(run_seed), width, height);
  std::printf("%-36s %-16s %7s %8s %8s %9s  refusals\n", "task", "planner", "scenes", "refused", "touched",
              "at grasp");
  for (const std::string& task : tasks) {
    std::map<double, Tally> tallies;
    int no_grasp = 0;  // scenes whose expert never closes an open gripper
    for (int e = 0; e < episodes; ++e) {
      sim_step::Simulator sim(robot, sim_options);
      stream::Record obs("obs");
      const sim_step::EpisodePlan plan{task, 0, episodes, run_seed, sim_step::SceneSet::eval};
      sim.handle(sim_step::plan_reset(plan, e), [&](const stream::Record& r) { obs = r; });
      world::World& world = *sim.world();
      const planning::StartState start = planning::start_state_from(obs);
      planning::Goal grasp;
      bool found = false;
      bool open = start.opening_m > 0.02;
      for (const tasks::Waypoint& w : sim.task()->expert_waypoints(world)) {
        if (open && !w.gripper_open) {
          grasp.tcp_pose = w.tcp_pose, grasp.gripper_open = false, found = true;
          break;
        }
        open = w.gripper_open;
      }
      if (!found) {
        ++no_grasp;
        continue;
      }
      for (const double m : {0.0, approach}) {
        planning::PlannerOptions options;
        options.approach_m = m;
        const planning::MotionPlanner planner(robot, world.robot_base_pose(), options);
        const planning::OccupancyScene scene = planner.scene_from(obs, start, &grasp);
        const planning::PlanResult result = planner.plan(start, grasp, scene, static_cast<uint64_t>(e));
        Tally& t = tallies[m];
        ++t.scenes;
        if (!result.failure.empty()) {
          ++t.refused, ++t.refusals[result.failure];
          continue;
        }
        world.set_robot_state(start.joints, start.opening_m);
        const Contact contact = first_contact(world, robot, result, grasp.tcp_pose);
        if (contact.what.empty()) continue;
        (contact.from_goal_m > 0.01 ? t.touched : t.at_grasp) += 1;
      }
    }
    if (tallies.empty()) {
      std::printf("%-36s (its expert does not grasp)\n", task.c_str());
      continue;
    }
    for (const auto& [m, t] : tallies) {
      std::string refusals;
      for (const auto& [why, n] : t.refusals) refusals += why + " " + std::to_string(n) + "  ";
      char way[32];
      std::snprintf(way, sizeof way, m > 0 ? "--approach %.2g" : "to the grasp", m);
      std::printf("%-36s %-16s %7d %8d %8d %9d  %s\n", task.c_str(), way, t.scenes, t.refused, t.touched, t.at_grasp,
                  refusals.c_str());
    }
    if (no_grasp > 0) std::printf("%-36s (%d scenes without a grasp by the expert left out)\n", task.c_str(), no_grasp);
    std::fflush(stdout);
  }
  return 0;
}
