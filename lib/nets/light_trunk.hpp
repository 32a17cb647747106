// `light`'s convolutional trunk run by oneDNN alone, forward and backward.
//
// Run layer by layer through LibTorch, every activation is converted between LibTorch's plain
// layout and oneDNN's blocked one around each convolution, and the activations, pooling,
// upsampling and sums are separate passes over plain tensors. Here the activations stay in
// oneDNN's blocked layout from the first convolution to the last: bias and LeakyReLU fused into
// each convolution, pooling and trilinear upsampling as oneDNN primitives, the backward as
// oneDNN's backward primitives (the weight gradients as in nets/onednn.hpp; the upsampling's
// backward our own, in the blocked layout, oneDNN having no vectorised kernel for it). The layers, their
// order and their parameters are LightNet's (nets/qattention_modules.cpp); Q values and
// gradients equal LibTorch's within fp32 rounding (tests/unit/nets/test_light_trunk.cpp).
#pragma once

#include <torch/torch.h>

#include <string>
#include <vector>

namespace qte::nets {

// The trunk of a grid batch [N, C, V, V, V] (channels first) with the proprioception's per-sample
// bias [N, k] added before the first activation, and the ten convolutions' parameters in
// LightNet's order (input, down1.0, down1.2, down2.0, down2.2, lateral2, up1, lateral1, up0, q),
// weight then bias of each. Returns the translation Q values [N, V, V, V] and, with `levels`,
// the four levels the dense head pools (e0, e1, e2, d0), each [N, C_l, ...]. With gradients on,
// the backward reaches proprio_bias and every parameter (not the grid).
std::vector<torch::Tensor> light_trunk(const torch::Tensor& grid, const torch::Tensor& proprio_bias,
                                       const std::vector<torch::Tensor>& parameters, bool levels);

// Whether light_trunk can run these inputs here: float tensors on the CPU, V a multiple of 4,
// and oneDNN vectorised kernels for its convolutions on this processor (chosen by oneDNN at
// run time); LightNet uses LibTorch's layers otherwise.
bool light_trunk_supported(const torch::Tensor& grid, int base_channels);

// The convolutions' arithmetic. bf16: each convolution reads its input and weights rounded to
// bf16 and accumulates in fp32 (oneDNN's kernels for AVX-512 BF16 or AMX, up to twice the fp32
// rate); the activations between layers, pooling, upsampling, sums, every gradient outside the
// convolutions, the parameters, Adam and the Q values stay fp32, so a checkpoint is the same
// whichever precision trained it. Where this processor has no native bf16 kernels for a shape,
// that trunk runs in fp32 (precision_running says which). fp32 is the default.
enum class Precision { fp32, bf16 };
// Whether oneDNN's effective instruction set here has AVX-512 BF16 (or AMX); ONEDNN_MAX_CPU_ISA
// lowers it.
bool bf16_native_here();
// Whether bf16 convolutions are faster than fp32 ones here: where oneDNN has AMX. With AVX-512
// BF16 alone they are not on every processor measured: an Intel Xeon (family 6 model 207) runs
// vdpbf16ps at half the rate of its fp32 multiply-adds, and oneDNN 2.6's bf16 kernels for these
// small-channel 3D convolutions took 1.3x the fp32 step (docs/performance.md).
bool bf16_faster_here();
// --precision's values: auto (bf16 where bf16_faster_here, else fp32), fp32, bf16; Error otherwise.
Precision precision_from_name(const std::string& name);
const char* precision_name(Precision precision);
void use_precision(Precision precision);
Precision precision_requested();
// What a training trunk of that shape runs in here: fp32 unless bf16 is requested, the oneDNN
// trunk is in use and oneDNN has native bf16 kernels for every convolution of it.
Precision precision_running(int64_t batch, int64_t channels, int base_channels, int64_t voxels);

// Whether forwards without gradients (acting, the learner's targets) run oneDNN's inference
// primitives, which keep nothing for a backward (default on). Off, they run the training
// primitives a forward with gradients runs; the benchmarks compare the two in one process.
void use_inference_primitives(bool on);

// Whether LightNet uses light_trunk where it can (default: onednn::layers_by_default()). Off,
// it runs LibTorch's layers; the tests and benchmarks compare the two in one process.
void use_onednn_trunk(bool on);
bool onednn_trunk_in_use();

// Wall time light_trunk has spent since the program started, by pass and by kind of work, for
// the benchmarks' share of the machine and where-the-time-goes tables (a clock read around each
// step: the CPU engine runs its primitives synchronously). The kinds add up to the passes.
struct TrunkTime {
  double training_forward_s = 0;  // forwards with gradients (a learner's training step)
  double backward_s = 0;
  double inference_s = 0;           // forwards without gradients (acting, targets)
  double forward_convolutions_s = 0;  // with their fused bias and LeakyReLU
  double backward_data_s = 0;         // the convolutions' input gradients
  double weight_gradients_s = 0;      // the swapped convolutions and their reorders
  double layouts_s = 0;               // plain <-> blocked conversions at the trunk's ends
  double precision_conversions_s = 0;  // bf16 roundings of the convolutions' inputs and gradients
  double other_s = 0;  // LeakyReLU backwards, pooling, upsampling, sums, bias gradients, buffers
};
TrunkTime light_trunk_time();

}  // namespace qte::nets
