// Prioritised replay: proportional sampling, importance weights, eviction that keeps
// demonstrations, references to frames, and files that grow while being read.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <tuple>

#include "replay/growing_stream.hpp"
#include "replay/replay_buffer.hpp"
#include "stream/codec.hpp"

using namespace qte;
using namespace qte::replay;

namespace {

stream::Record frame(int64_t episode, int32_t index) {
  stream::Record f("frame");
  f.set_scalar<int64_t>("episode_key", episode);
  f.set_scalar<int32_t>("frame", index);
  return f;
}

stream::Record transition(int64_t episode, int32_t from, int32_t to, bool demo) {
  stream::Record t("transition");
  t.set_scalar<int64_t>("episode_key", episode);
  t.set_scalar<int32_t>("frame", from);
  t.set_scalar<int32_t>("next_frame", to);
  t.set_scalar<uint8_t>("demo", demo);
  return t;
}

// A frame seen by one depth camera (the replay's compact form: millimetres), looking down at a
// plane whose depth varies with the pixel, so that every point differs.
stream::Record depth_frame(int64_t episode, int32_t index) {
  constexpr int kWidth = 24, kHeight = 16;
  stream::Record f = frame(episode, index);
  std::vector<uint8_t> rgb(kWidth * kHeight * 3);
  std::vector<uint16_t> depth_mm(kWidth * kHeight);
  for (int i = 0; i < kWidth * kHeight; ++i) {
    depth_mm[i] = static_cast<uint16_t>(900 + 7 * i + 13 * index);
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = static_cast<uint8_t>(i * (c + 1) + index);
  }
  depth_mm[5] = 0;  // no return: a NaN point
  f.set<uint8_t>("front.rgb", {kHeight, kWidth, 3}, rgb);
  f.set<uint16_t>("front.depth_mm", {kHeight, kWidth}, depth_mm);
  f.set<double>("front.intrinsics", {3, 3}, std::vector<double>{30, 0, 12, 0, 30, 8, 0, 0, 1});
  f.set<double>("front.extrinsics", {4, 4},
                std::vector<double>{1, 0, 0, 0.1 * index, 0, -1, 0, 0.2, 0, 0, -1, 1.8, 0, 0, 0, 1});
  return f;
}

bool same_bytes(const voxels::ObservationCloud& a, const voxels::ObservationCloud& b) {
  return a.xyz.size() == b.xyz.size() && a.rgb == b.rgb &&
         std::memcmp(a.xyz.data(), b.xyz.data(), a.xyz.size() * sizeof(float)) == 0;  // NaN too
}

void add_episode(ReplayBuffer& replay, int64_t episode, int transitions, bool demo) {
  for (int i = 0; i <= transitions; ++i) replay.add(frame(episode, i));
  for (int i = 0; i < transitions; ++i) replay.add(transition(episode, i, i + 1, demo));
}

}  // namespace

TEST(SumTree, FindsProportionallyAndStaysExact) {
  SumTree tree(5);
  const double p[5] = {1, 0, 3, 0.5, 0.5};
  for (int i = 0; i < 5; ++i) tree.set(i, p[i]);
  EXPECT_DOUBLE_EQ(tree.total(), 5.0);
  EXPECT_EQ(tree.find(0.5), 0u);
  EXPECT_EQ(tree.find(1.0), 2u);  // index 1 has no mass
  EXPECT_EQ(tree.find(3.99), 2u);
  EXPECT_EQ(tree.find(4.2), 3u);
  EXPECT_EQ(tree.find(4.9), 4u);
  for (int k = 0; k < 100000; ++k) tree.set(k % 5, 0.1 * (k % 7));
  double sum = 0;
  for (int i = 0; i < 5; ++i) sum += tree.get(i);
  EXPECT_DOUBLE_EQ(tree.total(), sum);
}

TEST(ReplayBuffer, SamplesInProportionToPriorityWithImportanceWeights) {
  ReplayBuffer replay;
  add_episode(replay, 1, 4, true);
  replay.update_priorities({0, 1, 2, 3}, {0.0, 1.0, 1.0, 8.0});
  std::mt19937_64 rng(3);
  std::vector<int> counts(4, 0);
  for (int round = 0; round < 2000; ++round) {
    const Sample s = replay.sample(8, 0.5, rng);
    double max_weight = 0;
    for (std::size_t i = 0; i < s.indices.size(); ++i) {
      counts[s.indices[i]] += 1;
      EXPECT_LE(s.weights[i], 1.0 + 1e-12);
      max_weight = std::max(max_weight, s.weights[i]);
    }
    EXPECT_DOUBLE_EQ(max_weight, 1.0);
  }
  // priorities (|td| + 1e-3)^0.7: 0.008, 1.0007, 1.0007, 4.29
  const double expected3 = std::pow(8.001, 0.7) / (std::pow(0.001, 0.7) + 2 * std::pow(1.001, 0.7) + std::pow(8.001, 0.7));
  EXPECT_NEAR(counts[3] / 16000.0, expected3, 0.02);
  EXPECT_LT(counts[0], 100);
  EXPECT_NEAR(counts[1], counts[2], 400);
}

