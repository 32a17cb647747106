#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "nets/checkpoint.hpp"
#include "nets/qattention_modules.hpp"
#include "stream/field_names.hpp"
#include "stream/writer.hpp"

namespace qte::nets {
namespace {

constexpr int V = 16;
constexpr int C = 10;

NetConfig config_of(Architecture architecture, int base_channels, int proprio = 4) {
  NetConfig config;
  config.architecture = architecture;
  config.base_channels = base_channels;
  config.proprio = proprio;
  return config;
}

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "nets_" + std::to_string(::getpid()) + "_" + name;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_file(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

void write_record(const std::string& path, const stream::Record& record) {
  stream::RecordWriter writer(path);
  writer.write(record);
  writer.close();
}

// Runs `load` and returns the message of the Error it must throw (failing if it is a
// StreamError: a mismatch is not damage).
template <class Load>
std::string mismatch_message(Load load) {
  try {
    load();
  } catch (const StreamError& e) {
    ADD_FAILURE() << "expected a mismatch Error, got StreamError: " << e.what();
    return e.what();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

// One channels-last grid as voxels::voxelize writes it: index channels everywhere, a cube of
// occupied voxels (mean position, grey colour, occupancy) of half-size `radius` at `centre`.
void fill_grid(float* grid, int cx, int cy, int cz, int radius) {
  for (int x = 0; x < V; ++x)
    for (int y = 0; y < V; ++y)
      for (int z = 0; z < V; ++z) {
        float* voxel = grid + ((x * V + y) * V + z) * C;
        const bool occupied = std::abs(x - cx) <= radius && std::abs(y - cy) <= radius && std::abs(z - cz) <= radius;
        for (int c = 0; c < C; ++c) voxel[c] = 0;
        if (occupied) {
          voxel[0] = (x + 0.5f) / V, voxel[1] = (y + 0.5f) / V, voxel[2] = (z + 0.5f) / V;
          voxel[3] = voxel[4] = voxel[5] = 0.2f;
          voxel[9] = 1;
        }
        voxel[6] = float(x) / V, voxel[7] = float(y) / V, voxel[8] = float(z) / V;
      }
}

TEST(QAttentionNet, ChannelsFirstKeepsTheVoxelIndexOrder) {
  auto grid = torch::zeros({1, V, V, V, C});
  grid[0][3][5][7][9] = 1;
  const auto first = channels_first(grid);
  EXPECT_EQ(first.sizes(), (torch::IntArrayRef{1, C, V, V, V}));
  EXPECT_EQ(first[0][9][3][5][7].item<float>(), 1);
  EXPECT_EQ(first.sum().item<float>(), 1);
}

TEST(QAttentionNet, OutputShapesForBothArchitecturesAndDepths) {
  seed_torch(1);
  const int batch = 2;
  std::vector<float> grids(batch * V * V * V * C, 0.1f), proprio(batch * 4, 0.5f);
  for (Architecture architecture : {Architecture::arm, Architecture::light}) {
    auto nets = make_coarse_to_fine_nets(config_of(architecture, default_base_channels(architecture)), 2);
    for (const auto& net : nets) {
      SCOPED_TRACE(std::string(architecture_name(architecture)) + " depth " + std::to_string(net.config().depth));
      const QValues q = net.predict(grids.data(), proprio.data(), batch);
      EXPECT_EQ(q.translation.size(), std::size_t(batch * V * V * V));
      const std::size_t rotations = net.config().is_last ? batch * kRotationAxes * kRotationBins : 0;
      const std::size_t grippers = net.config().is_last ? batch * kGripperActions : 0;
      EXPECT_EQ(q.rotation.size(), rotations);
      EXPECT_EQ(q.gripper.size(), grippers);
      for (float value : q.translation) ASSERT_TRUE(std::isfinite(value));
    }
    // The torch view of the last depth, with the shapes the learner indexes.
    auto& module = nets.back().module();
    const QOutputs out = module.forward(torch::randn({batch, C, V, V, V}), torch::randn({batch, 4}));
    EXPECT_EQ(out.translation.sizes(), (torch::IntArrayRef{batch, V, V, V}));
    EXPECT_EQ(out.rotation.sizes(), (torch::IntArrayRef{batch, 3, 72}));
    EXPECT_EQ(out.gripper.sizes(), (torch::IntArrayRef{batch, 2}));
    EXPECT_FALSE(nets.front().module().forward(torch::randn({1, C, V, V, V}), torch::randn({1, 4})).rotation.defined());
  }
}

// The pooling of forwards without gradients against max_pool3d: grid sides the U-Net meets
// (16, 8, 4) and odd or small ones, ties, and NaN (both give NaN where a window holds one).
TEST(QAttentionNet, PoolingWithoutGradientsEqualsMaxPool3d) {
  torch::manual_seed(3);
  for (int64_t side : {16, 8, 4, 6, 5, 2, 1}) {
    SCOPED_TRACE("side " + std::to_string(side));
    auto x = torch::randn({2, 3, side, side + 1, side});
    x.slice(2, 0, (side + 1) / 2).fill_(0.25);  // ties
    x[1][2][0][0][0] = std::nanf("");
    const auto expected = torch::max_pool3d(x, 3, 2, 1);
    torch::NoGradGuard no_grad;
    const auto pooled = max_pool(x);
    ASSERT_EQ(pooled.sizes(), expected.sizes());
    EXPECT_TRUE(torch::equal(pooled.isnan(), expected.isnan()));
    EXPECT_TRUE(torch::equal(pooled.nan_to_num(), expected.nan_to_num()));
  }
}

// Without gradients the networks pool another way (see max_pool): the same floats as the
// forward the learner differentiates, for both architectures, at both depths, with ties (empty
// voxels give equal activations) and a batch of one.
TEST(QAttentionNet, InferenceForwardEqualsTheTrainingForward) {
  for (Architecture architecture : {Architecture::light, Architecture::arm}) {
    seed_torch(6);
    auto nets = make_coarse_to_fine_nets(config_of(architecture, architecture == Architecture::arm ? 8 : 16), 2);
    for (auto& net : nets) {
      SCOPED_TRACE(std::string(architecture_name(architecture)) + " depth " + std::to_string(net.config().depth));
      for (int batch : {1, 3}) {
        auto grid = torch::rand({batch, C, V, V, V});
        grid.slice(2, 0, V / 2).zero_();  // half the grid empty
        const auto proprio = torch::rand({batch, 4});
        const QOutputs trained = net.module().forward(grid, proprio);
        ASSERT_TRUE(trained.translation.requires_grad());
        torch::NoGradGuard no_grad;
        const QOutputs inferred = net.module().forward(grid, proprio);
        EXPECT_TRUE(torch::equal(trained.translation, inferred.translation));
        if (!net.config().is_last) continue;
        EXPECT_TRUE(torch::equal(trained.rotation, inferred.rotation));
        EXPECT_TRUE(torch::equal(trained.gripper, inferred.gripper));
      }
    }
  }
}

// The leaves of a tree: predict_leaves gives every grid's translation Q at once and the head's
// values later, for the rows asked for only; they are the floats predict gives those rows, in
// every chunk of kPredictChunk and for a batch of one (run as two copies).
TEST(QAttentionNet, HeadsOfChosenLeavesEqualTheWholeBatches) {
  for (Architecture architecture : {Architecture::light, Architecture::arm}) {
    SCOPED_TRACE(architecture_name(architecture));
    seed_torch(4);
    const auto nets = make_coarse_to_fine_nets(config_of(architecture, architecture == Architecture::arm ? 8 : 16), 2);
    for (int batch : {1, kPredictChunk + 9}) {
      const auto grids = torch::rand({batch, V, V, V, C}), proprio = torch::rand({batch, 4});
      const QValues all = nets[1].predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), batch);
      QValues leaves = nets[1].predict_leaves(grids.data_ptr<float>(), proprio.data_ptr<float>(), batch);
      EXPECT_EQ(leaves.translation, all.translation);
      EXPECT_TRUE(leaves.rotation.empty());
      ASSERT_TRUE(leaves.heads_for);
      const std::vector<int> rows = batch == 1 ? std::vector<int>{0} : std::vector<int>{kPredictChunk + 3, 2, kPredictChunk};
      leaves.heads_for(rows, leaves);
      ASSERT_EQ(leaves.rotation.size(), all.rotation.size());
      ASSERT_EQ(leaves.gripper.size(), all.gripper.size());
      const int r = kRotationAxes * kRotationBins;
      for (int row = 0; row < batch; ++row) {
        const bool asked = std::find(rows.begin(), rows.end(), row) != rows.end();
        for (int i = 0; i < r; ++i)
          ASSERT_EQ(leaves.rotation[row * r + i], asked ? all.rotation[row * r + i] : 0.0f) << "row " << row;
        for (int i = 0; i < kGripperActions; ++i)
          ASSERT_EQ(leaves.gripper[row * 2 + i], asked ? all.gripper[row * 2 + i] : 0.0f) << "row " << row;
      }
      EXPECT_THROW(leaves.heads_for({batch}, leaves), Error);
    }
    // Activations beyond the bound are not kept: the heads come at once, as from predict.
    const auto three = torch::rand({3, V, V, V, C}), their_proprio = torch::rand({3, 4});
    const float *g = three.data_ptr<float>(), *p = their_proprio.data_ptr<float>();
    const QValues bounded = nets[1].predict_leaves(g, p, 3, 1e5);
    EXPECT_FALSE(bounded.heads_for);
    EXPECT_EQ(bounded.rotation, nets[1].predict(g, p, 3).rotation);
    // Without a head there is nothing to wait for.
    const auto grid = torch::rand({2, V, V, V, C}), proprio = torch::rand({2, 4});
    const QValues coarse = nets[0].predict_leaves(grid.data_ptr<float>(), proprio.data_ptr<float>(), 2);
    EXPECT_FALSE(coarse.heads_for);
    EXPECT_EQ(coarse.translation, nets[0].predict(grid.data_ptr<float>(), proprio.data_ptr<float>(), 2).translation);
  }
}

// Numbers printed by the PyTorch reference of ARM's published Q-attention network (its `Net`
// module, torch_qattention_ref.py; not part of this repository), whose Net takes 11 proprio
// inputs and 10 channels at 64 base kernels:
//   /usr/bin/python3 -c "import sys; sys.argv = ['x']; exec(open('torch_qattention_ref.py')
//     .read().split('if __name__')[0]); print([sum(p.numel() for p in Net(d).parameters())
//     for d in (False, True)])"
// gives [879553, 1186459]. Parameter names also match the reference's (so Python can load our
// weights into its Net by name): checked here for a few of them.
TEST(QAttentionNet, ArmParameterCountsEqualTheReference) {
  EXPECT_EQ(QAttentionNet(config_of(Architecture::arm, 64, 11)).parameter_count(), 879553);
  NetConfig last = config_of(Architecture::arm, 64, 11);
  last.is_last = true;
  QAttentionNet net(last);
  EXPECT_EQ(net.parameter_count(), 1186459);
  // With our 4 proprio inputs, the proprio layer has 7 x 64 weights fewer.
  EXPECT_EQ(QAttentionNet(config_of(Architecture::arm, 64, 4)).parameter_count(), 879553 - 7 * 64);
  const auto named = net.module().named_parameters();
  for (const char* name : {"inp.a.0.weight", "inp.c.4.bias", "prop.weight", "u2.p.b.2.weight", "u1.q.c.0.weight",
                           "f2.weight", "h.0.weight", "h.4.bias"})
    EXPECT_TRUE(named.contains(name)) << name;
  EXPECT_EQ(named["h.0.weight"].sizes(), (torch::IntArrayRef{128, 2048}));
  EXPECT_EQ(named["h.4.weight"].sizes(), (torch::IntArrayRef{218, 128}));
}

TEST(QAttentionNet, RefusesConfigsItCannotBuild) {
  NetConfig config;
  config.voxels = 10;
  EXPECT_THROW(QAttentionNet{config}, Error);
  config = config_of(Architecture::arm, 30);
  EXPECT_THROW(QAttentionNet{config}, Error);
  EXPECT_THROW(architecture_from_name("resnet"), Error);
  config = config_of(Architecture::arm, 8);
  config.head_input = HeadInput::voxel;  // built for light only
  EXPECT_THROW(QAttentionNet{config}, Error);
  EXPECT_THROW(head_input_from_name("local"), Error);
}

// HeadInput::voxel: the head also reads the finest level's features at one voxel, each sample's
// greedy voxel unless the caller names one. Checked against those features read off the trunk's
// finest level by hand, at the argmax found by hand.
TEST(QAttentionNet, VoxelHeadReadsTheFeaturesAtTheVoxelTaken) {
  NetConfig config = config_of(Architecture::light, 8);
  config.is_last = true;
  config.head_input = HeadInput::voxel;
  seed_torch(21);
  const auto module = make_qattention_module(config);
  EXPECT_EQ(module->named_parameters()["head.0.weight"].size(1), 4 * (8 + 16 + 32 + 8) + 8);
  const int batch = 3;
  const auto grid = torch::rand({batch, C, V, V, V}), proprio = torch::rand({batch, 4});
  const Trunk trunk = module->trunk(grid, proprio);
  ASSERT_EQ(trunk.levels.size(), 5u);
  const auto finest = trunk.levels[3].contiguous(), at_voxel = trunk.levels[4].contiguous();
  const auto q = trunk.translation.contiguous();
  std::vector<int64_t> greedy;
  for (int b = 0; b < batch; ++b) {
    const float* volume = q.data_ptr<float>() + b * V * V * V;
    const int64_t i = std::max_element(volume, volume + V * V * V) - volume;
    greedy.push_back(i);
    const int64_t x = i / (V * V), y = i / V % V, z = i % V;
    for (int c = 0; c < 8; ++c)
      ASSERT_EQ(at_voxel[b][c].item<float>(), finest[b][c][x][y][z].item<float>()) << "sample " << b;
  }
  const auto greedy_voxels = torch::tensor(greedy, torch::kLong);
  const QOutputs by_default = module->forward(grid, proprio), named = module->forward(grid, proprio, greedy_voxels);
  EXPECT_TRUE(torch::equal(by_default.rotation, named.rotation));
  EXPECT_TRUE(torch::equal(by_default.gripper, named.gripper));
  // Another voxel, other features: other rotation Q values, the same translation Q values.
  const QOutputs elsewhere = module->forward(grid, proprio, (greedy_voxels + 1) % (V * V * V));
  EXPECT_TRUE(torch::equal(elsewhere.translation, by_default.translation));
  EXPECT_FALSE(torch::equal(elsewhere.rotation, by_default.rotation));
  // A leaf's heads later (tree expansion) are its heads at once.
  QAttentionNet net(config);
  const auto grids = torch::rand({batch, V, V, V, C});
  const QValues all = net.predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), batch);
  QValues leaves = net.predict_leaves(grids.data_ptr<float>(), proprio.data_ptr<float>(), batch);
  ASSERT_TRUE(leaves.heads_for);
  leaves.heads_for({0, 1, 2}, leaves);
  EXPECT_EQ(leaves.rotation, all.rotation);
  EXPECT_EQ(leaves.gripper, all.gripper);
}

// A real learning check: two scenes with a block at different places; the target voxel is the
// block's centre. After a few dozen Adam steps the argmax of each Q volume is its target.
TEST(QAttentionNet, LightLearnsToPointAtTheBlock) {
  seed_torch(3);
  QAttentionNet net(config_of(Architecture::light, 16));
  const int targets[2][3] = {{4, 11, 6}, {12, 3, 9}};
  auto grids = torch::zeros({2, V, V, V, C});
  for (int b = 0; b < 2; ++b) fill_grid(grids[b].data_ptr<float>(), targets[b][0], targets[b][1], targets[b][2], 1);
  const auto input = channels_first(grids);
  const auto proprio = torch::zeros({2, 4});
  const auto target_index = torch::tensor({(targets[0][0] * V + targets[0][1]) * V + targets[0][2],
                                           (targets[1][0] * V + targets[1][1]) * V + targets[1][2]});
  torch::optim::Adam adam(net.module().parameters(), torch::optim::AdamOptions(3e-3));
  const auto loss_now = [&] {
    return torch::nn::functional::cross_entropy(net.module().forward(input, proprio).translation.flatten(1),
                                                target_index);
  };
  const float first_loss = loss_now().item<float>();
  for (int step = 0; step < 60; ++step) {
    adam.zero_grad();
    auto loss = loss_now();
    loss.backward();
    adam.step();
  }
  torch::NoGradGuard no_grad;
  const auto chosen = net.module().forward(input, proprio).translation.flatten(1).argmax(1);
  EXPECT_TRUE(torch::equal(chosen, target_index)) << "chose " << chosen << " want " << target_index;
  EXPECT_LT(loss_now().item<float>(), 0.5f * first_loss);
}

TEST(Checkpoint, RoundTripGivesIdenticalOutputs) {
  const std::string path = temp_path("round_trip.rec");
  seed_torch(11);
  auto saved = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  save_checkpoint(path, saved, nullptr, 1234);
  seed_torch(12);
  auto loaded = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  EXPECT_EQ(load_checkpoint(path, loaded), 1234);

  const CheckpointConfig config = read_checkpoint_config(path);
  EXPECT_EQ(config.net.architecture, Architecture::light);
  EXPECT_EQ(config.net.base_channels, 8);
  EXPECT_EQ(config.depths, 2);
  EXPECT_EQ(config.step, 1234);

  const auto grids = torch::rand({3, V, V, V, C});
  const auto proprio = torch::rand({3, 4});
  for (int d = 0; d < 2; ++d) {
    const QValues a = saved[d].predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), 3);
    const QValues b = loaded[d].predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), 3);
    EXPECT_EQ(a.translation, b.translation);
    EXPECT_EQ(a.rotation, b.rotation);
    EXPECT_EQ(a.gripper, b.gripper);
  }
  std::remove(path.c_str());
}

