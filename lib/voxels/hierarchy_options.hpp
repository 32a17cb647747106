// The coarse-to-fine hierarchy on the command line: --voxels, --bounds, --depths, --offset,
// one option group for every tool that voxelizes, labels or learns, so their help and their
// parsing cannot drift apart.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxels {

// --voxels and --bounds: the depth-0 grid (voxelize has them without the deeper depths).
std::vector<cli::OptionSpec> scene_options();
// The scene grid; --voxels refused outside min_voxels..max_voxels (the networks need 4..128).
GridBounds parse_scene(const cli::Arguments& args, int min_voxels = 2, int max_voxels = 256);

// --voxels, --depths, --offset, --bounds with the published defaults (keyframe, qattn-train).
std::vector<cli::OptionSpec> hierarchy_options();
CoarseToFine parse_hierarchy(const cli::Arguments& args, int min_voxels = 2, int max_voxels = 256);

// The same four options for a tool that takes the hierarchy from a checkpoint (qte-select):
// no defaults of their own, and any given must agree with the checkpoint.
std::vector<cli::OptionSpec> checkpoint_hierarchy_options();
// `trained` is the checkpoint's hierarchy where it kept one; voxels and depths always come
// from its networks. Options that differ are a UsageError naming `checkpoint`; for a
// checkpoint without a kept hierarchy they fill it in.
CoarseToFine checkpoint_hierarchy(const cli::Arguments& args, const std::optional<CoarseToFine>& trained,
                                  int voxels, int depths, const std::string& checkpoint);

}  // namespace qte::voxels
