// The two architectures. `arm` follows the PyTorch reference of ARM's published Q-attention
// network (its `Net` module; not part of this repository) layer for layer
// (same module names, so the same parameter names and counts); `light` is the CPU default,
// chosen by measurement (tests/bench/bench_nets.cpp).
#include "nets/qattention_modules.hpp"

#include <limits>
#include <string>

#include "common/error.hpp"
#include "nets/conv3d.hpp"
#include "nets/light_trunk.hpp"

namespace qte::nets {
namespace {

namespace F = torch::nn::functional;
using torch::nn::Conv3d;
using torch::nn::Conv3dOptions;
using torch::nn::LeakyReLU;
using torch::nn::Linear;
using torch::nn::Sequential;

constexpr double kSoftArgmaxTemperature = 0.01;
constexpr int kHeadHidden = 128;

LeakyReLU leaky() { return LeakyReLU(torch::nn::LeakyReLUOptions().negative_slope(kLeakySlope)); }
torch::Tensor leaky(const torch::Tensor& x) {
  return F::leaky_relu(x, F::LeakyReLUFuncOptions().negative_slope(kLeakySlope));
}

// The reference pads 3x3x3 convolutions by replicating the border voxels.
Conv3d replicate_conv3(int in, int out) {
  return Conv3d(Conv3dOptions(in, out, 3).padding(1).padding_mode(torch::kReplicate));
}
// Zero-padded convolutions train with the swapped weight gradient (nets/conv3d.hpp).
Conv3dLayer conv3(int in, int out) { return Conv3dLayer(Conv3dOptions(in, out, 3).padding(1)); }
Conv3dLayer conv1(int in, int out) { return Conv3dLayer(Conv3dOptions(in, out, 1)); }

// Builds a Sequential one layer per call, in order: the arguments of a single call are
// constructed in an unspecified order (GCC goes right to left), which would make the initial
// weights a seed draws depend on the compiler.
class Layers {
 public:
  template <class Layer>
  Layers& then(Layer layer) {
    sequence_->push_back(layer);
    return *this;
  }
  Sequential done() const { return sequence_; }