// The head's input travels with the checkpoint; the published one writes no field for it.
TEST(Checkpoint, HeadInputRoundTrips) {
  const std::string path = temp_path("head_input.rec");
  NetConfig config = config_of(Architecture::light, 8);
  seed_torch(13);
  save_checkpoint(path, make_coarse_to_fine_nets(config, 2), nullptr, 0);
  EXPECT_EQ(read_checkpoint_config(path).net.head_input, HeadInput::pooled);
  EXPECT_FALSE(read_online_checkpoint(path).has(qte::fields::head_input));
  config.head_input = HeadInput::voxel;
  auto saved = make_coarse_to_fine_nets(config, 2);
  save_checkpoint(path, saved, nullptr, 0);
  EXPECT_EQ(read_checkpoint_config(path).net.head_input, HeadInput::voxel);
  auto loaded = make_coarse_to_fine_nets(config, 2);
  load_checkpoint(path, loaded);
  const auto grids = torch::rand({2, V, V, V, C}), proprio = torch::rand({2, 4});
  EXPECT_EQ(saved[1].predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), 2).rotation,
            loaded[1].predict(grids.data_ptr<float>(), proprio.data_ptr<float>(), 2).rotation);
  auto pooled = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  EXPECT_THROW(load_checkpoint(path, pooled), Error);  // the head's first layer is wider
  stream::Record damaged = read_online_checkpoint(path);
  damaged.set_string(qte::fields::head_input, "local");
  EXPECT_THROW(checkpoint_config(damaged), StreamError);  // named by the field, as damage
  std::remove(path.c_str());
}