TEST(ReplayBuffer, UniformWhenAsked) {
  ReplayOptions options;
  options.prioritised = false;
  ReplayBuffer replay(options);
  add_episode(replay, 1, 4, false);
  replay.update_priorities({3}, {100.0});  // ignored
  std::mt19937_64 rng(4);
  std::vector<int> counts(4, 0);
  for (int round = 0; round < 4000; ++round)
    for (std::size_t i : replay.sample(4, 1.0, rng).indices) counts[i] += 1;
  for (int c : counts) EXPECT_NEAR(c, 4000, 300);
}

TEST(ReplayBuffer, FullReplaysEvictTheOldestAgentTransitionsAndKeepDemos) {
  ReplayOptions options;
  options.capacity = 6;
  ReplayBuffer replay(options);
  add_episode(replay, 1, 3, true);    // 3 demo transitions
  add_episode(replay, 2, 3, false);   // full
  add_episode(replay, 3, 2, false);   // replaces episode 2's first two
  EXPECT_EQ(replay.size(), 6u);
  EXPECT_EQ(replay.demo_count(), 3u);
  int from_episode[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < replay.size(); ++i) from_episode[replay.transition(i).scalar<int64_t>("episode_key")] += 1;
  EXPECT_EQ(from_episode[1], 3);
  EXPECT_EQ(from_episode[2], 1);
  EXPECT_EQ(from_episode[3], 2);
  // Frames nothing refers to any more are released: episode 2 keeps frames 2 and 3 only.
  EXPECT_EQ(replay.frame_count(), 4u + 2u + 3u);
}

TEST(ReplayBuffer, TransitionsNeedTheirFramesFirst) {
  ReplayBuffer replay;
  replay.add(frame(1, 0));
  stream::Record t = transition(1, 0, 5, false);
  t.position.source = "replay.rec";
  t.position.record_index = 7;
  try {
    replay.add(t);
    FAIL();
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("replay.rec: record 7 at byte 0: transition refers to frame 5"), std::string::npos);
  }
}

TEST(GrowingStream, ReturnsWholeRecordsAsTheyArrive) {
  char path[] = "/tmp/qte_growing_XXXXXX";
  const int fd = ::mkstemp(path);
  ASSERT_GE(fd, 0);
  const auto a = stream::encode_record(frame(1, 0)), b = stream::encode_record(frame(1, 1));
  ASSERT_EQ(::write(fd, a.data(), a.size()), static_cast<ssize_t>(a.size()));
  GrowingStream growing(path);
  EXPECT_EQ(growing.poll().size(), 1u);
  EXPECT_TRUE(growing.poll().empty());
  ASSERT_EQ(::write(fd, b.data(), 70), 70);  // half a record: not yet
  EXPECT_TRUE(growing.poll().empty());
  ASSERT_EQ(::write(fd, b.data() + 70, b.size() - 70), static_cast<ssize_t>(b.size() - 70));
  const auto records = growing.poll();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].scalar<int32_t>("frame"), 1);
  EXPECT_EQ(records[0].position.record_index, 1u);
  const uint8_t junk[64] = {1, 2, 3};
  ASSERT_EQ(::write(fd, junk, sizeof junk), 64);
  EXPECT_THROW(growing.poll(), StreamError);
  ::close(fd);
  ::unlink(path);
}

// Published importance weights: 1 / sqrt(P(i)), normalised by the batch's largest. With
// beta 0.5 the replay's (N P(i))^-beta over its maximum is that, written here independently.
TEST(ReplayBuffer, ImportanceWeightsAreOneOverRootPNormalisedByTheBatchMaximum) {
  ReplayBuffer replay;
  add_episode(replay, 1, 6, true);
  replay.update_priorities({0, 1, 2, 3, 4, 5}, {0.1, 0.5, 1.0, 2.0, 4.0, 8.0});
  double total = 0;
  for (double p : replay.priorities()) total += p;
  std::mt19937_64 rng(5);
  for (int round = 0; round < 50; ++round) {
    const Sample s = replay.sample(4, 0.5, rng);
    double largest = 0;
    for (std::size_t index : s.indices) largest = std::max(largest, 1 / std::sqrt(replay.priority(index) / total));
    for (std::size_t i = 0; i < s.indices.size(); ++i)
      EXPECT_NEAR(s.weights[i], 1 / std::sqrt(replay.priority(s.indices[i]) / total) / largest, 1e-12);
  }
}

