// The command-line options that choose tree expansion's branching, one declaration for
// qte-select (--k, acting) and qattn-train (--tree-target, the bootstrap target): a number K,
// or 'auto' with --k-margin M (every voxel within M of a node's best Q) or --k-mass P (the
// fewest best voxels holding P of its softmax), at most --k-max.
#pragma once

#include <string>
#include <vector>

#include "cli/command.hpp"
#include "qattention/tree_expansion.hpp"

namespace qte::qattention {

std::vector<cli::OptionSpec> branching_options();  // --k-margin, --k-mass, --k-max

// From the value of `k_option` ("K", at least `min_k`, or "auto") and the options above;
// UsageError when they do not make sense together (auto without a rule, both rules, a rule
// without auto).
Branching parse_branching(const cli::Arguments& args, const std::string& k_option, int min_k);

// "10", or "auto (margin 0.5, at most 10)": for logs and checkpoints' settings.
std::string describe(const Branching& branching);

}  // namespace qte::qattention
