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

// --chunk-episodes, --first-chunk, --chunk-stride, --gate: an actor that stays up for a whole
// learning run, paced by the loop through a DirectoryGate.
std::vector<cli::OptionSpec> chunk_options();

// What sim-step and robot-step do once their environment is made: `env` driven by the records
// of the input file and, with a plan (--task), by itself, in chunks when --chunk-episodes is
// given; observations to --output. With a plan, once it is done standard output is closed and
// the input read to its end, so that an actor loop closed by a FIFO winds down without broken
// pipes.
void run_episodes(const cli::Arguments& args, EpisodeStage& env, std::optional<EpisodePlan> plan);

}  // namespace qte::sim_step
