// light's trunk run by oneDNN alone (nets/light_trunk.hpp) against LibTorch's layers, through a
// whole network: Q values, the head's levels and every parameter's gradient.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "nets/conv3d.hpp"
#include "nets/light_trunk.hpp"
#include "nets/onednn.hpp"
#include "nets/qattention_modules.hpp"

namespace qte::nets {
namespace {

void expect_close(const torch::Tensor& a, const torch::Tensor& b, double tolerance, const std::string& what) {
  ASSERT_EQ(a.sizes(), b.sizes()) << what;
  const double scale = std::max(b.abs().max().item<double>(), 1e-12);
  EXPECT_LE((a - b).abs().max().item<double>(), tolerance * scale) << what;
}

struct Pass {
  QOutputs out;
  std::vector<torch::Tensor> levels, gradients;
};

// A training pass with the loss touching every output, so every parameter gets a gradient.
Pass training_pass(QAttentionModule& net, const torch::Tensor& grid, const torch::Tensor& proprio, bool onednn) {
  use_onednn_trunk(onednn);
  use_swapped_weight_gradient(onednn);
  net.zero_grad();
  Pass pass;
  const Trunk trunk = net.trunk(grid, proprio);
  pass.out.translation = trunk.translation;
  auto loss = (trunk.translation * torch::linspace(0.1, 1, trunk.translation.numel()).view(trunk.translation.sizes()))
                  .sum();
  if (net.config().is_last) {
    net.heads(trunk.levels, pass.out);
    loss = loss + pass.out.rotation.square().mean() + pass.out.gripper.square().mean();
    for (const auto& level : trunk.levels) pass.levels.push_back(level.detach().clone());
  }
  loss.backward();
  for (const auto& p : net.parameters()) pass.gradients.push_back(p.grad().clone());
  use_onednn_trunk(true);
  use_swapped_weight_gradient(true);
  return pass;
}

// A network of depth 0 or the last depth with its own seed, and a batch of 3 random inputs.
struct TrunkCase {
  NetConfig config;
  std::shared_ptr<QAttentionModule> net;
  torch::Tensor grid, proprio;
};
TrunkCase trunk_case(bool is_last, int seed) {
  TrunkCase c;
  c.config.is_last = is_last;
  c.config.proprio = 5;
  torch::manual_seed(seed);
  c.net = make_qattention_module(c.config);
  c.grid = torch::rand({3, c.config.channels, c.config.voxels, c.config.voxels, c.config.voxels});
  c.proprio = torch::rand({3, c.config.proprio});
  return c;
}

TEST(LightTrunk, IsUsedOnAProcessorWithAvx2) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2: LibTorch's layers are used";
  EXPECT_TRUE(light_trunk_supported(torch::zeros({3, 10, 16, 16, 16}), 16));
  EXPECT_TRUE(light_trunk_supported(torch::zeros({1, 10, 8, 8, 8}), 16));
  EXPECT_FALSE(light_trunk_supported(torch::zeros({3, 10, 16, 16, 16}, torch::kDouble), 16));
}

TEST(LightTrunk, EqualsLibTorchsLayersForwardAndBackward) {
  if (!light_trunk_supported(torch::zeros({3, 10, 16, 16, 16}), 16)) GTEST_SKIP() << "oneDNN trunk not supported here";
  for (const bool is_last : {false, true}) {
    const TrunkCase c = trunk_case(is_last, 11);
    const NetConfig& config = c.config;
    const auto& net = c.net;
    const auto &grid = c.grid, &proprio = c.proprio;
    const Pass theirs = training_pass(*net, grid, proprio, false);
    // The weight gradients by oneDNN's own kernel where it has a vectorised one (AVX-512), and
    // swapped (nets/onednn.hpp).
    for (const bool native : {true, false}) {
      onednn::use_native_weight_gradient(native);
      const Pass ours = training_pass(*net, grid, proprio, true), again = training_pass(*net, grid, proprio, true);
      onednn::use_native_weight_gradient(true);
      const std::string depth = std::string(is_last ? "last depth" : "depth 0") + (native ? "" : ", swapped dW") + ": ";
      expect_close(ours.out.translation, theirs.out.translation, 1e-5, depth + "Q values");
      ASSERT_EQ(ours.levels.size(), theirs.levels.size());
      for (size_t i = 0; i < ours.levels.size(); ++i)
        expect_close(ours.levels[i], theirs.levels[i], 1e-5, depth + "level " + std::to_string(i));
      if (is_last) {
        expect_close(ours.out.rotation, theirs.out.rotation, 1e-4, depth + "rotation Q");
        expect_close(ours.out.gripper, theirs.out.gripper, 1e-4, depth + "gripper Q");
      }
      ASSERT_EQ(ours.gradients.size(), theirs.gradients.size());
      const auto names = net->named_parameters().keys();
      for (size_t i = 0; i < ours.gradients.size(); ++i) {
        expect_close(ours.gradients[i], theirs.gradients[i], 2e-4, depth + names[i]);
        EXPECT_TRUE(torch::equal(ours.gradients[i], again.gradients[i])) << depth << names[i] << " repeats exactly";
      }
    }
  }
}

// Without gradients a batch larger than 4 runs padded to a multiple of 4: the same values.
TEST(LightTrunk, InferenceEqualsTheTrainingForward) {
  NetConfig config;
  config.is_last = true;
  torch::manual_seed(12);
  const auto net = make_qattention_module(config);
  for (const int batch : {1, 3, 6}) {
    const auto grid = torch::rand({batch, config.channels, config.voxels, config.voxels, config.voxels});
    const auto proprio = torch::rand({batch, config.proprio});
    const auto trained = net->forward(grid, proprio);
    torch::NoGradGuard no_grad;
    const auto inferred = net->forward(grid, proprio);
    EXPECT_TRUE(torch::equal(trained.translation, inferred.translation)) << "batch " << batch;
    EXPECT_TRUE(torch::equal(trained.rotation, inferred.rotation)) << "batch " << batch;
  }
}

// bf16 convolutions (inputs and weights rounded to bf16, fp32 sums) against fp32: the same Q
// values, levels and gradients within bf16's rounding, which is 2^-9 of each operand. Through
// ten layers and their backward the largest differences measured, as shares of the largest
// value, were 1% (Q values, levels) and 3% (the trunk's gradients); the dense head's first
// layer, which takes the pooled levels through a LeakyReLU, 12%: a pre-activation near 0 that
// bf16 moves across it changes its slope fifty-fold. 4%, 8% and 25% leave room and still catch
// a wrong layout, a dropped channel or another layer's gradient (differences of order 100%).
TEST(LightTrunk, Bf16EqualsFp32WithinBf16Rounding) {
  if (!bf16_native_here()) GTEST_SKIP() << "no AVX-512 BF16 or AMX here: bf16 runs only where it is native";
  for (const bool is_last : {false, true}) {
    const TrunkCase c = trunk_case(is_last, 13);
    const NetConfig& config = c.config;
    const auto& net = c.net;
    const auto &grid = c.grid, &proprio = c.proprio;
    use_precision(Precision::fp32);
    const Pass fp32 = training_pass(*net, grid, proprio, true);
    use_precision(Precision::bf16);
    // A processor can have the instructions and oneDNN still choose, for some of these layers,
    // kernels the trunk does not run (not its vectorised ones, or other layouts): the trunk then
    // runs fp32, as precision_in_use tells the user, and there is no bf16 to compare here.
    if (precision_running(3, config.channels, config.base_channels, config.voxels) != Precision::bf16) {
      use_precision(Precision::fp32);
      GTEST_SKIP() << "bf16 instructions, but oneDNN's kernels for these layers are not ones the trunk runs in bf16 "
                      "here (ONEDNN_VERBOSE=1 names them): the trunk runs fp32";
    }
    const Pass bf16 = training_pass(*net, grid, proprio, true), again = training_pass(*net, grid, proprio, true);
    use_precision(Precision::fp32);
    const std::string depth = is_last ? "last depth: " : "depth 0: ";
    EXPECT_FALSE(torch::equal(bf16.out.translation, fp32.out.translation)) << depth << "bf16 did not run";
    expect_close(bf16.out.translation, fp32.out.translation, 0.04, depth + "Q values");
    for (size_t i = 0; i < bf16.levels.size(); ++i)
      expect_close(bf16.levels[i], fp32.levels[i], 0.04, depth + "level " + std::to_string(i));
    if (is_last) {
      expect_close(bf16.out.rotation, fp32.out.rotation, 0.04, depth + "rotation Q");
      expect_close(bf16.out.gripper, fp32.out.gripper, 0.04, depth + "gripper Q");
    }
    const auto names = net->named_parameters().keys();
    ASSERT_EQ(bf16.gradients.size(), fp32.gradients.size());
    for (size_t i = 0; i < bf16.gradients.size(); ++i) {
      expect_close(bf16.gradients[i], fp32.gradients[i], names[i].rfind("head.0.", 0) == 0 ? 0.25 : 0.08,
                   depth + names[i]);
      EXPECT_TRUE(torch::equal(bf16.gradients[i], again.gradients[i])) << depth << names[i] << " repeats exactly";
    }
  }
}

// Without gradients the bf16 trunk runs inference primitives as fp32 does: the same values as
// its training forward.
TEST(LightTrunk, Bf16InferenceEqualsItsTrainingForward) {
  if (!bf16_native_here()) GTEST_SKIP() << "no AVX-512 BF16 or AMX here";
  NetConfig config;
  config.is_last = true;
  torch::manual_seed(14);
  const auto net = make_qattention_module(config);
  use_precision(Precision::bf16);
  const auto grid = torch::rand({4, config.channels, config.voxels, config.voxels, config.voxels});
  const auto proprio = torch::rand({4, config.proprio});
  const auto trained = net->forward(grid, proprio);
  torch::NoGradGuard no_grad;
  const auto inferred = net->forward(grid, proprio);
  use_precision(Precision::fp32);
  EXPECT_TRUE(torch::equal(trained.translation, inferred.translation));
  EXPECT_TRUE(torch::equal(trained.rotation, inferred.rotation));
}

TEST(LightTrunk, PrecisionNames) {
  EXPECT_EQ(precision_from_name("fp32"), Precision::fp32);
  EXPECT_EQ(precision_from_name("bf16"), Precision::bf16);
  EXPECT_EQ(precision_from_name("auto"), bf16_faster_here() ? Precision::bf16 : Precision::fp32);
  EXPECT_THROW(precision_from_name("fp16"), Error);
}

}  // namespace
}  // namespace qte::nets