TEST(Checkpoint, SameSeedGivesIdenticalBytes) {
  const auto save_seeded = [](uint64_t seed, const std::string& name) {
    seed_torch(seed);
    const auto nets = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
    const std::string path = temp_path(name);
    save_checkpoint(path, nets, nullptr, 0);
    const std::string bytes = file_bytes(path);
    std::remove(path.c_str());
    return bytes;
  };
  const std::string a = save_seeded(5, "a.rec"), b = save_seeded(5, "b.rec"), c = save_seeded(6, "c.rec");
  EXPECT_GT(a.size(), 100000u);
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == c);
}

TEST(Checkpoint, AdamStateRoundTripContinuesTrainingIdentically) {
  const auto train_step = [](std::vector<QAttentionNet>& nets, torch::optim::Adam& adam) {
    torch::manual_seed(99);  // the same batch for both copies
    const auto grids = torch::rand({2, C, V, V, V});
    const auto proprio = torch::rand({2, 4});
    adam.zero_grad();
    torch::Tensor loss = torch::zeros({});
    for (auto& net : nets) {
      const QOutputs out = net.module().forward(grids, proprio);
      loss = loss + out.translation.square().mean();
      if (out.rotation.defined()) loss = loss + out.rotation.square().mean() + out.gripper.square().mean();
    }
    loss.backward();
    adam.step();
  };
  const std::string path = temp_path("adam.rec");
  seed_torch(21);
  auto nets = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  torch::optim::Adam adam(parameters_of(nets), torch::optim::AdamOptions(1e-3));
  train_step(nets, adam);
  train_step(nets, adam);
  save_checkpoint(path, nets, &adam, 2);

  seed_torch(22);
  auto resumed = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  torch::optim::Adam resumed_adam(parameters_of(resumed), torch::optim::AdamOptions(1e-3));
  EXPECT_EQ(load_checkpoint(path, resumed, &resumed_adam), 2);
  EXPECT_EQ(resumed_adam.state().size(), adam.state().size());

  train_step(nets, adam);
  train_step(resumed, resumed_adam);
  const auto a = parameters_of(nets), b = parameters_of(resumed);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(torch::equal(a[i], b[i])) << "parameter " << i;

  // A weights-only load leaves the optimiser fresh.
  save_checkpoint(path, nets, nullptr, 3);
  load_checkpoint(path, resumed, &resumed_adam);
  EXPECT_EQ(resumed_adam.state().size(), 0u);
  std::remove(path.c_str());
}

