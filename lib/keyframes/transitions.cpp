#include "keyframes/transitions.hpp"

#include <cmath>
#include <cstring>
#include <set>
#include <sstream>

#include "common/error.hpp"
#include "common/random.hpp"
#include "keyframes/keyframes.hpp"
#include "robot/pose_values.hpp"
#include "robot/rotation_bins.hpp"
#include "stream/field_names.hpp"
#include "tasks/episode.hpp"
#include "voxels/grid_fields.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::keyframes {
namespace {

// A keyframe lies within half a voxel of depth d-1's voxel centre (per axis), and crop
// augmentation moves depth d's grid by up to a fraction f of its half edge: a grid too small
// for both would miss the keyframe, whose index is then clamped to the grid's face, and train
// depth d on a voxel the keyframe is not in. Throws UsageError then.
void check_crop_augmentation(const TransitionOptions& options) {
  if (!options.crop_augmentation) return;
  const voxels::CoarseToFine& h = options.hierarchy;
  const double f = options.crop_shift_fraction;
  for (int d = 1; d < h.depths; ++d) {
    const double half_voxel = 0.5 * h.bounds_at(d - 1, Eigen::Vector3d::Zero()).voxel_size_m();
    if (half_voxel + f * h.offset_at(d) <= h.offset_at(d) * (1 + 1e-9)) continue;
    std::ostringstream s;
    s.precision(3);
    s << "--offset: depth " << d << "'s half edge " << h.offset_at(d) << " m is too small for crop augmentation: "
      << "its grid moves by up to " << f * h.offset_at(d) << " m and a keyframe lies up to " << half_voxel
      << " m from depth " << d - 1 << "'s voxel centre, so it could fall outside the grid; use a half edge of at least "
      << half_voxel / (1 - f) << " m or --no-crop-augmentation";
    throw UsageError(s.str());
  }
}

// FNV-1a: a stable 64-bit key for an episode from what identifies it.
uint64_t fnv1a(const void* data, std::size_t n, uint64_t h = 1469598103934665603ull) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

Eigen::Isometry3d gripper_pose(const stream::Record& obs) {
  const auto p = obs.array<double>(fields::gripper_pose);
  if (p.size() != robot::kPoseValues) obs.fail(fields::gripper_pose, "float64 [7]");
  const double norm = std::sqrt(p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6]);
  for (int i = 0; i < robot::kPoseValues; ++i)
    if (!std::isfinite(p[i])) obs.fail(fields::gripper_pose, "finite position and quaternion");
  if (!(norm > 0.5 && norm < 1.5))
    obs.fail(fields::gripper_pose, "a unit quaternion (x, y, z, w), got norm " + std::to_string(norm));
  return robot::pose_from_values(p.data);
}

// The episode's key: what identifies it, hashed (frames refer to it across appended files).
int64_t episode_key_of(const std::vector<stream::Record>& episode, uint64_t seed) {
  const std::string task = episode[0].has(fields::task) ? episode[0].string(fields::task) : "";
  uint64_t key = fnv1a(task.data(), task.size());
  const int64_t episode_seed =
      episode[0].has(fields::episode_seed) ? episode[0].scalar<int64_t>(fields::episode_seed) : 0;
  const auto last_pose = episode.back().array<double>(fields::gripper_pose);
  key = fnv1a(&episode_seed, sizeof episode_seed, key);
  key = fnv1a(last_pose.data, 7 * sizeof(double), key);
  return static_cast<int64_t>(derive_seed(key, seed));
}

}  // namespace

std::string ConversionCounts::summary() const {
  std::string s = std::to_string(converted) + "/" + std::to_string(episodes) + " episodes converted, " +
                  std::to_string(frames) + " frames, " + std::to_string(transitions) + " transitions";
  const std::pair<const char*, int> skips[] = {{"empty", skipped_empty},
                                               {"unsuccessful", skipped_failed},
                                               {"without keyframes", skipped_no_keyframes},
                                               {"with frames out of order", skipped_out_of_order},
                                               {"with a keyframe outside the scene bounds", skipped_outside_bounds}};
  for (const auto& [what, n] : skips)
    if (n > 0) s += "; skipped " + std::to_string(n) + " " + what;
  return s;
}

AgentEpisodeConverter::AgentEpisodeConverter(TransitionOptions options) : options_(std::move(options)) {}

