// Shared by the Q-attention and learner tests: a stand-in for a network whose Q values are a
// function of the grid's content alone (so a grid's Qs do not depend on the batch it is in),
// irregular enough that top-K and max have no ties: per voxel from its mean point, colour and
// index; rotation and gripper from the whole grid. `phase` makes another network of it (an
// online and a target network that disagree everywhere).
#pragma once

#include <cmath>

#include "qattention/tree_expansion.hpp"

namespace qte::test_support {

inline nets::QValues content_q_values(int depth, const float* grids, int batch, float phase = 0) {
  const int cells = 16 * 16 * 16;
  nets::QValues out;
  out.batch = batch;
  out.translation.resize(static_cast<std::size_t>(batch) * cells);
  out.rotation.resize(static_cast<std::size_t>(batch) * 3 * 72);
  out.gripper.resize(static_cast<std::size_t>(batch) * 2);
  for (int b = 0; b < batch; ++b) {
    double sum_x = 0, occupied = 0;
    for (int cell = 0; cell < cells; ++cell) {
      const float* c = grids + (static_cast<std::size_t>(b) * cells + cell) * voxels::kChannels;
      const float point = c[9] * std::sin(17 * c[0] + 29 * c[1] + 41 * c[2] + depth + phase);
      out.translation[static_cast<std::size_t>(b) * cells + cell] =
          point + 0.25f * c[9] * c[3] + 0.1f * std::cos(13 * c[6] + 7 * c[7] + 5 * c[8] + 0.3f * depth + phase);
      sum_x += c[0];
      occupied += c[9];
    }
    for (int i = 0; i < 3 * 72; ++i)
      out.rotation[static_cast<std::size_t>(b) * 216 + i] =
          static_cast<float>(std::sin(0.37 * i * (1 + occupied) + sum_x + phase));
    out.gripper[b * 2] = static_cast<float>(std::sin(sum_x + phase));
    out.gripper[b * 2 + 1] = static_cast<float>(std::cos(sum_x + 2 * phase));
  }
  return out;
}

inline qattention::DepthEvaluator content_q(float phase = 0) {
  return [phase](int depth, const float* grids, const float*, int batch) {
    return content_q_values(depth, grids, batch, phase);
  };
}

}  // namespace qte::test_support
