// Acting: without exploration the action is the tree's choice and nothing more is evaluated;
// an explored action carries the Q-values of the voxels it takes and their path's value; the
// checkpoint's networks are loaded again only when the file was replaced.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "common/error.hpp"
#include "qattention/acting.hpp"
#include "random_cloud.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

constexpr int V = 16, kCells = V * V * V;

struct Cloud : test_support::RandomCloud {
  Cloud() : RandomCloud(2, {40, 160, 90}) {}
};

// Q from a voxel's mean point (-1 when empty), rotation and gripper at the last of two depths;
// a stand-in for the networks that counts the grids it evaluates.
struct ContentQ {
  int grids = 0;
  nets::QValues operator()(int depth, const float* g, const float*, int batch) {
    grids += batch;
    nets::QValues out;
    out.batch = batch;
    out.translation.assign(static_cast<std::size_t>(batch) * kCells, -1.0f);
    for (int b = 0; b < batch; ++b)
      for (int cell = 0; cell < kCells; ++cell) {
        const float* c = g + (static_cast<std::size_t>(b) * kCells + cell) * voxels::kChannels;
        if (c[9] > 0)
          out.translation[static_cast<std::size_t>(b) * kCells + cell] =
              std::cos(23 * c[0] - 19 * c[1] + 31 * c[2] + depth);
      }
    if (depth == 1) {
      out.rotation.assign(static_cast<std::size_t>(batch) * 3 * 72, 0.0f);
      out.gripper.assign(static_cast<std::size_t>(batch) * 2, 0.0f);
    }
    return out;
  }
};

int flat(const Eigen::Vector3i& i) { return (i.x() * V + i.y()) * V + i.z(); }

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "acting_" + std::to_string(::getpid()) + "_" + name;
}

}  // namespace

TEST(Acting, WithoutExplorationTheActionIsTheTreeChoice) {
  const Cloud cloud;
  ContentQ q;
  const voxels::CoarseToFine hierarchy;
  const std::vector<float> proprio = {1, 0.04f, 0.04f, 1};
  const Choice tree = expand(std::ref(q), hierarchy, cloud.view(), proprio, 3);
  q.grids = 0;
  std::mt19937_64 rng(4);
  Action action = act(std::ref(q), hierarchy, cloud.view(), proprio, 3, Exploration{}, rng);
  EXPECT_FALSE(action.explored);
  EXPECT_EQ(action.choice.indices, tree.indices);
  EXPECT_EQ(action.choice.q_values, tree.q_values);
  EXPECT_EQ(action.choice.value, tree.value);
  EXPECT_EQ(action.choice.expanded_grids, tree.expanded_grids);
  EXPECT_EQ(q.grids, 1 + 3);  // the tree alone: no path grid evaluated
  // The path's grids, evaluated alone on demand and once, give the tree's Q-values.
  for (int d = 0; d < 2; ++d) EXPECT_FLOAT_EQ(action.grids.at(d).q[flat(tree.indices[d])], tree.q_values[d]);
  action.grids.at(0);
  EXPECT_EQ(q.grids, 1 + 3 + 2);
}

TEST(Acting, AnExploredActionCarriesTheQValuesOfTheVoxelsItTakes) {
  const Cloud cloud;
  ContentQ q;
  const voxels::CoarseToFine hierarchy;
  const std::vector<float> proprio = {0, 0.01f, 0.01f, -0.5f};
  Exploration exploration;
  exploration.epsilon = 1;
  int explored = 0;
  for (uint64_t seed = 0; seed < 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 rng(seed);
    const Action action = act(std::ref(q), hierarchy, cloud.view(), proprio, 2, exploration, rng);
    explored += action.explored;
    if (!action.explored) continue;
    const Choice& c = action.choice;
    for (int d = 0; d < 2; ++d) {
      const GridQ alone = evaluate_grid(std::ref(q), d, c.bounds[d], cloud.view(), proprio);
      EXPECT_EQ(c.q_values[d], alone.q[flat(c.indices[d])]) << "depth " << d;
    }
    EXPECT_EQ(c.value, (c.q_values[0] + c.q_values[1]) / 2);
  }
  EXPECT_GE(explored, 4);  // a random voxel at both depths is the tree's with probability 1 / 16^6
}

TEST(Acting, CheckpointNetworksReloadOnlyAReplacedFile) {
  const std::string path = temp_path("latest.rec");
  nets::NetConfig config;
  config.base_channels = 8;
  nets::seed_torch(1);
  nets::save_checkpoint(path, nets::make_coarse_to_fine_nets(config, 2), nullptr, 5);
  CheckpointNetworks networks(path);
  EXPECT_EQ(networks.step(), 5);
  EXPECT_EQ(networks.config().depths, 2);
  ASSERT_EQ(networks.nets().size(), 2u);
  EXPECT_FALSE(networks.reload_if_changed());

  nets::seed_torch(2);
  const auto replacement = nets::make_coarse_to_fine_nets(config, 2);
  nets::save_checkpoint(path, replacement, nullptr, 9);  // renamed into place, as the learner does
  EXPECT_TRUE(networks.reload_if_changed());
  EXPECT_EQ(networks.step(), 9);
  EXPECT_FALSE(networks.reload_if_changed());
  std::vector<float> grid(static_cast<std::size_t>(kCells) * voxels::kChannels, 0.5f);
  const std::vector<float> proprio = {1, 0.04f, 0.04f, 1};
  EXPECT_EQ(networks.nets()[1].predict(grid.data(), proprio.data(), 1).translation,
            replacement[1].predict(grid.data(), proprio.data(), 1).translation);

  // Networks that take other inputs than the actor gives are refused, naming the file.
  config.proprio = 11;
  nets::save_checkpoint(path, nets::make_coarse_to_fine_nets(config, 2), nullptr, 0);
  try {
    CheckpointNetworks other(path);
    ADD_FAILURE() << "loaded networks with 11 proprioception inputs";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": the networks take 11 proprioception inputs"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}
