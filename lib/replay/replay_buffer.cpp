#include "replay/replay_buffer.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "stream/field_names.hpp"

namespace qte::replay {
namespace {

std::size_t cloud_size_bytes(const voxels::ObservationCloud& cloud) {
  return cloud.xyz.size() * sizeof(float) + cloud.rgb.size() + sizeof(cloud);
}

}  // namespace

ReplayBuffer::ReplayBuffer(ReplayOptions options)
    : options_(options), tree_(options.capacity), demo_tree_(options.capacity), agent_tree_(options.capacity) {
  if (options_.capacity == 0) throw Error("replay capacity must be at least 1");
}

bool ReplayBuffer::add(const stream::Record& record) {
  if (record.type() == record_type::frame) {
    const FrameKey key{record.scalar<int64_t>(fields::episode_key), record.scalar<int32_t>(fields::frame)};
    auto it = frames_.find(key);
    if (it == frames_.end()) frames_.emplace(key, std::make_pair(record, 0));
    return true;
  }
  if (record.type() != record_type::transition) return false;
  Stored stored{record,
                {record.scalar<int64_t>(fields::episode_key), record.scalar<int32_t>(fields::frame)},
                {record.scalar<int64_t>(fields::episode_key), record.scalar<int32_t>(fields::next_frame)},
                record.has(fields::step) ? record.scalar<int32_t>(fields::step) : 0,
                record.has(fields::demo) && record.scalar<uint8_t>(fields::demo) != 0};
  for (const FrameKey* key : {&stored.frame, &stored.next_frame})
    if (!frames_.count(*key))
      throw StreamError(record.position, "transition refers to frame " + std::to_string(key->second) +
                                             " of episode " + std::to_string(key->first) +
                                             ", which no 'frame' record before it holds");
  // Count the new references first: the transition evicted below may share a frame.
  frames_.at(stored.frame).second += 1;
  frames_.at(stored.next_frame).second += 1;
  std::size_t slot = transitions_.size();
  if (transitions_.size() == options_.capacity) {
    // Full: replace the oldest of the agent's transitions; with only demos, keep what we have.
    std::size_t checked = 0;
    while (checked < transitions_.size() && transitions_[next_evicted_].demo) {
      next_evicted_ = (next_evicted_ + 1) % transitions_.size();
      ++checked;
    }
    if (checked == transitions_.size()) {
      release(stored.frame);
      release(stored.next_frame);
      return false;
    }
    slot = next_evicted_;
    next_evicted_ = (next_evicted_ + 1) % transitions_.size();
    const auto acting = acting_on_.find({transitions_[slot].frame, transitions_[slot].step});
    if (acting != acting_on_.end() && acting->second == slot) acting_on_.erase(acting);
    release(transitions_[slot].frame);
    release(transitions_[slot].next_frame);
    demos_ -= transitions_[slot].demo;
  }
  demos_ += stored.demo;
  acting_on_[{stored.frame, stored.step}] = slot;
  if (slot == transitions_.size()) transitions_.push_back(std::move(stored));
  else transitions_[slot] = std::move(stored);
  set_priority(slot, options_.prioritised ? tree_.max() : 1.0);  // new: sampled at least once soon
  return true;
}

void ReplayBuffer::set_priority(std::size_t index, double priority) {
  tree_.set(index, priority);
  const bool demo = transitions_[index].demo;
  (demo ? demo_tree_ : agent_tree_).set(index, priority);
  (demo ? agent_tree_ : demo_tree_).set(index, 0.0);  // a slot may change kind when an agent's is replaced
}

void ReplayBuffer::release(const FrameKey& key) {
  auto it = frames_.find(key);
  if (it == frames_.end() || --it->second.second > 0) return;
  frames_.erase(it);
  const auto cloud = clouds_.find(key);
  if (cloud == clouds_.end()) return;
  cloud_bytes_ -= cloud_size_bytes(*cloud->second);
  clouds_.erase(cloud);
}

std::shared_ptr<const voxels::ObservationCloud> ReplayBuffer::cloud_of_frame(const FrameKey& key) const {
  const auto kept = clouds_.find(key);
  if (kept != clouds_.end()) return kept->second;
  auto cloud = std::make_shared<const voxels::ObservationCloud>(voxels::observation_cloud(frames_.at(key).first));
  const std::size_t bytes = cloud_size_bytes(*cloud);
  if (cloud_bytes_ + bytes <= options_.cloud_memory_bytes) {
    clouds_.emplace(key, cloud);
    cloud_bytes_ += bytes;
  }
  return cloud;
}

std::shared_ptr<const voxels::ObservationCloud> ReplayBuffer::cloud_of(std::size_t index) const {
  return cloud_of_frame(transitions_.at(index).frame);
}

std::shared_ptr<const voxels::ObservationCloud> ReplayBuffer::next_cloud_of(std::size_t index) const {
  return cloud_of_frame(transitions_.at(index).next_frame);
}

Sample ReplayBuffer::sample(std::size_t batch, double beta, std::mt19937_64& rng, double demo_share) const {
  if (transitions_.empty()) throw Error("cannot sample from an empty replay");
  Sample s;
  const std::size_t agents = transitions_.size() - demos_;
  if (demo_share > 0 && demos_ > 0 && agents > 0) {
    const auto from_demos =
        std::min(batch, static_cast<std::size_t>(std::lround(demo_share * static_cast<double>(batch))));
    draw(demo_tree_, from_demos, demos_, beta, rng, s);
    draw(agent_tree_, batch - from_demos, agents, beta, rng, s);
  } else if (!options_.prioritised) {
    std::uniform_int_distribution<std::size_t> pick(0, transitions_.size() - 1);
    for (std::size_t i = 0; i < batch; ++i) s.indices.push_back(pick(rng));
    s.weights.assign(batch, 1.0);
    return s;
  } else {
    draw(tree_, batch, transitions_.size(), beta, rng, s);
  }
  if (!options_.prioritised) {
    s.weights.assign(s.indices.size(), 1.0);
    return s;
  }
  if (s.weights.empty()) return s;
  const double max_weight = *std::max_element(s.weights.begin(), s.weights.end());
  for (double& w : s.weights) w /= max_weight;
  return s;
}

// Stratified: one draw per equal slice of the kind's priority mass; weights (n P(i))^-beta
// within the kind, not yet normalised.
void ReplayBuffer::draw(const SumTree& kind, std::size_t count, std::size_t kind_size, double beta,
                        std::mt19937_64& rng, Sample& into) const {
  const double total = kind.total(), slice = total / static_cast<double>(count), n = static_cast<double>(kind_size);
  for (std::size_t i = 0; i < count; ++i) {
    const double mass = std::min(total * (1 - 1e-12), (i + std::uniform_real_distribution<double>(0, 1)(rng)) * slice);
    const std::size_t index = std::min(kind.find(mass), transitions_.size() - 1);
    into.indices.push_back(index);
    into.weights.push_back(std::pow(n * (kind.get(index) / total), -beta));  // as n * P(i), for the same bytes
  }
}

void ReplayBuffer::update_priorities(const std::vector<std::size_t>& indices, const std::vector<double>& td_errors) {
  if (!options_.prioritised) return;
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (!std::isfinite(td_errors[i])) throw Error("non-finite TD error for transition " + std::to_string(indices[i]));
    set_priority(indices[i], std::pow(std::abs(td_errors[i]) + options_.priority_epsilon, options_.alpha));
  }
}

