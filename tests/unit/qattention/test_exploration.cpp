// Exploration: epsilon 0 changes nothing; epsilon 1 puts a random voxel in at every depth, with
// the deeper grids centred on it and chosen again by the deeper networks; index noise stays in
// the grid; rotation noise wraps around the 72 bins; the same seed explores the same way.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "qattention/exploration.hpp"
#include "random_cloud.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

constexpr int V = 16, kCells = V * V * V;

struct Cloud : test_support::RandomCloud {
  Cloud() : RandomCloud(1, {120, 80, 40}) {}
};

// A stand-in for the networks (this tests exploration, not them): Q from a voxel's mean point,
// -1 for empty voxels; the last depth's rotation Q is highest at bin 10 + its depth on every
// axis, so a choice's bins tell which depth's network chose them. Counts its calls.
struct ContentQ {
  int depths = 2;
  int calls = 0;
  nets::QValues operator()(int depth, const float* grids, const float*, int batch) {
    calls += 1;
    nets::QValues out;
    out.batch = batch;
    out.translation.assign(static_cast<std::size_t>(batch) * kCells, -1.0f);
    for (int b = 0; b < batch; ++b)
      for (int cell = 0; cell < kCells; ++cell) {
        const float* c = grids + (static_cast<std::size_t>(b) * kCells + cell) * voxels::kChannels;
        if (c[9] > 0)
          out.translation[static_cast<std::size_t>(b) * kCells + cell] =
              std::sin(17 * c[0] + 29 * c[1] + 41 * c[2] + depth);
      }
    if (depth + 1 == depths) {
      out.rotation.assign(static_cast<std::size_t>(batch) * 3 * 72, 0.0f);
      out.gripper.assign(static_cast<std::size_t>(batch) * 2, 0.0f);
      for (int b = 0; b < batch; ++b) {
        for (int axis = 0; axis < 3; ++axis)
          out.rotation[static_cast<std::size_t>(b) * 216 + axis * 72 + 10 + depth] = 1;
        out.gripper[b * 2 + 1] = 1;  // open
      }
    }
    return out;
  }
};

struct Scene {
  Cloud cloud;
  ContentQ q;
  voxels::CoarseToFine hierarchy;
  std::vector<float> proprio = {1, 0.04f, 0.04f, 0.5f};
  int k = 2;
  Choice chosen;
  explicit Scene(int depths) {
    q.depths = hierarchy.depths = depths;
    hierarchy.offsets_m.assign(std::max(depths - 1, 1), 0.15);
    chosen = expand(std::ref(q), hierarchy, cloud.view(), proprio, k);
    q.calls = 0;
  }
  Explored explore(const Exploration& e, std::mt19937_64& rng) {
    return qattention::explore(chosen, e, rng, std::ref(q), hierarchy, cloud.view(), proprio, k);
  }
};

void expect_same_choice(const Choice& a, const Choice& b) {
  EXPECT_EQ(a.indices, b.indices);
  ASSERT_EQ(a.bounds.size(), b.bounds.size());
  for (std::size_t d = 0; d < a.bounds.size(); ++d) {
    EXPECT_EQ(a.bounds[d].min_corner, b.bounds[d].min_corner);
    EXPECT_EQ(a.bounds[d].size_m, b.bounds[d].size_m);
  }
  EXPECT_EQ(a.q_values, b.q_values);
  EXPECT_EQ(a.value, b.value);
  EXPECT_EQ(a.rotation_bins, b.rotation_bins);
  EXPECT_EQ(a.gripper_open, b.gripper_open);
  EXPECT_EQ(a.expanded_grids, b.expanded_grids);
}

}  // namespace

TEST(Exploration, EpsilonZeroNeverExploresAndReturnsTheGreedyChoice) {
  Scene s(2);
  for (uint64_t seed = 0; seed < 10; ++seed) {
    std::mt19937_64 rng(seed);
    const std::mt19937_64 before = rng;
    const Explored e = s.explore(Exploration{}, rng);
    expect_same_choice(e.choice, s.chosen);
    EXPECT_EQ(e.replaced, std::vector<bool>(2, false));
    EXPECT_TRUE(rng == before) << "drew random numbers with exploration off";
  }
  EXPECT_EQ(s.q.calls, 0);
}

