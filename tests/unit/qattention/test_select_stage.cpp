// The qte-select stage on records: records pass through in order; a non-terminal observation
// is followed by the action tree expansion chooses for it with the checkpoint's networks (the
// same as acting on its cloud directly); terminal ones get none; a bad observation is refused
// naming the record and field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "common/error.hpp"
#include "common/random.hpp"
#include "qattention/proprio.hpp"
#include "qattention/select_stage.hpp"
#include "random_cloud.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

// An observation whose front camera's 40 x 50 pixels are the points of a random cloud.
stream::Record observation(int32_t step, bool terminal) {
  const test_support::RandomCloud cloud(3, {200, 40, 40});
  stream::Record obs("obs");
  obs.set<uint8_t>("front.rgb", {40, 50, 3}, cloud.rgb);
  obs.set<float>("front.points", {40, 50, 3}, cloud.xyz);
  obs.set_scalar<uint8_t>("gripper_open", 1);
  obs.set_scalar<double>("gripper_opening_m", 0.08);
  obs.set_scalar<int32_t>("step", step);
  obs.set_scalar<uint8_t>("terminal", terminal);
  return obs;
}

}  // namespace

TEST(SelectStage, EachLiveObservationIsFollowedByTheTreesAction) {
  const std::string path = ::testing::TempDir() + "select_stage_" + std::to_string(::getpid()) + ".rec";
  nets::NetConfig config;
  config.base_channels = 8;
  nets::seed_torch(4);
  nets::save_checkpoint(path, nets::make_coarse_to_fine_nets(config, 2), nullptr, 12);
  CheckpointNetworks networks(path);
  SelectOptions options;
  options.branching = Branching(3);
  options.seed = 9;
  SelectStage stage(networks, options);

  std::vector<stream::Record> out;
  const stream::Emit keep = [&](const stream::Record& r) { out.push_back(r); };
  stage.handle(stream::Record("reset"), keep);
  stage.handle(observation(0, false), keep);
  stage.handle(observation(1, true), keep);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[0].type(), "reset");
  EXPECT_EQ(out[1].type(), "obs");
  EXPECT_EQ(out[2].type(), "action");
  EXPECT_EQ(out[3].type(), "obs");  // terminal: no action
  EXPECT_EQ(stage.actions(), 1u);

  // The independent route: the same cloud and proprioception through act() directly.
  const test_support::RandomCloud cloud(3, {200, 40, 40});
  std::mt19937_64 rng(derive_seed(9, 0));
  const Action direct = act(network_evaluator(networks.nets()), options.hierarchy, cloud.view(),
                            proprio_of(observation(0, false), 0), options.branching, options.exploration, rng);
  for (int d = 0; d < 2; ++d) {
    const auto index = out[2].array<int32_t>("depth" + std::to_string(d) + ".index");
    EXPECT_EQ((Eigen::Vector3i(index[0], index[1], index[2])), direct.choice.indices[d]) << "depth " << d;
  }
  // Depth 0's best-ranked voxel, where K = 1 would have gone; none at the leaf.
  const auto argmax = out[2].array<int32_t>("depth0.argmax_index");
  EXPECT_EQ((Eigen::Vector3i(argmax[0], argmax[1], argmax[2])), direct.choice.argmax_indices[0]);
  EXPECT_FALSE(out[2].has("depth1.argmax_index"));
  EXPECT_EQ(out[2].scalar<int64_t>("checkpoint_step"), 12);

  stream::Record broken = observation(0, false);
  broken.set_scalar<double>("gripper_opening_m", NAN);
  try {
    stage.handle(broken, keep);
    ADD_FAILURE() << "acted on a NaN gripper opening";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("gripper_opening_m"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}
