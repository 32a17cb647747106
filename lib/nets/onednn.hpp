// oneDNN used directly by the networks (the library LibTorch itself runs its convolutions with,
// from Debian): one CPU engine, buffers owned by tensors, and the weight gradient of a 3D
// convolution by whichever of two ways oneDNN has a vectorised kernel for on this processor.
#pragma once

#include <oneapi/dnnl/dnnl.hpp>
#include <torch/torch.h>

namespace qte::nets::onednn {

const dnnl::engine& engine();

// Whether the networks' layers use oneDNN directly (nets/conv3d.hpp, nets/light_trunk.hpp)
// unless a program says otherwise: yes, unless the environment variable QTE_NETWORK_LAYERS is
// `libtorch` (LibTorch's layers throughout: a comparison kept on one implementation, such as a
// campaign begun with it). Any other value than `libtorch` or `onednn` is an Error.
bool layers_by_default();

// A oneDNN memory over a new tensor's storage (freed with the tensor).
struct Buffer {
  torch::Tensor storage;
  dnnl::memory memory;
};
Buffer buffer(const dnnl::memory::desc& desc);
// A memory of `desc` over an existing tensor's storage.
dnnl::memory over(const torch::Tensor& storage, const dnnl::memory::desc& desc);

// The weight gradient [O, I, k, k, k] (LibTorch's layout) of a stride-1 3D convolution padded by
// `padding` on every side, from its input x [N, I, ...] and output gradient dy [N, O, ...], each
// in any layout oneDNN knows, each f32 or bf16 (the gradient is f32 either way). Computed by oneDNN's own backward-weights primitive where it has a
// vectorised kernel for the shape on this processor (AVX-512 machines), otherwise as a forward
// convolution with batch and channels swapped (nets/conv3d.hpp says why: AVX2 machines). An
// input of few channels (the grid's 10), for which oneDNN's own kernel is im2col + GEMM, has its
// channels zero-padded to 16 for the vectorised kernel where that has one.
torch::Tensor weight_gradient(const dnnl::memory& x, const dnnl::memory& dy, int64_t padding);
// Whether oneDNN has a vectorised kernel for that computation on this processor, and whether it
// is oneDNN's own backward-weights primitive (not the swapped convolution).
bool weight_gradient_vectorised(const dnnl::memory::desc& x, const dnnl::memory::desc& dy, int64_t padding);
bool weight_gradient_native(const dnnl::memory::desc& x, const dnnl::memory::desc& dy, int64_t padding);
// Off, weight_gradient always computes the swapped convolution (default on); the tests and
// benchmarks compare the two in one process.
void use_native_weight_gradient(bool on);
// Off, an input whose channels are not a multiple of 16 (the grid's 10) gets no native kernel
// with its channels zero-padded to 16 (default on; the benchmarks compare the two).
void use_padded_weight_gradient(bool on);

}  // namespace qte::nets::onednn
