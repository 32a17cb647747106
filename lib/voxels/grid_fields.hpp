// Grids in records: a grid's bounds as the float64 [4] field (minimum corner x, y, z and edge
// length, metres) that transitions, actions and voxels records carry, and a whole hierarchy
// (`hierarchy.bounds`, `hierarchy.offsets` float64 [depths - 1], `hierarchy.depths` int32,
// `hierarchy.voxels` int32) as the learner's checkpoints carry it for the actor.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "stream/record.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxels {

std::vector<double> bounds_values(const GridBounds& bounds);
// The bounds of field `name` (fails naming the field unless it is float64 [4]).
GridBounds bounds_field(const stream::Record& record, const std::string& name, int voxels);

void set_hierarchy(stream::Record& record, const CoarseToFine& hierarchy);
// The record's hierarchy, or nothing when it has none (checkpoints written before it was kept).
std::optional<CoarseToFine> hierarchy_of(const stream::Record& record);

}  // namespace qte::voxels
