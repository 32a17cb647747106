// The simulator on the command line: the option groups sim-step and demo-record share, so
// their cameras and episode plans are given, documented and checked the same way.
#pragma once

#include <vector>

#include "cli/command.hpp"
#include "sim_step/simulator.hpp"

namespace qte::sim_step {

// --cameras, --image-size, --compress, --objects: what an observation holds.
std::vector<cli::OptionSpec> camera_options();
SimulatorOptions parse_camera_options(const cli::Arguments& args);

// --episodes, --variation, --scenes: the episodes of one task (the tool declares --task).
std::vector<cli::OptionSpec> episode_options(int default_episodes, SceneSet default_scenes);
// The plan of `task` (checked: an unknown task fails before anything is written).
EpisodePlan parse_episode_plan(const cli::Arguments& args, const std::string& task);

}  // namespace qte::sim_step
