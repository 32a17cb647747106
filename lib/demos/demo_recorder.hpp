// Expert demonstrations: a task's scripted waypoints executed through the planner in the
// simulator, with an observation at every control step (as RLBench stores demos).
#pragma once

#include <functional>
#include <string>

#include "planning/motion_planner.hpp"
#include "sim_step/simulator.hpp"

namespace qte::demos {

struct DemoOptions {
  sim_step::EpisodePlan episodes;
  sim_step::SimulatorOptions simulator;  // observe_every_step is forced on
  planning::PlannerOptions planner;
  int retries = 0;  // new seeds tried for an episode whose expert failed
};

struct DemoSummary {
  int episodes = 0;
  int successes = 0;
  int retried = 0;  // episodes that needed another seed
  double seconds = 0;
};

// Writes each kept episode's observations followed by one 'episode' record (task, variation,
// seed, success, frames, attempts, failure). `progress` gets a line per episode.
DemoSummary record_demos(const robot::RobotModel& robot, DemoOptions options,
                         const std::function<void(const stream::Record&)>& emit,
                         const std::function<void(const std::string&)>& progress);

}  // namespace qte::demos