void AgentEpisodeConverter::handle(const stream::Record& record, const stream::Emit& emit) {
  if (record.type() == record_type::obs) {
    if (!observations_.empty() && record.scalar<int32_t>(fields::step) == 0) convert(emit);  // a new episode
    observations_.push_back(record);
    if (record.scalar<uint8_t>(fields::terminal) != 0) convert(emit);
  } else if (record.type() == record_type::action && !observations_.empty()) {
    if (actions_.size() + 1 != observations_.size())
      throw StreamError(record.position, "'action' record without an observation of its own before it");
    actions_.push_back(record);
  }
}

void AgentEpisodeConverter::finish(const stream::Emit& emit) {
  if (!observations_.empty()) convert(emit);  // unfinished: its complete steps are still experience
}

void AgentEpisodeConverter::convert(const stream::Emit& emit) {
  counts_.episodes += 1;
  const std::size_t steps = std::min(actions_.size(), observations_.size() - 1);
  if (steps == 0) {
    counts_.skipped_empty += 1;
  } else {
    const int64_t episode_key = episode_key_of(observations_, options_.seed);
    const voxels::CoarseToFine& h = options_.hierarchy;
    for (std::size_t t = 0; t < steps; ++t) {
      const stream::Record &obs = observations_[t], &action = actions_[t], &next = observations_[t + 1];
      stream::Record r(record_type::transition);
      r.set_scalar<int64_t>(fields::episode_key, episode_key);
      r.set_scalar<int32_t>(fields::frame, obs.scalar<int32_t>(fields::frame));
      r.set_scalar<int32_t>(fields::next_frame, next.scalar<int32_t>(fields::frame));
      r.set_scalar<int32_t>(fields::step, obs.scalar<int32_t>(fields::step));
      r.set_scalar<int32_t>(fields::voxels, h.voxels());
      for (int d = 0; d < h.depths; ++d) {
        const auto index = action.array<int32_t>(fields::depth_field(d, fields::per_depth::index));
        const auto bounds = action.array<double>(fields::depth_field(d, fields::per_depth::bounds));
        if (index.size() != 3) action.fail(fields::depth_field(d, fields::per_depth::index), "int32 [3]");
        if (bounds.size() != 4) action.fail(fields::depth_field(d, fields::per_depth::bounds), "float64 [4]");
        for (int axis = 0; axis < 3; ++axis)
          if (index[axis] < 0 || index[axis] >= h.voxels())
            action.fail(fields::depth_field(d, fields::per_depth::index),
                        "indices in 0.." + std::to_string(h.voxels() - 1) + " (--voxels)");
        action.require_finite(fields::depth_field(d, fields::per_depth::bounds));
        if (!(bounds[3] > 0))
          action.fail(fields::depth_field(d, fields::per_depth::bounds),
                      "a positive edge length (x, y, z, size in metres)");
        r.add(action.field(fields::depth_field(d, fields::per_depth::index)));
        r.add(action.field(fields::depth_field(d, fields::per_depth::bounds)));
      }
      if (action.has(fields::depth_field(h.depths, fields::per_depth::index)))
        action.fail(fields::depth_field(h.depths, fields::per_depth::index),
                    "no more than " + std::to_string(h.depths) + " depths (--depths)");
      r.add(action.field(fields::rotation_bins));
      r.set_scalar<uint8_t>(fields::gripper_open,
                            action.has(fields::gripper_open) ? action.scalar<uint8_t>(fields::gripper_open) : 1);
      r.set_scalar<uint8_t>(fields::ignore_collisions, action.has(fields::ignore_collisions)
                                                           ? action.scalar<uint8_t>(fields::ignore_collisions)
                                                           : 0);
      const auto pose = action.array<double>(fields::pose);
      if (pose.size() != robot::kPoseValues) action.fail(fields::pose, "float64 [7]");
      action.require_finite(fields::pose);
      next.require_finite(fields::reward);
      r.set<double>(fields::target_pose, {robot::kPoseValues}, pose.data);
      r.set_scalar<float>(fields::reward, next.scalar<float>(fields::reward));
      r.set_scalar<uint8_t>(fields::terminal, next.scalar<uint8_t>(fields::terminal));
      r.set_scalar<uint8_t>(fields::demo, 0);
      if (t == 0) emit(frame_record(obs, episode_key));
      emit(frame_record(next, episode_key));
      counts_.frames += t == 0 ? 2 : 1;
      emit(r);
      counts_.transitions += 1;
    }
    counts_.converted += 1;
  }
  observations_.clear();
  actions_.clear();
}