// --demo-share: a fixed part of each batch from the demonstrations, the rest from the agent's
// transitions, each part sampled in proportion to its own kind's priorities and weighted as a
// replay of that kind alone, (n_kind P_kind(i))^-beta, over the batch's largest: written out
// here from the priorities themselves.
TEST(ReplayBuffer, ADemoShareDrawsItsPartOfEachBatchFromTheDemonstrationsByTheirOwnPriorities) {
  ReplayBuffer replay;
  add_episode(replay, 1, 3, true);   // indices 0-2: demonstrations
  add_episode(replay, 2, 5, false);  // 3-7: the agent's
  replay.update_priorities({0, 1, 2, 3, 4, 5, 6, 7}, {0.2, 1.0, 3.0, 0.1, 0.1, 0.5, 2.0, 6.0});
  const std::vector<double> p = replay.priorities();
  const double demo_mass = p[0] + p[1] + p[2], agent_mass = p[3] + p[4] + p[5] + p[6] + p[7];
  std::mt19937_64 rng(11);
  std::vector<int> counts(8, 0);
  const int rounds = 4000;
  for (int round = 0; round < rounds; ++round) {
    const Sample s = replay.sample(8, 0.5, rng, 0.25);
    ASSERT_EQ(s.indices.size(), 8u);
    double largest = 0;
    std::vector<double> unnormalised;
    for (std::size_t i = 0; i < 8; ++i) {
      const std::size_t index = s.indices[i];
      EXPECT_EQ(index < 3, i < 2) << "draw " << i << " of the batch is index " << index;  // 2 of 8 demos, first
      const double w = index < 3 ? 1 / std::sqrt(3 * p[index] / demo_mass) : 1 / std::sqrt(5 * p[index] / agent_mass);
      unnormalised.push_back(w);
      largest = std::max(largest, w);
      counts[index] += 1;
    }
    for (std::size_t i = 0; i < 8; ++i) EXPECT_NEAR(s.weights[i], unnormalised[i] / largest, 1e-12);
  }
  for (int i = 0; i < 8; ++i) {
    const double expected = i < 3 ? 2.0 * rounds * p[i] / demo_mass : 6.0 * rounds * p[i] / agent_mass;
    EXPECT_NEAR(counts[i], expected, 0.05 * expected + 30) << "index " << i;
  }
}

// The demonstrations' part is the share of the batch rounded to the nearest draw, and all of it
// at a share of 1.
TEST(ReplayBuffer, ADemoShareRoundsToTheNearestDraw) {
  ReplayBuffer replay;
  add_episode(replay, 1, 2, true);
  add_episode(replay, 2, 2, false);
  std::mt19937_64 rng(13);
  for (const auto& [batch, share, demos] : {std::tuple<std::size_t, double, std::size_t>{3, 0.5, 2}, {3, 0.1, 0},
                                            {5, 0.3, 2}, {4, 1.0, 4}, {1, 0.5, 1}}) {
    const Sample s = replay.sample(batch, 0.5, rng, share);
    ASSERT_EQ(s.indices.size(), batch);
    std::size_t from_demos = 0;
    for (std::size_t index : s.indices) from_demos += index < 2;
    EXPECT_EQ(from_demos, demos) << "batch " << batch << ", share " << share;
  }
}

// While the replay holds one kind only (pretraining: demonstrations; or the agent's alone), a
// share draws as one draw over all: the same indices and weights, so a run's pretraining does
// not depend on it.
TEST(ReplayBuffer, ADemoShareOverOneKindIsTheOneDrawOverAll) {
  for (const bool demo : {true, false}) {
    ReplayBuffer replay;
    add_episode(replay, 1, 6, demo);
    replay.update_priorities({0, 1, 2, 3, 4, 5}, {0.1, 0.5, 1.0, 2.0, 4.0, 8.0});
    std::mt19937_64 plain(7), shared(7);
    for (int round = 0; round < 20; ++round) {
      const Sample a = replay.sample(4, 0.5, plain), b = replay.sample(4, 0.5, shared, 0.5);
      EXPECT_EQ(a.indices, b.indices);
      EXPECT_EQ(a.weights, b.weights);
    }
  }
}

