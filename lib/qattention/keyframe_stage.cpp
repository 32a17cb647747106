#include "qattention/keyframe_stage.hpp"

#include <map>
#include <utility>

#include "common/error.hpp"
#include "qattention/action_record.hpp"
#include "stream/reader.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::qattention {

namespace {

KeyframeAction keyframe_action(const stream::Record& t) {
  KeyframeAction a;
  const int voxels = t.scalar<int32_t>("voxels");
  for (int d = 0; t.has("depth" + std::to_string(d) + ".index"); ++d) {
    const std::string prefix = "depth" + std::to_string(d);
    const auto index = t.array<int32_t>(prefix + ".index");
    if (index.size() != 3) t.fail(prefix + ".index", "int32 [3]");
    a.indices.emplace_back(index[0], index[1], index[2]);
    a.bounds.push_back(voxels::bounds_field(t, prefix + ".bounds", voxels));
    if (!a.bounds.back().contains(a.indices.back())) t.fail(prefix + ".index", "a voxel of its grid");
    a.q_values.push_back(0);
  }
  if (a.indices.empty()) t.fail("depth0.index", "int32 [3]: a transition as keyframe(1) writes it");
  const auto bins = t.array<int32_t>("rotation_bins");
  if (bins.size() != 3) t.fail("rotation_bins", "int32 [3]");
  a.rotation_bins = Eigen::Vector3i(bins[0], bins[1], bins[2]);
  a.gripper_open = t.scalar<uint8_t>("gripper_open") != 0;
  return a;
}

}  // namespace

std::vector<std::vector<KeyframeAction>> demonstrated_keyframes(const std::string& transitions_path) {
  // Per episode (in the order of its first transition): each transition by the frame it starts from.
  std::vector<int64_t> order;
  std::map<int64_t, std::map<int32_t, stream::Record>> episodes;
  stream::RecordReader reader(transitions_path);
  while (auto record = reader.next()) {
    if (record->type() != "transition") continue;
    const int64_t key = record->scalar<int64_t>("episode_key");
    if (!episodes.count(key)) order.push_back(key);
    const int32_t frame = record->scalar<int32_t>("frame");
    episodes[key].insert_or_assign(frame, std::move(*record));
  }
  if (order.empty()) throw Error(transitions_path + ": no 'transition' records: expected keyframe(1)'s output");
  std::vector<std::vector<KeyframeAction>> demonstrations;
  for (int64_t key : order) {
    auto& by_frame = episodes[key];
    std::vector<KeyframeAction> chain;
    // From the first frame along next_frame to the terminal transition: the keyframes.
    auto it = by_frame.find(0);
    if (it == by_frame.end()) by_frame.begin()->second.fail("frame", "a transition from frame 0 (the episode's first)");
    while (true) {
      const stream::Record& t = it->second;
      chain.push_back(keyframe_action(t));
      if (t.scalar<uint8_t>("terminal") != 0) break;
      if (chain.size() > by_frame.size()) t.fail("next_frame", "a chain of keyframes that ends (this one loops)");
      it = by_frame.find(t.scalar<int32_t>("next_frame"));
      if (it == by_frame.end())
        t.fail("next_frame", "a frame with a transition from it, up to a terminal one (the chain breaks off here)");
    }
    demonstrations.push_back(std::move(chain));
  }
  return demonstrations;
}

KeyframeStage::KeyframeStage(std::vector<std::vector<KeyframeAction>> demonstrations, std::string source,
                             bool ignore_collisions)
    : demonstrations_(std::move(demonstrations)), source_(std::move(source)), ignore_collisions_(ignore_collisions) {}

void KeyframeStage::handle(const stream::Record& record, const stream::Emit& emit) {
  emit(record);
  if (record.type() != "obs") return;
  if (record.has("terminal") && record.scalar<uint8_t>("terminal") != 0) return;
  const int32_t step = record.scalar<int32_t>("step");
  if (step < 0) record.fail("step", "a step of 0 or more");
  if (step == 0) episode_ += 1;
  if (episode_ < 0) record.fail("step", "0 at an episode's first observation");
  if (episode_ >= static_cast<int64_t>(demonstrations_.size()))
    record.fail("step", "at most " + std::to_string(demonstrations_.size()) + " episodes: " + source_ + " holds " +
                            std::to_string(demonstrations_.size()) + " demonstrations");
  const auto& keyframes = demonstrations_[episode_];
  const KeyframeAction& a = keyframes[std::min<std::size_t>(step, keyframes.size() - 1)];
  emit(action_record(a, ignore_collisions_, 1, false, -1, step));
}

}  // namespace qte::qattention
