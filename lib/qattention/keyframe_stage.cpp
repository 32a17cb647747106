#include "qattention/keyframe_stage.hpp"

#include <optional>
#include <utility>

#include "common/error.hpp"
#include "qattention/action_record.hpp"
#include "replay/replay_buffer.hpp"
#include "robot/rotation_bins.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::qattention {

namespace {

Choice keyframe_action(const stream::Record& t) {
  Choice a;
  const int voxels = t.scalar<int32_t>(fields::voxels);
  for (int d = 0; t.has(fields::depth_field(d, fields::per_depth::index)); ++d) {
    const auto index = t.array<int32_t>(fields::depth_field(d, fields::per_depth::index));
    if (index.size() != 3) t.fail(fields::depth_field(d, fields::per_depth::index), "int32 [3]");
    a.indices.emplace_back(index[0], index[1], index[2]);
    a.bounds.push_back(voxels::bounds_field(t, fields::depth_field(d, fields::per_depth::bounds), voxels));
    if (!a.bounds.back().contains(a.indices.back()))
      t.fail(fields::depth_field(d, fields::per_depth::index), "a voxel of its grid");
    a.q_values.push_back(0);
  }
  if (a.indices.empty())
    t.fail(fields::depth_field(0, fields::per_depth::index), "int32 [3]: a transition as keyframe(1) writes it");
  const auto bins = t.array<int32_t>(fields::rotation_bins);
  if (bins.size() != 3) t.fail(fields::rotation_bins, "int32 [3]");
  a.rotation_bins = Eigen::Vector3i(bins[0], bins[1], bins[2]);
  a.gripper_open = t.scalar<uint8_t>(fields::gripper_open) != 0;
  return a;
}

}  // namespace

std::vector<std::vector<Choice>> demonstrated_keyframes(const std::string& transitions_path) {
  // The learner's replay follows the chains: sized to hold every transition, in file order.
  std::vector<stream::Record> records;
  std::size_t transitions = 0;
  stream::RecordReader reader(transitions_path);
  while (auto record = reader.next()) {
    if (record->type() != record_type::frame && record->type() != record_type::transition) continue;
    transitions += record->type() == record_type::transition;
    records.push_back(std::move(*record));
  }
  if (transitions == 0) throw Error(transitions_path + ": no 'transition' records: expected keyframe(1)'s output");
  replay::ReplayBuffer buffer({transitions, false});
  for (const stream::Record& record : records) buffer.add(record);
  records.clear();
  // A demonstration's chain starts at its first frame, step 0, and goes keyframe by keyframe
  // (successor_of) to its terminal transition; demo augmentation's chains start elsewhere.
  std::vector<std::vector<Choice>> demonstrations;
  for (std::size_t first = 0; first < buffer.size(); ++first) {
    const stream::Record& start = buffer.transition(first);
    if (start.scalar<int32_t>(fields::frame) != 0 || start.scalar<int32_t>(fields::step) != 0) continue;
    std::vector<Choice> chain;
    std::optional<std::size_t> t = first;
    while (true) {
      const stream::Record& transition = buffer.transition(*t);
      chain.push_back(keyframe_action(transition));
      if (transition.scalar<uint8_t>(fields::terminal) != 0) break;
      t = buffer.successor_of(*t);
      if (!t)
        transition.fail(fields::next_frame,
                        "a frame with a transition from it, up to a terminal one (the chain breaks off here)");
    }
    demonstrations.push_back(std::move(chain));
  }
  return demonstrations;
}

KeyframeStage::KeyframeStage(std::vector<std::vector<Choice>> demonstrations, std::string source,
                             bool ignore_collisions, Eigen::Vector3i rotation_offset)
    : demonstrations_(std::move(demonstrations)),
      source_(std::move(source)),
      ignore_collisions_(ignore_collisions),
      rotation_offset_(std::move(rotation_offset)) {}

void KeyframeStage::handle(const stream::Record& record, const stream::Emit& emit) {
  emit(record);
  if (record.type() != record_type::obs) return;
  if (record.has(fields::terminal) && record.scalar<uint8_t>(fields::terminal) != 0) return;
  const int32_t step = record.scalar<int32_t>(fields::step);
  if (step < 0) record.fail(fields::step, "a step of 0 or more");
  if (step == 0) episode_ += 1;
  if (episode_ < 0) record.fail(fields::step, "0 at an episode's first observation");
  if (episode_ >= static_cast<int64_t>(demonstrations_.size()))
    record.fail(fields::step, "at most " + std::to_string(demonstrations_.size()) + " episodes: " + source_ +
                                  " holds " + std::to_string(demonstrations_.size()) + " demonstrations");
  const auto& keyframes = demonstrations_[episode_];
  Choice a = keyframes[std::min<std::size_t>(step, keyframes.size() - 1)];
  for (int axis = 0; axis < 3; ++axis)
    a.rotation_bins[axis] = ((a.rotation_bins[axis] + rotation_offset_[axis]) % robot::kRotationBins + robot::kRotationBins) %
                            robot::kRotationBins;
  emit(action_record(a, ignore_collisions_, 1, false, -1, step));
}

}  // namespace qte::qattention