TEST(Exploration, EpsilonOneReplacesEveryDepthWithDeeperGridsCentredOnIt) {
  Scene s(3);
  int depth0_changed = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(seed);
    Exploration e;
    e.epsilon = 1;
    const Explored x = s.explore(e, rng);
    const Choice& c = x.choice;
    EXPECT_EQ(x.replaced, std::vector<bool>(3, true));
    ASSERT_EQ(c.indices.size(), 3u);
    for (int d = 0; d < 3; ++d) {
      EXPECT_TRUE(c.bounds[d].contains(c.indices[d])) << "depth " << d << " index " << c.indices[d].transpose();
      const voxels::GridBounds expected =
          d == 0 ? s.hierarchy.scene : s.hierarchy.bounds_at(d, c.bounds[d - 1].centre_of(c.indices[d - 1]));
      EXPECT_TRUE(c.bounds[d].min_corner.isApprox(expected.min_corner, 1e-12)) << "depth " << d;
      EXPECT_DOUBLE_EQ(c.bounds[d].size_m, expected.size_m);
    }
    // Bins and gripper from the last network (depth 2), below the random voxels.
    EXPECT_EQ(c.rotation_bins, Eigen::Vector3i(12, 12, 12));
    EXPECT_TRUE(c.gripper_open);
    // Below depth 0's voxel a 2-depth tree (1 + K grids), below depth 1's a 1-depth one.
    EXPECT_EQ(c.expanded_grids, s.chosen.expanded_grids + (1 + s.k) + 1);
    depth0_changed += c.indices[0] != s.chosen.indices[0];
  }
  EXPECT_GE(depth0_changed, 19);  // the greedy voxel again has probability 1 / 16^3
  EXPECT_EQ(s.q.calls, 20 * 3);   // two forwards below depth 0's voxel, one below depth 1's
}

TEST(Exploration, RotationNoiseWrapsAroundTheBins) {
  Scene s(2);
  s.chosen.rotation_bins = Eigen::Vector3i(0, 71, 36);
  Exploration e;
  e.rotation_noise = 30;
  bool below_zero = false, above_71 = false;
  for (uint64_t seed = 0; seed < 100; ++seed) {
    std::mt19937_64 rng(seed), same(seed);
    const Explored x = s.explore(e, rng);
    // The same draws by hand: bin + round(noise), modulo 72.
    std::normal_distribution<double> noise(0, e.rotation_noise);
    for (int axis = 0; axis < 3; ++axis) {
      const long bin = s.chosen.rotation_bins[axis] + std::lround(noise(same));
      below_zero |= bin < 0;
      above_71 |= bin > 71;
      const long wrapped = ((bin % 72) + 72) % 72;
      EXPECT_EQ(x.choice.rotation_bins[axis], wrapped) << "seed " << seed << " axis " << axis << " bin " << bin;
      EXPECT_GE(x.choice.rotation_bins[axis], 0);
      EXPECT_LT(x.choice.rotation_bins[axis], 72);
    }
    EXPECT_EQ(x.choice.indices, s.chosen.indices);  // only the bins change
    EXPECT_EQ(x.replaced, std::vector<bool>(2, false));
  }
  EXPECT_TRUE(below_zero && above_71);  // both ways around happened
}

TEST(Exploration, IndexNoiseStaysInTheGridAndMarksTheLastDepth) {
  Scene s(2);
  Exploration e;
  e.index_noise = 20;
  for (uint64_t seed = 0; seed < 50; ++seed) {
    std::mt19937_64 rng(seed);
    const Explored x = s.explore(e, rng);
    EXPECT_EQ(x.choice.indices[0], s.chosen.indices[0]);
    EXPECT_TRUE(x.choice.bounds[1].contains(x.choice.indices[1])) << x.choice.indices[1].transpose();
    EXPECT_EQ(x.replaced, (std::vector<bool>{false, bool(x.choice.indices[1] != s.chosen.indices[1])}));
  }
}

TEST(Exploration, SameSeedSameExploration) {
  Scene s(2);
  Exploration e;
  e.epsilon = 0.5;
  e.index_noise = 1;
  e.rotation_noise = 2;
  e.gripper_flip = 0.3;
  int differs_from_seed_0 = 0;
  std::mt19937_64 first(0);
  const Explored seed0 = s.explore(e, first);
  for (uint64_t seed = 0; seed < 10; ++seed) {
    std::mt19937_64 a(seed), b(seed);
    const Explored x = s.explore(e, a), y = s.explore(e, b);
    expect_same_choice(x.choice, y.choice);
    EXPECT_EQ(x.replaced, y.replaced);
    EXPECT_TRUE(a == b);
    differs_from_seed_0 += !same_action(x.choice, seed0.choice);
  }
  EXPECT_GE(differs_from_seed_0, 5);
}

TEST(Exploration, SameActionIsTheSamePoseAndGripperCommand) {
  Scene s(2);
  Choice c = s.chosen;
  c.q_values[0] += 1;
  c.value += 1;
  c.expanded_grids += 5;
  EXPECT_TRUE(same_action(c, s.chosen));  // what chose it does not matter
  c = s.chosen;
  c.indices[0].x() = (c.indices[0].x() + 1) % V;
  EXPECT_FALSE(same_action(c, s.chosen));
  c = s.chosen;
  c.rotation_bins[2] = (c.rotation_bins[2] + 1) % 72;
  EXPECT_FALSE(same_action(c, s.chosen));
  c = s.chosen;
  c.gripper_open = !c.gripper_open;
  EXPECT_FALSE(same_action(c, s.chosen));
  // A flip with probability 1 always flips.
  Exploration flip;
  flip.gripper_flip = 1;
  std::mt19937_64 rng(3);
  EXPECT_EQ(s.explore(flip, rng).choice.gripper_open, !s.chosen.gripper_open);
}
