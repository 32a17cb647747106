// Shared by the learner's tests: synthetic frames (a grey floor and one coloured block) and
// terminal transitions to the block, and a replay of four such episodes.
#pragma once

#include <random>

#include "learner/settings.hpp"
#include "replay/replay_buffer.hpp"
#include "stream/record.hpp"

namespace qte::test_support {

constexpr int V = 16;

// A frame with a synthetic point cloud: a floor of grey points and one coloured block whose
// position identifies the frame (what the networks can tell frames apart by).
inline stream::Record frame(int64_t episode, int32_t index, const Eigen::Vector3f& block, uint8_t red) {
  std::mt19937 rng(static_cast<uint32_t>(episode * 100 + index));
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (int i = 0; i < 1500; ++i) {
    xyz.insert(xyz.end(), {-0.3f + u(rng), -0.5f + u(rng), 0.76f});
    rgb.insert(rgb.end(), {90, 90, 90});
  }
  for (int i = 0; i < 300; ++i) {
    xyz.insert(xyz.end(), {block.x() + 0.04f * u(rng), block.y() + 0.04f * u(rng), block.z() + 0.04f * u(rng)});
    rgb.insert(rgb.end(), {red, 20, 20});
  }
  stream::Record r("frame");
  r.set_scalar<int64_t>("episode_key", episode);
  r.set_scalar<int32_t>("frame", index);
  const int64_t n = static_cast<int64_t>(rgb.size() / 3);
  r.set<float>("front.points", {1, n, 3}, xyz);
  r.set<uint8_t>("front.rgb", {1, n, 3}, rgb);
  r.set_scalar<uint8_t>("gripper_open", 1);
  r.set_scalar<double>("gripper_opening_m", 0.08);
  return r;
}

// A transition to the block's voxel at every depth, terminal with reward 100 (target 1).
inline stream::Record transition(const voxels::CoarseToFine& h, int64_t episode, const Eigen::Vector3d& goal, bool terminal) {
  stream::Record t("transition");
  t.set_scalar<int64_t>("episode_key", episode);
  t.set_scalar<int32_t>("frame", 0);
  t.set_scalar<int32_t>("next_frame", 1);
  t.set_scalar<int32_t>("step", 0);
  t.set_scalar<int32_t>("voxels", V);
  const auto indices = h.indices_of(goal);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int d = 0; d < h.depths; ++d) {
    const voxels::GridBounds b = h.bounds_at(d, centre);
    t.set<int32_t>("depth" + std::to_string(d) + ".index", {3}, indices[d].data());
    t.set<double>("depth" + std::to_string(d) + ".bounds", {4},
                  std::vector<double>{b.min_corner.x(), b.min_corner.y(), b.min_corner.z(), b.size_m});
    centre = b.centre_of(indices[d]);
  }
  t.set<int32_t>("rotation_bins", {3}, std::vector<int32_t>{36, 36, 18});
  t.set_scalar<uint8_t>("gripper_open", 0);
  t.set_scalar<uint8_t>("ignore_collisions", 0);
  t.set_scalar<float>("reward", terminal ? 100.0f : 0.0f);
  t.set_scalar<uint8_t>("terminal", terminal);
  t.set_scalar<uint8_t>("demo", 1);
  return t;
}

// Four episodes, each one terminal transition to its block.
inline replay::ReplayBuffer tiny_replay(const learner::LearnerConfig& config) {
  replay::ReplayBuffer replay;
  const Eigen::Vector3f blocks[4] = {{0.1f, -0.2f, 0.78f}, {0.3f, 0.2f, 0.78f}, {0.0f, 0.3f, 0.78f}, {0.4f, -0.3f, 0.78f}};
  for (int e = 0; e < 4; ++e) {
    replay.add(frame(e, 0, blocks[e], 220));
    replay.add(frame(e, 1, blocks[e], 220));
    replay.add(transition(config.hierarchy, e, blocks[e].cast<double>() + Eigen::Vector3d(0.02, 0.02, 0.02), true));
  }
  return replay;
}

}  // namespace qte::test_support