 private:
  Sequential sequence_;
};

torch::Tensor upsample(const torch::Tensor& x) {
  return F::interpolate(x, F::InterpolateFuncOptions()
                               .scale_factor(std::vector<double>{2, 2, 2})
                               .mode(torch::kTrilinear)
                               .align_corners(false));
}

// Multiply-accumulates of the weights under `module` when its convolutions produce `voxels`
// outputs each (linear layers count once).
int64_t weight_macs(const torch::nn::Module& module, int64_t voxels) {
  int64_t macs = 0;
  for (const auto& p : module.named_parameters()) {
    const std::string& name = p.key();
    if (name.size() < 6 || name.compare(name.size() - 6, 6, "weight") != 0) continue;
    macs += p.value().numel() * (p.value().dim() == 5 ? voxels : 1);
  }
  return macs;
}

// Expected (x, y, z) in [-1, 1] of a sharp softmax over each channel's voxels: 3C features,
// all x first, then y, then z (as the reference).
torch::Tensor soft_argmax(const torch::Tensor& t) {
  const auto p = (t.flatten(2) / kSoftArgmaxTemperature).softmax(-1).view(t.sizes());
  const auto axis = [&](int64_t n) { return torch::linspace(-1, 1, n, t.options()); };
  const auto x = (p.sum({3, 4}) * axis(t.size(2))).sum(-1);
  const auto y = (p.sum({2, 4}) * axis(t.size(3))).sum(-1);
  const auto z = (p.sum({2, 3}) * axis(t.size(4))).sum(-1);
  return torch::cat({x, y, z}, 1);
}

// The dense head's input: per level, the max over voxels then the soft-argmax position; then
// the chosen voxel's features as they are (Trunk::levels' [B, C] entry, with HeadInput::voxel).
torch::Tensor pooled_features(const std::vector<torch::Tensor>& levels) {
  std::vector<torch::Tensor> features;
  for (const auto& t : levels)
    if (t.dim() == 5) features.push_back(t.amax({2, 3, 4}));
  for (const auto& t : levels)
    if (t.dim() == 5) features.push_back(soft_argmax(t));
  for (const auto& t : levels)
    if (t.dim() == 2) features.push_back(t);
  return torch::cat(features, 1);
}

// The features [B, C] of `finest` ([B, C, V, V, V]) at each sample's voxel ([B] flat indices).
torch::Tensor features_at(const torch::Tensor& finest, const torch::Tensor& voxel) {
  const int64_t b = finest.size(0), c = finest.size(1);
  return finest.reshape({b, c, -1}).gather(2, voxel.view({b, 1, 1}).expand({b, c, 1})).squeeze(2);
}

Sequential dense_head(int features) {
  return Layers()
      .then(Linear(features, kHeadHidden))
      .then(leaky())
      .then(Linear(kHeadHidden, kHeadHidden))
      .then(leaky())
      .then(Linear(kHeadHidden, kRotationAxes * kRotationBins + kGripperActions))
      .done();
}

void split_head(const torch::Tensor& head_out, QOutputs& out) {
  const int64_t rotations = kRotationAxes * kRotationBins;
  out.rotation = head_out.slice(1, 0, rotations).view({-1, kRotationAxes, kRotationBins});
  out.gripper = head_out.slice(1, rotations, rotations + kGripperActions);
}

// Proprioception as a per-sample, per-channel vector to tile over the voxels.
torch::Tensor tiled(const torch::Tensor& per_sample) { return per_sample.view({per_sample.size(0), -1, 1, 1, 1}); }

// ---- arm: inception-style blocks (reference `Inc`, `Up`, `Net`) ----------------------------

// Three branches concatenated: 1x1 (out/2), 1x1 -> 3x3x3 (out/4), 1x1 -> 3x3x3 -> 3x3x3 (out/4);
// the inner width is 32 whatever the block's size, as in the reference.
struct Inception : torch::nn::Module {
  Inception(int in, int out) {
    a = register_module("a", Layers().then(conv1(in, out / 2)).then(leaky()).done());
    b = register_module(
        "b", Layers().then(conv1(in, 32)).then(leaky()).then(replicate_conv3(32, out / 4)).then(leaky()).done());
    c = register_module("c", Layers()
                                 .then(conv1(in, 32))
                                 .then(leaky())
                                 .then(replicate_conv3(32, 32))
                                 .then(leaky())
                                 .then(replicate_conv3(32, out / 4))
                                 .then(leaky())
                                 .done());
  }
  torch::Tensor forward(const torch::Tensor& x) { return torch::cat({a->forward(x), b->forward(x), c->forward(x)}, 1); }
  Sequential a{nullptr}, b{nullptr}, c{nullptr};
};

// Inception at the coarse level, trilinear x2, inception at the fine level.
struct InceptionUp : torch::nn::Module {
  InceptionUp(int in, int out) {
    p = register_module("p", std::make_shared<Inception>(in, out));
    q = register_module("q", std::make_shared<Inception>(out, out));
  }
  torch::Tensor forward(const torch::Tensor& x) { return q->forward(upsample(p->forward(x))); }
  std::shared_ptr<Inception> p, q;
};

class ArmNet : public QAttentionModule {
 public:
  explicit ArmNet(const NetConfig& config) : QAttentionModule(config) {
    const int k = config.base_channels;
    // Registration order is the reference's, so that a seed draws the same initial weights.
    inp = register_module("inp", std::make_shared<Inception>(config.channels, k));
    prop = register_module("prop", Linear(config.proprio, k));
    d0 = register_module("d0", std::make_shared<Inception>(2 * k, k));
    d1 = register_module("d1", std::make_shared<Inception>(k, 2 * k));
    d2 = register_module("d2", std::make_shared<Inception>(2 * k, 4 * k));
    u2 = register_module("u2", std::make_shared<InceptionUp>(4 * k, k));
    u1 = register_module("u1", std::make_shared<InceptionUp>(3 * k, k));
    f = register_module("f", replicate_conv3(2 * k, k));
    f2 = register_module("f2", replicate_conv3(k, 1));
    if (config.is_last) h = register_module("h", dense_head(4 * (k + 2 * k + 4 * k + k)));
  }

  Trunk trunk_batch(const torch::Tensor& grid, const torch::Tensor& proprio) override {
    const auto x = inp->forward(grid);
    const auto p = tiled(leaky(prop->forward(proprio))).expand({-1, -1, grid.size(2), grid.size(3), grid.size(4)});
    const auto e0 = d0->forward(torch::cat({x, p}, 1));
    const auto e1 = d1->forward(max_pool(e0));
    const auto e2 = d2->forward(max_pool(e1));
    const auto up1 = u1->forward(torch::cat({e1, u2->forward(e2)}, 1));
    const auto features = leaky(f->forward(torch::cat({e0, up1}, 1)));
    Trunk out{f2->forward(features).squeeze(1), {}};
    if (h) out.levels = {e0, e1, e2, features};
    return out;
  }
  torch::Tensor dense_head_forward(const torch::Tensor& pooled) override { return h->forward(pooled); }

