// An agent without networks: it acts with demonstrated keyframes as keyframe(1) discretized
// them for the learner, the voxels, rotation bins and gripper commands the networks are trained
// to choose. Run in the acting loop on the demonstrations' own scenes, it is the discretized
// expert acting open-loop: a reference for what this grid, planner and task allow (the
// ceiling of learning, qte-select --keyframes), not a strict bound on a network, which acts
// closed-loop and may retry.
#pragma once

#include <string>
#include <vector>

#include "qattention/tree_expansion.hpp"
#include "stream/field_names.hpp"
#include "stream/stage.hpp"

namespace qte::qattention {

// Per demonstration, in the order of the file: its keyframes' actions (the voxel per depth, its
// grid's bounds, the rotation bins, the gripper; not the expert's ignore_collisions, which the
// networks never choose), in order: the chain of transitions from frame 0 to the terminal one
// (demo augmentation's chains from the frames between keyframes are left out). Fails naming
// the file, record and byte offset on anything else (a chain that breaks off).
std::vector<std::vector<Choice>> demonstrated_keyframes(const std::string& transitions_path);

// Every record passes through; after each non-terminal 'obs' an 'action' record: the n-th
// episode of the input (an observation with step 0 starts one) takes demonstration n, step s
// its keyframe s, the last one again after its end.
class KeyframeStage : public stream::Stage {
 public:
  // `ignore_collisions`: every action's, as qte-select --ignore-collisions sets it for networks.
  // `rotation_offset`: bins added to every keyframe's rotation bins (wrapped around), a
  // rotation error of the same size in every action: how precise a task needs its rotations.
  KeyframeStage(std::vector<std::vector<Choice>> demonstrations, std::string source, bool ignore_collisions,
                Eigen::Vector3i rotation_offset = Eigen::Vector3i::Zero());
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::obs}; }

 private:
  std::vector<std::vector<Choice>> demonstrations_;
  std::string source_;
  bool ignore_collisions_;
  Eigen::Vector3i rotation_offset_;
  int64_t episode_ = -1;
};

}  // namespace qte::qattention