std::vector<double> ReplayBuffer::priorities() const {
  std::vector<double> p(transitions_.size());
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = tree_.get(i);
  return p;
}

void ReplayBuffer::restore_priorities(const std::vector<double>& priorities, double max_priority) {
  if (priorities.size() != transitions_.size())
    throw Error("replay: " + std::to_string(priorities.size()) + " priorities for " +
                std::to_string(transitions_.size()) + " transitions");
  for (std::size_t i = 0; i < priorities.size(); ++i) {
    if (!(priorities[i] > 0) || !std::isfinite(priorities[i])) throw Error("replay: a priority is not positive");
    set_priority(i, priorities[i]);
  }
  if (!(max_priority > 0) || !std::isfinite(max_priority)) throw Error("replay: the largest priority is not positive");
  tree_.restore_max(max_priority);
}

const stream::Record& ReplayBuffer::frame_of(std::size_t index) const {
  return frames_.at(transitions_.at(index).frame).first;
}

const stream::Record& ReplayBuffer::next_frame_of(std::size_t index) const {
  return frames_.at(transitions_.at(index).next_frame).first;
}

std::optional<std::size_t> ReplayBuffer::successor_of(std::size_t index) const {
  const Stored& t = transitions_.at(index);
  const auto found = acting_on_.find({t.next_frame, t.step + 1});
  if (found == acting_on_.end()) return std::nullopt;
  return found->second;
}

}  // namespace qte::replay
