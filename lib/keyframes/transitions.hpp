// Demonstrations to replay transitions, as C2F-ARM builds them: keyframes of each episode,
// chains started at every n-th frame (demo augmentation), and per transition the action of
// the next keyframe: coarse-to-fine voxel indices (with crop augmentation), rotation bins,
// gripper state. Observations are stored once, compactly, as 'frame' records; transitions
// refer to them.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "stream/field_names.hpp"
#include "stream/record.hpp"
#include "stream/stage.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::keyframes {

// The step a demo-augmentation chain counts from, and so the time input of its samples
// (proprioception's time, 1 - 2 step / (episode length - 1)). `reset`, the published code's:
// every chain from 0, so a chain started mid-episode is trained with the time of an episode's
// first step. `episode`: from the number of keyframes at or before the chain's first frame,
// the step an agent acting in that phase is at, so training and acting agree on time.
enum class ChainSteps { reset, episode };

struct TransitionOptions {
  voxels::CoarseToFine hierarchy;
  int augmentation_every_n = 10;  // 0: chains only from the first frame
  ChainSteps chain_steps = ChainSteps::reset;
  bool crop_augmentation = true;
  double crop_shift_fraction = 0.75;  // of the offset, per axis, uniform
  double stopping_delta = 0.1;
  bool keep_failed = false;  // transitions from unsuccessful episodes too (reward 0)
  bool demo = true;          // mark transitions as demonstrations
  uint64_t seed = 0;
};

// What happened to the episodes given to an EpisodeConverter, for the report on stderr.
struct ConversionCounts {
  int episodes = 0, converted = 0;
  int skipped_empty = 0, skipped_failed = 0, skipped_no_keyframes = 0, skipped_out_of_order = 0,
      skipped_outside_bounds = 0;
  int64_t frames = 0, transitions = 0;
  std::string summary() const;
};

class EpisodeConverter : public stream::Stage {
 public:
  // Throws UsageError when crop augmentation could move a deeper grid off its keyframe (offsets
  // too small for options.crop_shift_fraction).
  explicit EpisodeConverter(TransitionOptions options);

  // Feed a demonstration stream record by record: obs records gather into an episode, which
  // ends at an 'episode' record or at an obs with frame 0; finish() converts the last one.
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::obs}; }
  void finish(const stream::Emit& emit) override;
  const ConversionCounts& counts() const { return counts_; }

 private:
  // The steps of converting one episode: its keyframes and success (no keyframes when the
  // episode is skipped, the reason counted), then each transition of its chains.
  std::vector<int> usable_keyframes(const std::vector<stream::Record>& episode, const stream::Record* summary,
                                    bool& success);
  void convert(std::vector<stream::Record>& episode, const stream::Record* summary, const stream::Emit& emit);
  stream::Record transition(const std::vector<stream::Record>& episode, int from, int to, int step, int64_t episode_key,
                            bool last, bool success);

  TransitionOptions options_;
  std::vector<stream::Record> episode_;
  ConversionCounts counts_;
  std::mt19937_64 rng_;
};

// The agent's own episodes to transitions: the stream of the learning loop (sim-step's
// observations with qte-select's action after each non-terminal one) gives one transition per
// action, from the observation it was chosen for to the one it led to, with that one's reward
// and terminal flag. The action's own per-depth indices and bounds are kept as chosen (so
// exploration is learned from as it happened). Unsuccessful episodes are kept: they are the
// agent's experience. Episodes end at a terminal observation or at an obs with step 0.
class AgentEpisodeConverter : public stream::Stage {
 public:
  explicit AgentEpisodeConverter(TransitionOptions options);
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::obs}; }
  void finish(const stream::Emit& emit) override;
  const ConversionCounts& counts() const { return counts_; }

 private:
  void convert(const stream::Emit& emit);

  TransitionOptions options_;
  std::vector<stream::Record> observations_, actions_;  // actions_[t] was chosen for observations_[t]
  ConversionCounts counts_;
};

// The compact 'frame' record of an observation: images (rgb; depth as uint16 millimetres,
// zstd-compressed), camera matrices and proprioception, keyed by (episode_key, frame).
stream::Record frame_record(const stream::Record& obs, int64_t episode_key);

}  // namespace qte::keyframes
