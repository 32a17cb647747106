#include "demos/demo_recorder.hpp"

#include <chrono>
#include <cstdio>
#include <vector>

#include "stream/field_names.hpp"

namespace qte::demos {
namespace {

struct Attempt {
  std::vector<stream::Record> records;
  bool success = false;
  std::string failure;
  int64_t seed = 0;
  int variation = 0;
};

Attempt run_episode(sim_step::Simulator& sim, planning::PlanPathFilter& planner, const stream::Record& reset) {
  Attempt attempt;
  attempt.seed = reset.scalar<int64_t>(fields::seed);
  attempt.variation = reset.scalar<int32_t>(fields::variation);
  auto keep = [&](const stream::Record& r) { attempt.records.push_back(r); };
  sim.handle(reset, keep);
  // Waypoints are fixed at the start, from the scene as it was reset (as RLBench's are).
  const auto waypoints = sim.task()->expert_waypoints(*sim.world());
  for (const auto& waypoint : waypoints) {
    if (sim.episode_over()) break;
    planning::Goal goal;
    goal.tcp_pose = waypoint.tcp_pose;
    goal.gripper_open = waypoint.gripper_open;
    goal.ignore_collisions = waypoint.ignore_collisions;
    std::vector<stream::Record> planned;
    planner.handle(attempt.records.back(), [](const stream::Record&) {});  // the state to plan from
    planner.handle(planning::action_record(goal), [&](const stream::Record& r) { planned.push_back(r); });
    sim.handle(planned.back(), keep);  // the trajectory (or failure)
  }
  const stream::Record& last = attempt.records.back();
  attempt.success = last.scalar<uint8_t>(fields::success) != 0;
  if (last.has(fields::failure))
    attempt.failure = last.string(fields::failure);
  else if (!attempt.success) attempt.failure = "expert_did_not_succeed";
  return attempt;
}

}  // namespace

DemoSummary record_demos(const robot::RobotModel& robot, DemoOptions options,
                         const std::function<void(const stream::Record&)>& emit,
                         const std::function<void(const std::string&)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  options.simulator.observe_every_step = true;
  sim_step::Simulator sim(robot, options.simulator);
  planning::PlanPathFilter planner(robot, world::SceneLayout{}.robot_base_pose(), options.planner);
  DemoSummary summary;
  const int n = options.episodes.episodes;
  for (int e = 0; e < n; ++e) {
    const auto episode_start = std::chrono::steady_clock::now();
    Attempt attempt;
    int attempts = 0;
    do {
      // Retries use seeds no first attempt uses: indices past the plan's episodes.
      const int index = attempts == 0 ? e : n + e * options.retries + attempts - 1;
      attempt = run_episode(sim, planner, sim_step::plan_reset(options.episodes, index));
      ++attempts;
    } while (!attempt.success && attempts <= options.retries);
    for (const auto& r : attempt.records) emit(r);
    stream::Record episode(record_type::episode);
    episode.set_string(fields::task, options.episodes.task);
    episode.set_scalar<int32_t>(fields::episode, e);
    episode.set_scalar<int32_t>(fields::variation, attempt.variation);
    episode.set_scalar<int64_t>(fields::seed, attempt.seed);
    episode.set_scalar<uint8_t>(fields::success, attempt.success);
    episode.set_scalar<int32_t>(fields::frames, static_cast<int32_t>(attempt.records.size()));
    episode.set_scalar<int32_t>(fields::attempts, attempts);
    if (!attempt.failure.empty()) episode.set_string(fields::failure, attempt.failure);
    emit(episode);
    summary.episodes += 1;
    summary.successes += attempt.success;
    summary.retried += attempts > 1;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - episode_start).count();
    char timing[64];
    std::snprintf(timing, sizeof timing, ", %zu frames, %.2f s", attempt.records.size(), seconds);
    std::string line = "episode " + std::to_string(e + 1) + "/" + std::to_string(n) + " " +
                       options.episodes.task + ": " +
                       (attempt.success ? std::string("success") : "failed (" + attempt.failure + ")") + timing;
    if (attempts > 1) line += " after " + std::to_string(attempts) + " attempts (new seeds)";
    progress(line);
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace qte::demos
