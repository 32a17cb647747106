// A sum tree over non-negative priorities: O(log n) update and proportional sampling, the
// data structure of prioritised experience replay.
#pragma once

#include <cstddef>
#include <vector>

namespace qte::replay {

class SumTree {
 public:
  explicit SumTree(std::size_t capacity = 0);

  std::size_t capacity() const { return capacity_; }
  void resize(std::size_t capacity);  // keeps existing priorities
  void set(std::size_t index, double priority);
  double get(std::size_t index) const { return nodes_[leaf_offset_ + index]; }
  double total() const { return nodes_.empty() ? 0.0 : nodes_[1]; }
  double max() const { return max_; }  // largest priority ever set (new items start with it)
  void restore_max(double max) { max_ = max; }  // a resumed run's
  // The index whose cumulative range holds `mass` (0 <= mass < total()).
  std::size_t find(double mass) const;

 private:
  std::size_t capacity_ = 0, leaf_offset_ = 1;
  std::vector<double> nodes_;  // 1-based heap; leaves from leaf_offset_
  double max_ = 1.0;
};

}  // namespace qte::replay
