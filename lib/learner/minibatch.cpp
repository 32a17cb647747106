#include "learner/minibatch.hpp"

#include <chrono>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

#include "qattention/proprio.hpp"
#include "stream/field_names.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::learner {
namespace {

std::string format_metres(double metres) {
  std::ostringstream text;
  text << metres;
  return text.str();
}

}  // namespace

void check_transition(const stream::Record& t, const LearnerConfig& config) {
  const int v = config.hierarchy.voxels(), depths = config.hierarchy.depths;
  if (t.has(fields::voxels) && t.scalar<int32_t>(fields::voxels) != v)
    t.fail(fields::voxels, std::to_string(v) + " voxels per side, as the networks (--voxels); the transition has " +
                               std::to_string(t.scalar<int32_t>(fields::voxels)));
  for (int d = 0; d < depths; ++d) {
    if (!t.has(fields::depth_field(d, fields::per_depth::index)))
      t.fail(fields::depth_field(d, fields::per_depth::index),
             "an action at each of the networks' " + std::to_string(depths) + " depths (--depths)");
    const auto index = t.array<int32_t>(fields::depth_field(d, fields::per_depth::index));
    if (index.size() != 3) t.fail(fields::depth_field(d, fields::per_depth::index), "int32 [3]");
    for (int axis = 0; axis < 3; ++axis)
      if (index[axis] < 0 || index[axis] >= v)
        t.fail(fields::depth_field(d, fields::per_depth::index),
               "voxel indices in 0.." + std::to_string(v - 1) + " (--voxels " + std::to_string(v) + ")");
    // The next states' grids are cut with the learner's own edges: a transition keyframed with
    // another --offset (or scene) would be learned from grids of two sizes.
    const double edge = voxels::bounds_field(t, fields::depth_field(d, fields::per_depth::bounds), v).size_m;
    const double expected = config.hierarchy.bounds_at(d, Eigen::Vector3d::Zero()).size_m;
    if (std::abs(edge - expected) > 1e-6)
      t.fail(fields::depth_field(d, fields::per_depth::bounds),
             "a grid edge of " + format_metres(expected) + " m, as the learner's " +
                 (d == 0 ? std::string("scene (--bounds)") : "--offset (2 x offset)") + "; the transition has " +
                 format_metres(edge) + " m (keyframed with other settings?)");
  }
  if (t.has(fields::depth_field(depths, fields::per_depth::index)))
    t.fail(fields::depth_field(depths, fields::per_depth::index),
           "no more than the networks' " + std::to_string(depths) + " depths (--depths)");
  const auto bins = t.array<int32_t>(fields::rotation_bins);
  if (bins.size() != 3) t.fail(fields::rotation_bins, "int32 [3]");
  for (int axis = 0; axis < 3; ++axis)
    if (bins[axis] < 0 || bins[axis] >= nets::kRotationBins) t.fail(fields::rotation_bins, "bins in 0..71");
  if (!std::isfinite(t.scalar<float>(fields::reward))) t.fail(fields::reward, "a finite reward");
}

Minibatch assemble_minibatch(const replay::ReplayBuffer& replay, const replay::Sample& sample,
                             const LearnerConfig& config) {
  const voxels::CoarseToFine& h = config.hierarchy;
  const int v = h.voxels(), depths = h.depths;
  const std::size_t grid_floats = static_cast<std::size_t>(v) * v * v * voxels::kChannels;
  Minibatch b;
  std::map<std::pair<const stream::Record*, int32_t>, int64_t> next_states;  // (frame, step) -> id
  b.size = static_cast<int>(sample.indices.size());
  b.indices = sample.indices;
  b.weights = sample.weights;
  b.grids.assign(depths, std::vector<float>(grid_floats * b.size));
  b.voxel.assign(depths, std::vector<int64_t>(b.size));
  for (int i = 0; i < b.size; ++i) {
    const std::size_t index = sample.indices[i];
    const stream::Record& t = replay.transition(index);  // checked when read (check_transition)
    const stream::Record& frame = replay.frame_of(index);
    auto start = std::chrono::steady_clock::now();
    const auto cloud = replay.cloud_of(index);
    b.clouds_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    voxels::require_points_in_scene(frame, *cloud, h.scene);  // never learn from an empty scene
    for (int d = 0; d < depths; ++d) {
      const voxels::GridBounds g = voxels::bounds_field(t, fields::depth_field(d, fields::per_depth::bounds), v);
      const auto index3 = t.array<int32_t>(fields::depth_field(d, fields::per_depth::index));
      b.voxel[d][i] = voxels::flat_index(Eigen::Vector3i(index3[0], index3[1], index3[2]), v);
      voxels::voxelize(cloud->view(), g, b.grids[d].data() + i * grid_floats);
    }
    const std::vector<float> p = qattention::proprio_of(frame, t.scalar<int32_t>(fields::step));
    b.proprio.insert(b.proprio.end(), p.begin(), p.end());
    const auto bins = t.array<int32_t>(fields::rotation_bins);
    for (int axis = 0; axis < 3; ++axis) b.rotation_bins.push_back(bins[axis]);
    b.gripper.push_back(t.scalar<uint8_t>(fields::gripper_open) != 0 ? 1 : 0);
    b.demo.push_back(t.has(fields::demo) && t.scalar<uint8_t>(fields::demo) != 0 ? 1.0f : 0.0f);
    // The n-step return: rewards along the chain until it ends or n transitions are summed,
    // then the discounted value of the observation reached.
    std::size_t last = index;
    double reward = 0, discount = 1;
    for (int n = 0; n < config.n_step; ++n) {
      const stream::Record& u = replay.transition(last);
      reward += discount * u.scalar<float>(fields::reward);
      discount *= config.gamma;
      if (u.scalar<uint8_t>(fields::terminal) != 0) {
        discount = 0;
        break;
      }
      if (n + 1 == config.n_step) break;
      const std::optional<std::size_t> successor = replay.successor_of(last);
      if (!successor) break;
      last = *successor;
    }
    b.reward.push_back(static_cast<float>(reward));
    b.discount.push_back(static_cast<float>(discount));
    const stream::Record& next = replay.next_frame_of(last);
    const int32_t next_step = replay.transition(last).scalar<int32_t>(fields::step) + 1;
    start = std::chrono::steady_clock::now();
    b.next_clouds.push_back(replay.next_cloud_of(last));
    b.clouds_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    voxels::require_points_in_scene(next, *b.next_clouds.back(), h.scene);
    b.next_proprio.push_back(qattention::proprio_of(next, next_step));
    b.next_state.push_back(next_states.emplace(std::pair{&next, next_step}, next_states.size()).first->second);
  }
  return b;
}

}  // namespace qte::learner