TEST(Checkpoint, LoadErrorsNameTheField) {
  const std::string path = temp_path("errors.rec");
  seed_torch(31);
  auto nets = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  const stream::Record good = checkpoint_record(nets, nullptr, 0);

  stream::Record wrong_shape = good;
  wrong_shape.set("depth1.head.4.weight", {218, 64}, std::vector<float>(218 * 64, 0.0f));
  write_record(path, wrong_shape);
  EXPECT_EQ(mismatch_message([&] { load_checkpoint(path, nets); }),
            path +
                ": record 0 at byte 0: 'checkpoint' record: depth1.head.4.weight has shape [218, 64], "
                "the network expects [218, 128]");

  stream::Record missing = good;
  missing.remove("depth0.up0.bias");
  write_record(path, missing);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("depth0.up0.bias is missing"),
            std::string::npos);

  stream::Record extra = good;
  extra.set("depth0.spare.weight", {2}, std::vector<float>{1, 2});
  write_record(path, extra);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("depth0.spare.weight is not a tensor"),
            std::string::npos);

  stream::Record wrong_dtype = good;
  wrong_dtype.set("depth0.q.bias", {1}, std::vector<double>{0.0});
  write_record(path, wrong_dtype);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("depth0.q.bias is float64"), std::string::npos);

  seed_torch(32);
  save_checkpoint(path, make_coarse_to_fine_nets(config_of(Architecture::arm, 8), 2), nullptr, 0);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("architecture is arm, the networks have light"),
            std::string::npos);

  save_checkpoint(path, make_coarse_to_fine_nets(config_of(Architecture::light, 8), 3), nullptr, 0);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("depths is 3, the networks have 2"),
            std::string::npos);

  save_checkpoint(path, make_coarse_to_fine_nets(config_of(Architecture::light, 8, 11), 2), nullptr, 0);
  EXPECT_NE(mismatch_message([&] { load_checkpoint(path, nets); }).find("proprio is 11, the networks have 4"),
            std::string::npos);

  // A failed load leaves the networks as they were.
  const auto before = parameters_of(nets)[0].clone();
  write_record(path, wrong_shape);
  EXPECT_THROW(load_checkpoint(path, nets), Error);
  EXPECT_TRUE(torch::equal(before, parameters_of(nets)[0]));
  std::remove(path.c_str());
}

