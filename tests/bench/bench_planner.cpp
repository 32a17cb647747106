// Prints planner figures: success rate and median / 95th-percentile planning time over random
// reachable goals in task scenes, scene (OctoMap + distance field) build time, IK time.
// --decisions FILE: one line per goal (task, scene, goal, outcome, waypoints, duration), to
// diff the planner's decisions between two builds.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "planning/motion_planner.hpp"
#include "sim_step/simulator.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

static double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * v.size()))];
}

static double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

int main(int argc, char** argv) {
  std::FILE* decisions = argc == 3 && std::string(argv[1]) == "--decisions" ? std::fopen(argv[2], "w") : nullptr;
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  const Eigen::Isometry3d base = world::SceneLayout{}.robot_base_pose();
  std::mt19937 rng(11);

  // IK from the ready pose to random reachable targets.
  {
    std::vector<double> times;
    int solved = 0;
    robot::JointVector ready;
    ready << 0, -0.35, 0, 0.75, 0, 1.1, 0;
    for (int i = 0; i < 500; ++i) {
      robot::JointVector q;
      for (int k = 0; k < 7; ++k)
        q[k] = std::uniform_real_distribution<>(std::max(-2.5, robot.lower_limits()[k]), std::min(2.5, robot.upper_limits()[k]))(rng);
      const auto t0 = Clock::now();
      solved += robot::solve_ik(robot, robot.tcp_pose(q), ready).has_value();
      times.push_back(seconds_since(t0));
    }
    std::printf("ik: %d/500 random reachable targets solved from the ready pose; median %.2f ms, p95 %.2f ms\n",
                solved, 1e3 * percentile(times, 0.5), 1e3 * percentile(times, 0.95));
  }

  // Planning in task scenes: 10 scenes x 20 goals per task family.
  std::vector<double> scene_times, plan_times;
  std::map<std::string, int> outcomes;
  int goals = 0;
  for (const char* task : {"pick_and_lift", "lift_numbered_block", "reach_target"}) {
    for (int scene_index = 0; scene_index < (std::string(task) == "reach_target" ? 2 : 4); ++scene_index) {
      sim_step::SimulatorOptions options;
      sim_step::Simulator sim(robot, options);
      stream::Record obs("obs");
      sim.handle(sim_step::plan_reset({task, 0, 10, 3}, scene_index), [&](const stream::Record& r) { obs = r; });
      planning::MotionPlanner planner(robot, base);
      const planning::StartState start = planning::start_state_from(obs);
      for (int g = 0; g < 20; ++g) {
        // A random reachable TCP pose above the table, gripper pointing down-ish.
        planning::Goal goal;
        for (;;) {
          robot::JointVector q;
          for (int k = 0; k < 7; ++k)
            q[k] = std::uniform_real_distribution<>(std::max(-2.5, robot.lower_limits()[k]), std::min(2.5, robot.upper_limits()[k]))(rng);
          goal.tcp_pose = base * robot.tcp_pose(q);
          const Eigen::Vector3d p = goal.tcp_pose.translation();
          if (p.z() > 0.80 && p.z() < 1.25 && p.x() > -0.1 && p.x() < 0.45 && std::abs(p.y()) < 0.35 &&
              goal.tcp_pose.linear().col(2).z() < -0.3 && planner.collisions().state_valid(q, start.opening_m, nullptr))
            break;
        }
        auto t0 = Clock::now();
        const planning::OccupancyScene scene = planner.scene_from(obs, start, &goal);
        scene_times.push_back(seconds_since(t0));
        const planning::PlanResult plan = planner.plan(start, goal, scene, goals);
        plan_times.push_back(plan.planning_time_s);
        const std::string outcome = plan.failure.empty() ? "ok:" + plan.method : plan.failure;
        outcomes[outcome] += 1;
        if (decisions)
          std::fprintf(decisions, "%s %d %d %s %zu %.6f\n", task, scene_index, g, outcome.c_str(),
                       plan.time_s.size(), plan.time_s.empty() ? 0.0 : plan.time_s.back());
        ++goals;
      }
    }
  }
  int ok = 0;
  for (const auto& [k, n] : outcomes) ok += k.rfind("ok:", 0) == 0 ? n : 0;
  std::printf("plan: %d/%d random reachable goals planned (%.1f%%) in 10 task scenes\n", ok, goals, 100.0 * ok / goals);
  for (const auto& [k, n] : outcomes) std::printf("  %-22s %d\n", k.c_str(), n);
  std::printf("plan time: median %.1f ms, p95 %.1f ms (IK + collision checks + RRT-Connect + shortcut + timing)\n",
              1e3 * percentile(plan_times, 0.5), 1e3 * percentile(plan_times, 0.95));
  std::printf("scene build (OctoMap insertion + distance field, 128x128 front camera): median %.0f ms, p95 %.0f ms\n",
              1e3 * percentile(scene_times, 0.5), 1e3 * percentile(scene_times, 0.95));
  if (decisions) std::fclose(decisions);
}