  int64_t multiply_accumulates() const override {
    const int64_t v0 = cube(config().voxels), v1 = cube(config().voxels / 2), v2 = cube(config().voxels / 4);
    int64_t macs = weight_macs(*inp, v0) + weight_macs(*prop, 1) + weight_macs(*d0, v0) + weight_macs(*d1, v1) +
                   weight_macs(*d2, v2) + weight_macs(*u2->p, v2) + weight_macs(*u2->q, v1) + weight_macs(*u1->p, v1) +
                   weight_macs(*u1->q, v0) + weight_macs(*f, v0) + weight_macs(*f2, v0);
    if (h) macs += weight_macs(*h, 1);
    return macs;
  }

 private:
  static int64_t cube(int64_t n) { return n * n * n; }
  std::shared_ptr<Inception> inp, d0, d1, d2;
  std::shared_ptr<InceptionUp> u2, u1;
  Linear prop{nullptr};
  Conv3d f{nullptr}, f2{nullptr};
  Sequential h{nullptr};
};

// ---- light: plain 3x3x3 convolutions ------------------------------------------------------
//
// Level 0 (V^3, k channels): one convolution of the grid, plus the proprioception through a
// linear layer added per channel: tiling proprio over the voxels and convolving it is, by
// linearity, such a per-sample bias (exactly so away from the zero-padded border), at none of
// the cost of k more input channels. Level 1 ((V/2)^3, 2k) and level 2 ((V/4)^3, 4k): two
// convolutions each after a max-pool. Back up, each coarser level goes through a 1x1
// convolution to the finer level's width (before upsampling: 8x fewer voxels), is upsampled
// and added to the skip connection, then one 3x3x3 convolution. A 1x1 convolution gives Q.
// The receptive field is over 33 voxels wide: every output voxel sees the whole 16^3 grid.
//
// Why (training step at batch 32, 2 threads, measured against arm's ~4.5 s): full-resolution
// convolutions dominate the cost, so there are only two of them (no concatenated skips, which
// widen the finer convolutions: a two-level concat U-Net at k=16 cost 1.9x this one); the
// second downsampling costs little (4^3 voxels) and buys the whole-grid receptive field that
// a one-downsampling U-Net (about 19 voxels) lacks. k=16 is ~0.23-0.36 s a step (12-20x
// cheaper than arm); k=8 ~0.11-0.18 s, k=24 ~0.41-0.65 s, k=32 ~0.6-0.96 s.
class LightNet : public QAttentionModule {
 public:
  explicit LightNet(const NetConfig& config) : QAttentionModule(config) {
    const int k = config.base_channels;
    input = register_module("input", conv3(config.channels, k));
    proprio = register_module("proprio", Linear(config.proprio, k));
    down1 = register_module(
        "down1", Layers().then(conv3(k, 2 * k)).then(leaky()).then(conv3(2 * k, 2 * k)).then(leaky()).done());
    down2 = register_module(
        "down2", Layers().then(conv3(2 * k, 4 * k)).then(leaky()).then(conv3(4 * k, 4 * k)).then(leaky()).done());
    lateral2 = register_module("lateral2", conv1(4 * k, 2 * k));
    up1 = register_module("up1", conv3(2 * k, 2 * k));
    lateral1 = register_module("lateral1", conv1(2 * k, k));
    up0 = register_module("up0", conv3(k, k));
    q = register_module("q", conv1(k, 1));
    const int voxel_features = config.head_input == HeadInput::voxel ? k : 0;
    if (config.is_last) head = register_module("head", dense_head(4 * (k + 2 * k + 4 * k + k) + voxel_features));
  }

  Trunk trunk_batch(const torch::Tensor& grid, const torch::Tensor& proprio_in) override {
    const auto proprio_bias = proprio->forward(proprio_in);
    if (onednn_trunk_in_use() && light_trunk_supported(grid, config().base_channels)) {
      const bool last = static_cast<bool>(head);
      std::vector<torch::Tensor> out = light_trunk(grid, proprio_bias, convolution_parameters(), last);
      Trunk t{out[0], {}};
      if (last) t.levels.assign(out.begin() + 1, out.end());
      return t;
    }
    const auto e0 = leaky(input->forward(grid) + tiled(proprio_bias));
    const auto e1 = down1->forward(max_pool(e0));
    const auto e2 = down2->forward(max_pool(e1));
    const auto d1 = leaky(up1->forward(e1 + upsample(lateral2->forward(e2))));
    const auto d0 = leaky(up0->forward(e0 + upsample(lateral1->forward(d1))));
    Trunk out{q->forward(d0).squeeze(1), {}};
    if (head) out.levels = {e0, e1, e2, d0};
    return out;
  }
  torch::Tensor dense_head_forward(const torch::Tensor& pooled) override { return head->forward(pooled); }

