// The networks' 3D convolutions, with a faster weight gradient.
//
// LibTorch 1.13 hands a float 3D convolution's backward to oneDNN, which on processors without
// AVX-512 has no vectorised kernel for the weight gradient of a 3D convolution and falls back to
// im2col + GEMM: for `light`'s small channel counts that runs at 17-30% of the machine's peak,
// where its forward runs at 55-75% (tests/bench/bench_nets_layers). The weight gradient is
// itself a convolution, with batch and channels swapped:
//
//   dW[o, i, k] = sum over n, x of  dY[n, o, x] * X[n, i, x + k - p]
//
// is a forward convolution of an input with batch i and channels n (X, swapped) by a kernel with
// outputs o, inputs n and the spatial size of dY, padded by p, giving a k^3 output. oneDNN runs
// that forward with its vectorised kernel (3-4x the GEMM path's speed on AVX2, same sums in
// another order). Where oneDNN does have a vectorised weight-gradient kernel (AVX-512), that is
// used instead (nets/onednn.hpp). oneDNN chooses the kernels for the processor at run time; where
// it offers only its reference or GEMM code for both, LibTorch's own weight gradient is used.
#pragma once

#include <torch/torch.h>

namespace qte::nets {

// A Conv3d (same options, same parameter names) whose backward computes the weight gradient as
// above when its options allow (zero padding, stride 1, no dilation, one group, float on the
// CPU); otherwise exactly Conv3d.
class Conv3dLayerImpl : public torch::nn::Conv3dImpl {
 public:
  using torch::nn::Conv3dImpl::Conv3dImpl;
  torch::Tensor forward(const torch::Tensor& input);
};
TORCH_MODULE(Conv3dLayer);

// The weight gradient of a stride-1 3D convolution with `padding` on every side, from its input
// x [N, I, D, H, W] and output gradient dy [N, O, D', H', W']: [O, I, k, k, k].
torch::Tensor conv3d_weight_gradient(const torch::Tensor& x, const torch::Tensor& dy, int64_t padding);

// Whether Conv3dLayer's backward uses conv3d_weight_gradient (default: onednn::layers_by_default(),
// and only where oneDNN has a vectorised kernel for it on this processor). Off, it is LibTorch's backward throughout; the
// benchmarks and tests compare the two in one process.
void use_swapped_weight_gradient(bool on);
bool swapped_weight_gradient_in_use();

}  // namespace qte::nets
