// The weight gradient (nets/conv3d.hpp, nets/onednn.hpp: oneDNN's own kernel where it has a
// vectorised one, the swapped convolution otherwise) against a brute-force sum written here, both
// ways, and against LibTorch's own backward, alone and through a whole network.
#include <gtest/gtest.h>

#include "nets/conv3d.hpp"
#include "nets/onednn.hpp"
#include "nets/qattention_modules.hpp"

namespace qte::nets {
namespace {

// dW[o, i, k] = sum over n and output voxels x of dy[n, o, x] * input[n, i, x + k - p] (zero
// outside the input): the definition, one term at a time.
torch::Tensor brute_force_weight_gradient(const torch::Tensor& x, const torch::Tensor& dy, int64_t p) {
  const int64_t n = x.size(0), in = x.size(1), out = dy.size(1);
  const int64_t k0 = x.size(2) + 2 * p - dy.size(2) + 1, k1 = x.size(3) + 2 * p - dy.size(3) + 1,
                k2 = x.size(4) + 2 * p - dy.size(4) + 1;
  auto dw = torch::zeros({out, in, k0, k1, k2}, torch::kDouble);
  const auto x64 = x.to(torch::kDouble), dy64 = dy.to(torch::kDouble);
  const auto X = x64.accessor<double, 5>();
  const auto DY = dy64.accessor<double, 5>();
  auto DW = dw.accessor<double, 5>();
  for (int64_t b = 0; b < n; ++b)
    for (int64_t o = 0; o < out; ++o)
      for (int64_t i = 0; i < in; ++i)
        for (int64_t a = 0; a < k0; ++a)
          for (int64_t c = 0; c < k1; ++c)
            for (int64_t e = 0; e < k2; ++e)
              for (int64_t u = 0; u < dy.size(2); ++u)
                for (int64_t v = 0; v < dy.size(3); ++v)
                  for (int64_t w = 0; w < dy.size(4); ++w) {
                    const int64_t xu = u + a - p, xv = v + c - p, xw = w + e - p;
                    if (xu < 0 || xv < 0 || xw < 0 || xu >= x.size(2) || xv >= x.size(3) || xw >= x.size(4)) continue;
                    DW[o][i][a][c][e] += DY[b][o][u][v][w] * X[b][i][xu][xv][xw];
                  }
  return dw.to(torch::kFloat);
}

void expect_close(const torch::Tensor& a, const torch::Tensor& b, double tolerance, const char* what) {
  ASSERT_EQ(a.sizes(), b.sizes()) << what;
  const double scale = b.abs().max().item<double>();
  EXPECT_LE((a - b).abs().max().item<double>(), tolerance * scale) << what;
}

TEST(Conv3dWeightGradient, EqualsTheBruteForceSum) {
  torch::manual_seed(1);
  struct Case {
    int64_t n, in, out, d, h, w, kernel, padding;
  };
  for (const Case c : {Case{2, 3, 2, 5, 4, 3, 3, 1}, Case{3, 10, 16, 4, 4, 4, 3, 1}, Case{2, 4, 5, 6, 5, 4, 1, 0},
                       Case{1, 2, 3, 5, 5, 5, 3, 0}}) {
    const auto x = torch::randn({c.n, c.in, c.d, c.h, c.w});
    const int64_t od = c.d + 2 * c.padding - c.kernel + 1, oh = c.h + 2 * c.padding - c.kernel + 1,
                  ow = c.w + 2 * c.padding - c.kernel + 1;
    const auto dy = torch::randn({c.n, c.out, od, oh, ow});
    const auto expected = brute_force_weight_gradient(x, dy, c.padding);
    for (const bool native : {true, false}) {
      onednn::use_native_weight_gradient(native);
      expect_close(conv3d_weight_gradient(x, dy, c.padding), expected, 1e-5,
                   native ? "weight gradient, oneDNN's kernel where it has one" : "weight gradient, swapped");
    }
    onednn::use_native_weight_gradient(true);
  }
}

// Every convolution of `light` at its own shapes (batch 4): the gradients of Conv3dLayer and of
// LibTorch's Conv3d with the same weights.
TEST(Conv3dLayer, GradientsEqualLibTorchsAtLightsShapes) {
  struct Shape {
    int in, out, kernel, voxels;
  };
  for (const Shape s : {Shape{10, 16, 3, 16}, Shape{16, 32, 3, 8}, Shape{32, 32, 3, 8}, Shape{32, 64, 3, 4},
                        Shape{64, 32, 1, 4}, Shape{32, 16, 1, 8}, Shape{16, 1, 1, 16}}) {
    torch::manual_seed(2);
    const auto options = torch::nn::Conv3dOptions(s.in, s.out, s.kernel).padding(s.kernel / 2);
    Conv3dLayer ours(options);
    torch::nn::Conv3d theirs(options);
    {
      torch::NoGradGuard no_grad;
      theirs->weight.copy_(ours->weight);
      theirs->bias.copy_(ours->bias);
    }
    const auto x = torch::randn({4, s.in, s.voxels, s.voxels, s.voxels});
    const auto x_ours = x.clone().requires_grad_(true), x_theirs = x.clone().requires_grad_(true);
    const auto dy = torch::randn({4, s.out, s.voxels, s.voxels, s.voxels});
    const auto y_ours = ours->forward(x_ours), y_theirs = theirs->forward(x_theirs);
    EXPECT_TRUE(torch::equal(y_ours, y_theirs)) << "the forward is LibTorch's own";
    y_ours.backward(dy);
    y_theirs.backward(dy);
    expect_close(ours->weight.grad(), theirs->weight.grad(), 1e-5, "weight");
    expect_close(ours->bias.grad(), theirs->bias.grad(), 1e-5, "bias");
    expect_close(x_ours.grad(), x_theirs.grad(), 1e-6, "input");
  }
}

// A whole network's training gradients with the swapped weight gradient and with LibTorch's:
// same Q values, gradients within fp32 rounding, and the same bytes on a second run.
TEST(Conv3dLayer, NetworkGradientsEqualLibTorchsAndRepeatExactly) {
  NetConfig config;
  config.is_last = true;
  config.proprio = 4;
  torch::manual_seed(3);
  const auto net = make_qattention_module(config);
  const auto grid = torch::rand({3, config.channels, config.voxels, config.voxels, config.voxels});
  const auto proprio = torch::rand({3, config.proprio});
  const auto gradients = [&](bool swapped) {
    use_swapped_weight_gradient(swapped);
    net->zero_grad();
    const auto out = net->forward(grid, proprio);
    (out.translation.square().mean() + out.rotation.square().mean() + out.gripper.square().mean()).backward();
    std::vector<torch::Tensor> g{out.translation.detach()};
    for (const auto& p : net->parameters()) g.push_back(p.grad().clone());
    return g;
  };
  const auto theirs = gradients(false), ours = gradients(true), again = gradients(true);
  use_swapped_weight_gradient(true);
  ASSERT_EQ(ours.size(), theirs.size());
  EXPECT_TRUE(torch::equal(ours[0], theirs[0])) << "Q values";
  for (size_t i = 1; i < ours.size(); ++i) {
    expect_close(ours[i], theirs[i], 1e-4, net->named_parameters()[i - 1].key().c_str());
    EXPECT_TRUE(torch::equal(ours[i], again[i])) << net->named_parameters()[i - 1].key();
  }
}

}  // namespace
}  // namespace qte::nets
