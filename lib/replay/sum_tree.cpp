#include "replay/sum_tree.hpp"

#include <algorithm>

#include "common/error.hpp"

namespace qte::replay {

SumTree::SumTree(std::size_t capacity) { resize(capacity); }

void SumTree::resize(std::size_t capacity) {
  std::vector<double> leaves;
  for (std::size_t i = 0; i < capacity_; ++i) leaves.push_back(get(i));
  capacity_ = capacity;
  leaf_offset_ = 1;
  while (leaf_offset_ < std::max<std::size_t>(capacity, 1)) leaf_offset_ *= 2;
  nodes_.assign(2 * leaf_offset_, 0.0);
  for (std::size_t i = 0; i < std::min(leaves.size(), capacity); ++i) set(i, leaves[i]);
}

void SumTree::set(std::size_t index, double priority) {
  if (index >= capacity_) throw Error("sum tree: index " + std::to_string(index) + " beyond capacity");
  if (!(priority >= 0)) throw Error("sum tree: priorities must be non-negative numbers");
  max_ = std::max(max_, priority);
  std::size_t node = leaf_offset_ + index;
  nodes_[node] = priority;
  // Parents are recomputed, not adjusted by differences, so rounding never accumulates.
  for (node /= 2; node >= 1; node /= 2) nodes_[node] = nodes_[2 * node] + nodes_[2 * node + 1];
}

std::size_t SumTree::find(double mass) const {
  std::size_t node = 1;
  while (node < leaf_offset_) {
    const std::size_t left = 2 * node;
    if (mass < nodes_[left] || nodes_[left + 1] <= 0) {
      node = left;
    } else {
      mass -= nodes_[left];
      node = left + 1;
    }
  }
  return std::min(node - leaf_offset_, capacity_ > 0 ? capacity_ - 1 : 0);
}

}  // namespace qte::replay
