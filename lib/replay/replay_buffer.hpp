// The learner's replay: frames (observations stored once) and the transitions that refer to
// them, with prioritised sampling (priority = (|TD error| + eps)^alpha, importance weights
// (N * P(i))^-beta normalised by their maximum) or uniform sampling, over all transitions or
// with a fixed share of each batch from the demonstrations. Demonstrations are kept for good;
// when full, the oldest of the agent's own transitions makes room.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "replay/sum_tree.hpp"
#include "stream/record.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::replay {

struct ReplayOptions {
  std::size_t capacity = 100000;  // transitions
  bool prioritised = true;
  double alpha = 0.7;
  double priority_epsilon = 1e-3;
  // Memory for the frames' point clouds, each computed the first time one of its transitions is
  // sampled and kept while the frame is in the replay; past it, a frame's cloud is computed at
  // every use (0: none kept).
  std::size_t cloud_memory_bytes = std::size_t{2048} << 20;
};

struct Sample {
  std::vector<std::size_t> indices;
  std::vector<double> weights;  // importance weights, max 1 (all 1 when uniform)
};

class ReplayBuffer {
 public:
  explicit ReplayBuffer(ReplayOptions options = {});

  // Takes 'frame' and 'transition' records (others are ignored). A transition must follow
  // the frames it refers to: otherwise a StreamError names it. Returns true if it was kept.
  bool add(const stream::Record& record);

  std::size_t size() const { return transitions_.size(); }
  std::size_t demo_count() const { return demos_; }
  std::size_t frame_count() const { return frames_.size(); }

  // One draw over all transitions; or, with demo_share > 0 while the replay holds both kinds,
  // round(demo_share * batch) of the batch from the demonstrations and the rest from the
  // agent's transitions (demonstrations first), each part sampled and importance-weighted
  // within its own kind as if it were a replay of its own; weights normalised over the batch.
  // (A uniform replay's parts are then stratified over their kind, all weights 1.)
  Sample sample(std::size_t batch, double beta, std::mt19937_64& rng, double demo_share = 0) const;
  void update_priorities(const std::vector<std::size_t>& indices, const std::vector<double>& td_errors);
  double priority(std::size_t index) const { return tree_.get(index); }
  // Every transition's priority, in index order, and back (a learner's checkpoint).
  std::vector<double> priorities() const;
  // The largest priority ever set, which new transitions start with: a resumed run must
  // restore it as well for new transitions to be sampled as in an uninterrupted run.
  double max_priority() const { return tree_.max(); }
  void restore_priorities(const std::vector<double>& priorities, double max_priority);

  const stream::Record& transition(std::size_t index) const { return transitions_.at(index).record; }
  // The observation a transition acts on, and the one it reaches.
  const stream::Record& frame_of(std::size_t index) const;
  const stream::Record& next_frame_of(std::size_t index) const;
  // Their point clouds (voxels::observation_cloud), kept within ReplayOptions::cloud_memory_bytes.
  std::shared_ptr<const voxels::ObservationCloud> cloud_of(std::size_t index) const;
  std::shared_ptr<const voxels::ObservationCloud> next_cloud_of(std::size_t index) const;
  std::size_t cloud_memory_used() const { return cloud_bytes_; }
  // The transition that continues `index`'s chain, if the replay holds one: what n-step
  // returns follow. It acts on the observation `index` reaches, one step later; chains that
  // share a frame at another step (demo augmentation starts chains at several frames) are
  // others.
  std::optional<std::size_t> successor_of(std::size_t index) const;

 private:
  using FrameKey = std::pair<int64_t, int32_t>;  // (episode_key, frame)
  using ChainKey = std::pair<FrameKey, int32_t>;  // (frame acted on, step of the chain)
  struct Stored {
    stream::Record record;
    FrameKey frame, next_frame;
    int32_t step = 0;
    bool demo = false;
  };
  void release(const FrameKey& key);
  void set_priority(std::size_t index, double priority);
  void draw(const SumTree& kind, std::size_t count, std::size_t kind_size, double beta, std::mt19937_64& rng,
            Sample& into) const;
  std::shared_ptr<const voxels::ObservationCloud> cloud_of_frame(const FrameKey& key) const;

  ReplayOptions options_;
  std::vector<Stored> transitions_;
  std::map<FrameKey, std::pair<stream::Record, int>> frames_;  // frame and its reference count
  // Point clouds kept so far (filled as frames are sampled: sampling is a const operation).
  mutable std::map<FrameKey, std::shared_ptr<const voxels::ObservationCloud>> clouds_;
  mutable std::size_t cloud_bytes_ = 0;
  std::map<ChainKey, std::size_t> acting_on_;  // the newest transition acting on each frame at each step
  SumTree tree_;
  // The same priorities split by kind, each zero at the other kind's slots (for demo_share).
  SumTree demo_tree_, agent_tree_;
  std::size_t demos_ = 0;
  std::size_t next_evicted_ = 0;  // ring position among the agent's transitions
};

}  // namespace qte::replay
