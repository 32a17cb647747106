// An agent without networks: it acts with demonstrated keyframes as keyframe(1) discretized
// them for the learner, the actions the networks are trained to choose. Run in the acting loop
// on the demonstrations' own scenes, it measures what a network could reach at best on this
// grid, planner and task: the ceiling of learning (qte-select --keyframes).
#pragma once

#include <string>
#include <vector>

#include "qattention/tree_expansion.hpp"
#include "stream/stage.hpp"

namespace qte::qattention {

struct KeyframeAction {
  Choice choice;  // the voxel per depth, its grid's bounds, the rotation bins, the gripper
  bool ignore_collisions = false;
};

// Per demonstration, in the order of the file: its keyframes' actions, in order (the chain of
// transitions from frame 0 along next_frame; demo augmentation's transitions from the frames
// between keyframes are left out). Fails naming the file on anything else.
std::vector<std::vector<KeyframeAction>> demonstrated_keyframes(const std::string& transitions_path);

// Every record passes through; after each non-terminal 'obs' an 'action' record: the n-th
// episode of the input (an observation with step 0 starts one) takes demonstration n, step s
// its keyframe s, the last one again after its end.
class KeyframeStage : public stream::Stage {
 public:
  KeyframeStage(std::vector<std::vector<KeyframeAction>> demonstrations, std::string source);
  void handle(const stream::Record& record, const stream::Emit& emit) override;

 private:
  std::vector<std::vector<KeyframeAction>> demonstrations_;
  std::string source_;
  int64_t episode_ = -1;
};

}  // namespace qte::qattention