stream::Record frame_record(const stream::Record& obs, int64_t episode_key) {
  stream::Record frame(record_type::frame);
  frame.set_scalar<int64_t>(fields::episode_key, episode_key);
  frame.set_scalar<int32_t>(fields::frame, obs.scalar<int32_t>(fields::frame));
  for (const auto& field : obs.fields()) {
    const std::string& name = field.name();
    if (stream::ends_with(name, fields::per_camera::rgb)) {
      stream::Field rgb = field;  // read compressed: its zstd frame is written as it came
      rgb.compress = true;
      frame.add(rgb);
    } else if (stream::ends_with(name, fields::per_camera::depth)) {
      // Millimetres in 16 bits: 0.5 mm rounding, far below a 1.9 cm voxel, half the bytes.
      const auto depth = obs.array<float>(name);
      const std::string camera = name.substr(0, name.size() - std::strlen(fields::per_camera::depth));
      frame.set<uint16_t>(camera + fields::per_camera::depth_mm, depth.shape,
                          voxels::depth_in_mm(depth.data, depth.size()), /*compress=*/true);
    } else if (stream::ends_with(name, fields::per_camera::depth_mm)) {  // a depth camera's own millimetres (obs-pack)
      stream::Field mm = field;
      mm.compress = true;
      frame.add(mm);
    } else if (stream::ends_with(name, fields::per_camera::intrinsics) ||
               stream::ends_with(name, fields::per_camera::extrinsics)) {
      frame.add(field);
    }
  }
  for (const char* name : {fields::joint_positions, fields::gripper_pose, fields::gripper_open,
                           fields::gripper_opening_m, fields::episode_length, fields::task, fields::variation})
    if (obs.has(name)) frame.add(obs.field(name));
  // Nothing non-finite reaches the replay: every real value kept is checked at its source
  // (depth is stored as millimetres, where no return is 0).
  for (const auto& field : frame.fields())
    if (field.dtype() == stream::DType::f32 || field.dtype() == stream::DType::f64) obs.require_finite(field.name());
  for (const std::string& camera : obs.prefixes(fields::per_camera::extrinsics))
    voxels::check_camera_matrices(obs, camera);
  return frame;
}

EpisodeConverter::EpisodeConverter(TransitionOptions options) : options_(std::move(options)), rng_(options_.seed) {
  check_crop_augmentation(options_);
}

void EpisodeConverter::handle(const stream::Record& record, const stream::Emit& emit) {
  if (record.type() == record_type::episode) {
    convert(episode_, &record, emit);
    episode_.clear();
  } else if (record.type() == record_type::obs) {
    if (!episode_.empty() && record.scalar<int32_t>(fields::frame) == 0) {
      convert(episode_, nullptr, emit);
      episode_.clear();
    }
    episode_.push_back(record);
  }
}

void EpisodeConverter::finish(const stream::Emit& emit) {
  if (!episode_.empty()) convert(episode_, nullptr, emit);
  episode_.clear();
}

std::vector<int> EpisodeConverter::usable_keyframes(const std::vector<stream::Record>& episode,
                                                    const stream::Record* summary, bool& success) {
  if (episode.size() < 2) {
    counts_.skipped_empty += 1;
    return {};
  }
  for (std::size_t i = 1; i < episode.size(); ++i)
    if (episode[i].scalar<int32_t>(fields::frame) != episode[i - 1].scalar<int32_t>(fields::frame) + 1) {
      counts_.skipped_out_of_order += 1;
      return {};
    }
  success =
      summary ? summary->scalar<uint8_t>(fields::success) != 0 : episode.back().scalar<uint8_t>(fields::success) != 0;
  if (!success && !options_.keep_failed) {
    counts_.skipped_failed += 1;
    return {};
  }
  std::vector<FrameState> states;
  for (const auto& obs : episode) {
    FrameState s;
    s.gripper_open = obs.scalar<uint8_t>(fields::gripper_open) != 0;
    const auto v = obs.array<double>(fields::joint_velocities);
    if (v.size() != 7) obs.fail(fields::joint_velocities, "float64 [7]");
    std::copy(v.begin(), v.end(), s.joint_velocities.begin());
    states.push_back(s);
  }
  const std::vector<int> keyframes = discover_keyframes(states, options_.stopping_delta);
  if (keyframes.empty()) {
    counts_.skipped_no_keyframes += 1;
    return {};
  }
  const voxels::GridBounds& scene = options_.hierarchy.scene;
  for (int k : keyframes)
    if (!scene.contains(scene.index_of(gripper_pose(episode[k]).translation()))) {
      counts_.skipped_outside_bounds += 1;
      return {};
    }
  return keyframes;
}

