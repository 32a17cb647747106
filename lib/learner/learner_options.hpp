// The learner's command-line options, one group per settings struct (LearnerConfig, LoopOptions,
// ReplayOptions). Each option's default is the struct's own initial value, so a setting has one
// home: qattn-train's --help, its man page and docs/learner.md's table all show what the struct
// says (tests/tools/test_docs_settings.py compares them).
#pragma once

#include <vector>

#include "cli/command.hpp"
#include "learner/settings.hpp"
#include "learner/training_loop.hpp"
#include "replay/replay_buffer.hpp"

namespace qte::learner {

// --architecture, --base-channels, --batch, --gamma ... --n-step (the networks' voxel grids and
// the tree target's branching have their own groups: voxels::hierarchy_options(),
// qattention::branching_options()).
std::vector<cli::OptionSpec> learner_config_options();
// Every value range-checked, then LearnerConfig::validate(); hierarchy parsed with the grids the
// networks can take.
LearnerConfig learner_config_from(const cli::Arguments& args);

// --steps, --follow, --stop-file, --replay-ratio, --pretrain, --start-after, --checkpoint-every,
// --metrics, --log-every, --beta, --threads.
std::vector<cli::OptionSpec> loop_options();
LoopOptions loop_options_from(const cli::Arguments& args);

// --uniform, --alpha, --capacity, --cloud-memory.
std::vector<cli::OptionSpec> replay_options();
replay::ReplayOptions replay_options_from(const cli::Arguments& args);

}  // namespace qte::learner