// A resumed replay samples its parts as the one never stopped: the kinds' priorities come back
// with the checkpoint's, including a slot that changed kind (an agent's replaced by a demo's).
TEST(ReplayBuffer, RestoredPrioritiesDrawTheSameDemoShare) {
  ReplayOptions options;
  options.capacity = 5;
  ReplayBuffer straight(options), resumed(options);
  for (ReplayBuffer* r : {&straight, &resumed}) {
    add_episode(*r, 1, 2, true);
    add_episode(*r, 2, 3, false);  // full
    add_episode(*r, 3, 1, true);   // replaces the agent's oldest, index 2
  }
  EXPECT_EQ(straight.demo_count(), 3u);
  straight.update_priorities({0, 1, 2, 3, 4}, {0.3, 2.0, 5.0, 0.2, 1.0});
  resumed.restore_priorities(straight.priorities(), straight.max_priority());
  std::mt19937_64 a(9), b(9);
  for (int round = 0; round < 20; ++round) {
    const Sample x = straight.sample(6, 0.5, a, 0.5), y = resumed.sample(6, 0.5, b, 0.5);
    EXPECT_EQ(x.indices, y.indices);
    EXPECT_EQ(x.weights, y.weights);
    for (int i = 0; i < 3; ++i) EXPECT_LT(x.indices[i], 3u) << "0-2 are the demonstrations";
    for (int i = 3; i < 6; ++i) EXPECT_GE(x.indices[i], 3u) << "3 and 4 are the agent's";
  }
}

// New transitions start at the largest priority ever set: a resumed replay restores it, so a
// transition added after the resume is sampled as in the run that was never stopped.
TEST(ReplayBuffer, RestoredPrioritiesKeepTheLargestEverForNewTransitions) {
  ReplayBuffer straight;
  add_episode(straight, 1, 3, false);
  straight.update_priorities({0, 1, 2}, {9.0, 0.1, 0.2});  // the largest ever: 9's
  straight.update_priorities({0}, {0.3});                 // ... no longer held by any transition
  const std::vector<double> saved = straight.priorities();
  const double saved_max = straight.max_priority();
  ReplayBuffer resumed;
  add_episode(resumed, 1, 3, false);
  resumed.restore_priorities(saved, saved_max);
  for (ReplayBuffer* r : {&straight, &resumed}) add_episode(*r, 2, 1, false);
  EXPECT_DOUBLE_EQ(resumed.priority(3), straight.priority(3));
  EXPECT_DOUBLE_EQ(resumed.priority(3), std::pow(9.001, 0.7));
  ReplayBuffer forgetful;  // what a resume without it gave
  add_episode(forgetful, 1, 3, false);
  forgetful.restore_priorities(saved, 1.0);
  add_episode(forgetful, 2, 1, false);
  EXPECT_NE(forgetful.priority(3), straight.priority(3));
}

// The replay keeps each frame's point cloud once it is first asked for: the same bytes as one
// computed from the frame again, within its memory budget, and gone with the frame.
TEST(ReplayBuffer, KeptPointCloudsEqualRecomputedOnesByteForByte) {
  ReplayOptions options;
  options.capacity = 2;
  ReplayBuffer replay(options);
  for (int e = 0; e < 2; ++e) {
    replay.add(depth_frame(e, 0));
    replay.add(depth_frame(e, 1));
    replay.add(transition(e, 0, 1, false));
  }
  EXPECT_EQ(replay.cloud_memory_used(), 0u);  // nothing computed before it is asked for
  for (std::size_t i = 0; i < replay.size(); ++i) {
    const auto kept = replay.cloud_of(i), next = replay.next_cloud_of(i);
    EXPECT_TRUE(same_bytes(*kept, voxels::observation_cloud(replay.frame_of(i)))) << i;
    EXPECT_TRUE(same_bytes(*next, voxels::observation_cloud(replay.next_frame_of(i)))) << i;
    EXPECT_EQ(replay.cloud_of(i), kept) << "asked again: the kept one";
    EXPECT_TRUE(std::isnan(kept->xyz[15]));
  }
  const std::size_t four = replay.cloud_memory_used();
  EXPECT_GT(four, 4u * 24 * 16 * 15);
  // Full: a new transition evicts episode 0's, and its frames' clouds go with it.
  replay.add(depth_frame(2, 0));
  replay.add(depth_frame(2, 1));
  replay.add(transition(2, 0, 1, false));
  EXPECT_EQ(replay.cloud_memory_used(), four / 2);

  // A budget for one cloud keeps the first; the others are computed at every use, alike.
  ReplayOptions small;
  small.cloud_memory_bytes = four / 4;
  ReplayBuffer tight(small);
  tight.add(depth_frame(0, 0));
  tight.add(depth_frame(0, 1));
  tight.add(transition(0, 0, 1, false));
  const auto first = tight.cloud_of(0), second = tight.next_cloud_of(0);
  EXPECT_EQ(tight.cloud_memory_used(), four / 4);
  EXPECT_NE(tight.next_cloud_of(0), second) << "not kept: computed again";
  EXPECT_TRUE(same_bytes(*tight.next_cloud_of(0), *second));
  EXPECT_EQ(tight.cloud_of(0), first);
}