  // Weight and bias of each convolution, in the order of nets/light_trunk.hpp.
  std::vector<torch::Tensor> convolution_parameters() const {
    using Conv = torch::nn::Conv3dImpl;
    const std::vector<const Conv*> convolutions{
        input.get(),           down1->ptr(0)->as<Conv>(), down1->ptr(2)->as<Conv>(), down2->ptr(0)->as<Conv>(),
        down2->ptr(2)->as<Conv>(), lateral2.get(),        up1.get(),                 lateral1.get(),
        up0.get(),             q.get()};
    std::vector<torch::Tensor> p;
    for (const Conv* c : convolutions) {
      p.push_back(c->weight);
      p.push_back(c->bias);
    }
    return p;
  }

  int64_t multiply_accumulates() const override {
    const int64_t v = config().voxels, v0 = v * v * v, v1 = v0 / 8, v2 = v0 / 64;
    int64_t macs = weight_macs(*input, v0) + weight_macs(*proprio, 1) + weight_macs(*down1, v1) +
                   weight_macs(*down2, v2) + weight_macs(*lateral2, v2) + weight_macs(*up1, v1) +
                   weight_macs(*lateral1, v1) + weight_macs(*up0, v0) + weight_macs(*q, v0);
    if (head) macs += weight_macs(*head, 1);
    return macs;
  }

 private:
  Conv3dLayer input{nullptr}, lateral2{nullptr}, up1{nullptr}, lateral1{nullptr}, up0{nullptr}, q{nullptr};
  Linear proprio{nullptr};
  Sequential down1{nullptr}, down2{nullptr}, head{nullptr};
};

}  // namespace

QOutputs QAttentionModule::forward(const torch::Tensor& grid, const torch::Tensor& proprio,
                                   const torch::Tensor& voxel) {
  const Trunk t = trunk(grid, proprio, voxel);
  QOutputs out{t.translation, {}, {}};
  if (config_.is_last) heads(t.levels, out);
  return out;
}

Trunk QAttentionModule::trunk(const torch::Tensor& grid, const torch::Tensor& proprio, const torch::Tensor& voxel) {
  Trunk t;
  if (grid.size(0) != 1) {
    t = trunk_batch(grid, proprio);
  } else {
    t = trunk_batch(torch::cat({grid, grid}), torch::cat({proprio, proprio}));
    t.translation = t.translation.slice(0, 0, 1);
    for (auto& level : t.levels) level = level.slice(0, 0, 1);
  }
  if (config_.is_last && config_.head_input == HeadInput::voxel) {
    // The greedy voxel is the one acting takes at the last depth, in each grid of a tree too.
    const auto at = voxel.defined() ? voxel.to(torch::kLong)
                                    : t.translation.detach().reshape({t.translation.size(0), -1}).argmax(1);
    t.levels.push_back(features_at(t.levels.back(), at));
  }
  return t;
}

void QAttentionModule::heads(const std::vector<torch::Tensor>& levels, QOutputs& out) {
  split_head(dense_head_forward(pooled_features(levels)), out);
}

std::shared_ptr<QAttentionModule> make_qattention_module(const NetConfig& config) {
  config.validate();
  switch (config.architecture) {
    case Architecture::arm:
      return std::make_shared<ArmNet>(config);
    case Architecture::light:
      return std::make_shared<LightNet>(config);
  }
  throw Error("unknown network architecture");
}

torch::Tensor channels_first(const torch::Tensor& grids) {
  if (grids.dim() != 5)
    throw Error("voxel grids must be [batch, V, V, V, channels], got " + std::to_string(grids.dim()) + " dimensions");
  return grids.permute({0, 4, 1, 2, 3}).contiguous();
}

torch::Tensor max_pool(const torch::Tensor& x) {
  if (torch::GradMode::is_enabled()) return torch::max_pool3d(x, 3, 2, 1);
  auto y = torch::constant_pad_nd(x, {1, 1, 1, 1, 1, 1}, -std::numeric_limits<double>::infinity());
  for (int64_t dim = 2; dim < 5; ++dim) {
    const int64_t out = (x.size(dim) - 1) / 2 + 1;
    const auto window = [&](int64_t start) { return y.slice(dim, start, start + 2 * out - 1, 2); };
    y = torch::maximum(torch::maximum(window(0), window(1)), window(2));
  }
  return y;
}
std::vector<torch::Tensor> parameters_of(std::vector<QAttentionNet>& nets) {
  std::vector<torch::Tensor> all;
  for (auto& net : nets) {
    const auto p = net.module().parameters();
    all.insert(all.end(), p.begin(), p.end());
  }
  return all;
}

}  // namespace qte::nets
