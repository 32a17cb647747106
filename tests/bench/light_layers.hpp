// The layers of the `light` network (lib/nets/qattention_modules.cpp, LightNet) at 16 base
// channels, 10 input channels and a 16^3 grid, with their multiply-accumulates: the benchmarks'
// FLOP counts (2 FLOPs a multiply-accumulate) for GFLOP/s and the share of the machine's peak.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nets/onednn.hpp"
#include "nets/qattention_net.hpp"

namespace qte::bench {

struct Layer {
  std::string name;
  int in, out, kernel, voxels;  // kernel 0: a linear layer (voxels 1)
  int64_t macs_per_sample() const {
    const int64_t v = static_cast<int64_t>(voxels) * voxels * voxels;
    return kernel == 0 ? static_cast<int64_t>(in) * out
                       : v * in * out * static_cast<int64_t>(kernel) * kernel * kernel;
  }
};

// e0 at 16^3, e1 at 8^3, e2 at 4^3, then back up; the trunk's ten convolutions, then the dense
// head of the last depth, which pools 4 levels of 16 + 32 + 64 + 16 channels.
inline std::vector<Layer> light_layers() {
  const int k = 16, c = 10;
  return {{"input conv3", c, k, 3, 16},          {"down1.0 conv3", k, 2 * k, 3, 8},
          {"down1.2 conv3", 2 * k, 2 * k, 3, 8}, {"down2.0 conv3", 2 * k, 4 * k, 3, 4},
          {"down2.2 conv3", 4 * k, 4 * k, 3, 4}, {"lateral2 conv1", 4 * k, 2 * k, 1, 4},
          {"up1 conv3", 2 * k, 2 * k, 3, 8},     {"lateral1 conv1", 2 * k, k, 1, 8},
          {"up0 conv3", k, k, 3, 16},            {"q conv1", k, 1, 1, 16},
          {"head.0 linear", 4 * 128, 128, 0, 1}, {"head.2 linear", 128, 128, 0, 1},
          {"head.4 linear", 128, nets::kRotationAxes * nets::kRotationBins + nets::kGripperActions, 0, 1}};
}

// The FLOPs of one sample through the convolutional trunk: the forward, the input gradients
// (every convolution's but the first's: the grid needs none) and the weight gradients.
struct TrunkFlops {
  double forward = 0, backward_data = 0, weight_gradients = 0;
  double training() const { return forward + backward_data + weight_gradients; }
};

inline TrunkFlops light_trunk_flops() {
  TrunkFlops f;
  bool first = true;
  for (const Layer& l : light_layers()) {
    if (l.kernel == 0) continue;
    const double flops = 2.0 * static_cast<double>(l.macs_per_sample());
    f.forward += flops, f.weight_gradients += flops;
    if (!first) f.backward_data += flops;
    first = false;
  }
  return f;
}

// Whether the weight gradients run by oneDNN's own backward-weights kernel on this processor
// (nets/onednn.hpp), asked for down1.0's shape at batch 32: the choice is the processor's, not
// the layer's.
inline bool native_weight_gradient_here() {
  const auto desc = [](int channels) {
    return dnnl::memory::desc({32, channels, 8, 8, 8}, dnnl::memory::data_type::f32, dnnl::memory::format_tag::ncdhw);
  };
  return nets::onednn::weight_gradient_native(desc(16), desc(32), 1);
}

}  // namespace qte::bench