void EpisodeConverter::convert(std::vector<stream::Record>& episode, const stream::Record* summary,
                               const stream::Emit& emit) {
  counts_.episodes += 1;
  bool success = false;
  const std::vector<int> keyframes = usable_keyframes(episode, summary, success);
  if (keyframes.empty()) return;
  const int64_t episode_key = episode_key_of(episode, options_.seed);

  // Chains: from frame 0 and every n-th frame before the last keyframe, through the
  // keyframes after it. Each frame is stored once, before the first transition that uses it.
  std::vector<int> starts = {0};
  if (options_.augmentation_every_n > 0)
    for (int i = options_.augmentation_every_n; i < keyframes.back(); i += options_.augmentation_every_n) starts.push_back(i);
  std::set<int> stored;
  auto store = [&](int i) {
    if (stored.insert(i).second) {
      emit(frame_record(episode[i], episode_key));
      counts_.frames += 1;
    }
  };
  for (int start : starts) {
    int previous = start, step = 0;
    for (int k : keyframes) {
      if (k <= start) {  // a keyframe the chain starts after: the agent's step there counts it
        if (options_.chain_steps == ChainSteps::episode) ++step;
        continue;
      }
      const stream::Record t = transition(episode, previous, k, step, episode_key, k == keyframes.back(), success);
      store(previous);
      store(k);
      emit(t);
      counts_.transitions += 1;
      previous = k;
      ++step;
    }
  }
  counts_.converted += 1;
}

// The transition from frame `from` to keyframe `to`: the target's voxel at every depth (the
// deeper grids' centres shifted at random with crop augmentation), rotation bins, gripper; the
// success reward on the last keyframe of a successful episode.
stream::Record EpisodeConverter::transition(const std::vector<stream::Record>& episode, int from, int to, int step,
                                            int64_t episode_key, bool last, bool success) {
  const voxels::CoarseToFine& h = options_.hierarchy;
  const stream::Record& target = episode[to];
  const Eigen::Isometry3d pose = gripper_pose(target);
  std::uniform_real_distribution<double> shift(-options_.crop_shift_fraction, options_.crop_shift_fraction);
  std::vector<Eigen::Vector3d> shifts(h.depths, Eigen::Vector3d::Zero());
  if (options_.crop_augmentation)
    for (int d = 1; d < h.depths; ++d)  // a fraction of depth d's own half edge
      shifts[d] = Eigen::Vector3d(shift(rng_), shift(rng_), shift(rng_)) * h.offset_at(d);
  const auto indices = h.indices_of(pose.translation(), shifts);

  stream::Record t(record_type::transition);
  t.set_scalar<int64_t>(fields::episode_key, episode_key);
  t.set_scalar<int32_t>(fields::frame, episode[from].scalar<int32_t>(fields::frame));
  t.set_scalar<int32_t>(fields::next_frame, target.scalar<int32_t>(fields::frame));
  t.set_scalar<int32_t>(fields::step, step);
  t.set_scalar<int32_t>(fields::voxels, h.voxels());
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int d = 0; d < h.depths; ++d) {
    if (d > 0) centre += shifts[d];
    const voxels::GridBounds b = h.bounds_at(d, centre);
    t.set<int32_t>(fields::depth_field(d, fields::per_depth::index), {3}, indices[d].data());
    t.set<double>(fields::depth_field(d, fields::per_depth::bounds), {4}, voxels::bounds_values(b));
    centre = b.centre_of(indices[d]);
  }
  const Eigen::Vector3i bins = robot::rotation_bins(pose.linear());
  t.set<int32_t>(fields::rotation_bins, {3}, bins.data());
  t.set_scalar<uint8_t>(fields::gripper_open, target.scalar<uint8_t>(fields::gripper_open));
  t.set_scalar<uint8_t>(fields::ignore_collisions,
                        target.has(fields::ignore_collisions) ? target.scalar<uint8_t>(fields::ignore_collisions) : 0);
  t.set<double>(fields::target_pose, {robot::kPoseValues}, robot::pose_values(pose));
  t.set_scalar<float>(fields::reward, last && success ? tasks::kSuccessReward : 0.0f);
  t.set_scalar<uint8_t>(fields::terminal, last);
  t.set_scalar<uint8_t>(fields::demo, options_.demo);
  return t;
}

}  // namespace qte::keyframes
