// The torch side of the Q-attention networks, for the learning code only (everything else
// includes nets/qattention_net.hpp, which keeps LibTorch's headers out).
#pragma once

#include <torch/torch.h>

#include <memory>
#include <vector>

#include "nets/qattention_net.hpp"

namespace qte::nets {

// The networks' LeakyReLU slope (the reference's), in LibTorch's layers and oneDNN's alike.
constexpr double kLeakySlope = 0.02;

struct QOutputs {
  torch::Tensor translation;  // [B, V, V, V]
  torch::Tensor rotation;     // [B, 3, 72]; undefined unless the config is_last
  torch::Tensor gripper;      // [B, 2]; undefined unless the config is_last
};

// The convolutional part of a forward: translation Q and, at the last depth, the U-Net
// activations the dense head pools (kept so that the head can run later on some samples only).
struct Trunk {
  torch::Tensor translation;           // [B, V, V, V]
  // [B, C_l, ...] per pooled level, then with HeadInput::voxel the finest level's features at
  // the chosen voxel, [B, C_0]; empty unless is_last.
  std::vector<torch::Tensor> levels;
};

// One depth's network. Parameter names are those of the architecture's module tree; for
// `arm` they are exactly those of the PyTorch reference of ARM's published Q-attention network
// (its `Net` module; not part of this repository), so Python can
// load our weights into it by name.
class QAttentionModule : public torch::nn::Module {
 public:
  explicit QAttentionModule(const NetConfig& config) : config_(config) {}
  const NetConfig& config() const { return config_; }

  // grid: [B, channels, V, V, V] (channels first: see channels_first), proprio: [B, proprio].
  // trunk + heads. `voxel` ([B] flat indices into the Q volume, undefined: each sample's
  // greedy voxel) is the voxel whose features a HeadInput::voxel head reads; the learner passes
  // the transitions' own, so that the rotation Q values it trains are those of the voxel taken.
  QOutputs forward(const torch::Tensor& grid, const torch::Tensor& proprio, const torch::Tensor& voxel = {});
  // A batch of one runs as two copies of the sample: LibTorch 1.13 sends batch-1 3D
  // convolutions with 3x3x3 kernels to its vol2col fallback rather than oneDNN, which makes
  // them slower than the same convolutions at batch 2 (measured with PyTorch 1.13 on 2 threads:
  // light 41 ms at batch 1 against 6 ms at batch 2, arm 368 ms against 77 ms).
  Trunk trunk(const torch::Tensor& grid, const torch::Tensor& proprio, const torch::Tensor& voxel = {});
  // Rotation and gripper Q values (into `out`) from a trunk's levels, or from rows of them:
  // pooled features, then the dense head. Row by row the same values as in the whole batch.
  void heads(const std::vector<torch::Tensor>& levels, QOutputs& out);

  // Multiply-accumulates of one sample's forward pass in convolutions and linear layers
  // (element-wise work not counted); x2 for FLOPs, about x3 again for forward + backward.
  virtual int64_t multiply_accumulates() const = 0;

 protected:
  virtual Trunk trunk_batch(const torch::Tensor& grid, const torch::Tensor& proprio) = 0;
  virtual torch::Tensor dense_head_forward(const torch::Tensor& pooled) = 0;

 private:
  NetConfig config_;
};

std::shared_ptr<QAttentionModule> make_qattention_module(const NetConfig& config);
// The U-Net's downsampling: 3x3x3 max pooling, stride 2, padding 1, over [B, C, D, H, W].
// Without gradients (acting, the targets' forwards) it is elementwise maxima of strided views,
// one axis at a time: the same values as max_pool3d, which also finds the argmax indices a
// backward pass needs and costs 4-5x as much (PyTorch 1.13, one thread: 4.2 ms against 0.85 ms
// for 10 grids of 16 channels at 16^3; 19% of an inference forward of `light` by PyTorch's
// profiler).
torch::Tensor max_pool(const torch::Tensor& x);

// Our grids are channels last, [B, V, V, V, C] (voxels::voxelize); convolutions want
// [B, C, V, V, V]. Index order x, y, z is kept, so Q volumes come out in our order.
torch::Tensor channels_first(const torch::Tensor& grids);

// Every parameter of the networks (for an optimiser over all depths).
std::vector<torch::Tensor> parameters_of(std::vector<QAttentionNet>& nets);

}  // namespace qte::nets