// A checkpoint's settings are checked before any network is built from them: 2^31 - 1 depths
// or base channels asked for terabytes.
TEST(Checkpoint, SettingsOutOfRangeAreRefusedBeforeBuilding) {
  seed_torch(33);
  const stream::Record good = checkpoint_record(make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2), nullptr, 0);
  for (const char* field : {"depths", "base_channels", "voxels", "channels", "proprio"}) {
    for (int64_t bad : {int64_t{2147483647}, int64_t{1} << 40, int64_t{0}, int64_t{-3}}) {
      stream::Record hostile = good;
      hostile.set_scalar<int64_t>(field, bad);
      try {
        checkpoint_config(hostile);
        ADD_FAILURE() << field << " = " << bad << " accepted";
      } catch (const StreamError& e) {
        EXPECT_NE(std::string(e.what()).find(std::string("field '") + field + "'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("got " + std::to_string(bad)), std::string::npos) << e.what();
      }
    }
  }
}

TEST(Checkpoint, DamagedFileGivesStreamError) {
  const std::string path = temp_path("damaged.rec");
  seed_torch(41);
  auto nets = make_coarse_to_fine_nets(config_of(Architecture::light, 8), 2);
  save_checkpoint(path, nets, nullptr, 0);
  const std::string bytes = file_bytes(path);

  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x10;
  write_file(path, flipped);
  EXPECT_THROW(load_checkpoint(path, nets), StreamError);

  write_file(path, bytes.substr(0, bytes.size() - 100));
  EXPECT_THROW(load_checkpoint(path, nets), StreamError);

  write_file(path, "");
  EXPECT_THROW(load_checkpoint(path, nets), StreamError);

  write_record(path, stream::Record("metrics"));
  EXPECT_THROW(load_checkpoint(path, nets), StreamError);

  write_file(path, bytes);
  EXPECT_NO_THROW(load_checkpoint(path, nets));
  std::remove(path.c_str());
}

// Networks whose Q values are not finite, or absurd, are refused as the checkpoint's fault
// (a Q bias of -3e38 once reached the tree as "row -1 of 10").
TEST(QAttentionNet, NonFiniteOrAbsurdQValuesAreTheNetworksFault) {
  seed_torch(2);
  std::vector<float> grids(2 * V * V * V * C, 0.1f), proprio(2 * 4, 0.5f);
  for (const float bias : {-3e38f, std::numeric_limits<float>::infinity(), std::nanf("")}) {
    auto nets = make_coarse_to_fine_nets(config_of(Architecture::light, 16), 2);
    {
      torch::NoGradGuard no_grad;
      for (auto& item : nets[0].module().named_parameters())
        if (item.key().rfind("q.", 0) == 0 && item.key().find("bias") != std::string::npos) item.value().fill_(bias);
    }
    try {
      nets[0].predict(grids.data(), proprio.data(), 2);
      FAIL() << "Q bias " << bias << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("damaged or diverged"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace qte::nets
