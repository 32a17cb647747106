// Inference cost per grid of one depth's network (no gradients), the cost that tree-expanded
// targets multiply: B (1 + K) grids per step. Compares, interleaved in one run so that a noisy
// machine hits every variant alike: QAttentionNet::predict as shipped, and the module's forward
// with the input and weights in NCDHW or NDHWC (channels-last, oneDNN's preferred layout and
// our grids' native one), in chunks of 16, 32, 64 samples, under NoGradGuard or InferenceMode.
//
// Options: --arch light|arm, --grids N (default 352 = 32 x (1 + 10)), --threads N (default 1),
//          --reps N (default 5), --last (the last depth's network, with the dense head).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <ATen/autocast_mode.h>

#include "nets/qattention_modules.hpp"

using namespace qte::nets;
using Clock = std::chrono::steady_clock;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Variant {
  std::string name;
  std::function<void()> run;
  std::vector<double> seconds;
};

}  // namespace

int main(int argc, char** argv) {
  prepare_process_for_networks(argv);
  std::string arch = "light";
  int grids = 352, threads = 1, reps = 5;
  bool last = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--arch" && i + 1 < argc) arch = argv[++i];
    else if (a == "--grids" && i + 1 < argc) grids = std::stoi(argv[++i]);
    else if (a == "--threads" && i + 1 < argc) threads = std::stoi(argv[++i]);
    else if (a == "--reps" && i + 1 < argc) reps = std::stoi(argv[++i]);
    else if (a == "--last") last = true;
    else {
      std::fprintf(stderr, "bench_nets_predict: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  set_torch_threads(threads);
  seed_torch(0);
  NetConfig config;
  config.architecture = architecture_from_name(arch);
  config.base_channels = default_base_channels(config.architecture);
  config.is_last = last;
  QAttentionNet shipped(config), nchw(config), nhwc(config);
  {
    torch::NoGradGuard no_grad;
    for (auto& p : nhwc.module().parameters())
      if (p.dim() == 5) p.set_data(p.contiguous(torch::MemoryFormat::ChannelsLast3d));
  }
  const int v = config.voxels, c = config.channels;
  std::vector<float> data(static_cast<std::size_t>(grids) * v * v * v * c), proprio(grids * config.proprio);
  {
    auto g = torch::rand({static_cast<int64_t>(data.size())});
    std::memcpy(data.data(), g.data_ptr<float>(), data.size() * sizeof(float));
  }
  const auto input = torch::from_blob(data.data(), {grids, v, v, v, c});
  const auto state = torch::from_blob(proprio.data(), {grids, config.proprio});
  const auto chunked = [&](QAttentionNet& net, int chunk, bool channels_last, bool inference_mode,
                           bool bfloat16 = false) {
    return [&, chunk, channels_last, inference_mode, bfloat16] {
      std::unique_ptr<c10::InferenceMode> im;
      std::unique_ptr<torch::NoGradGuard> ng;
      if (inference_mode) im = std::make_unique<c10::InferenceMode>();
      else ng = std::make_unique<torch::NoGradGuard>();
      // CPU autocast: convolutions and matrix products in bfloat16 (AVX-512 BF16 here).
      at::autocast::set_cpu_enabled(bfloat16);
      at::autocast::set_autocast_cpu_dtype(at::kBFloat16);
      for (int first = 0; first < grids; first += chunk) {
        const int n = std::min(chunk, grids - first);
        const auto g = input.slice(0, first, first + n).permute({0, 4, 1, 2, 3});
        const auto x = channels_last ? g.contiguous(torch::MemoryFormat::ChannelsLast3d) : g.contiguous();
        const QOutputs out = net.module().forward(x, state.slice(0, first, first + n));
        (void)out.translation.to(torch::kFloat).contiguous().data_ptr<float>();
      }
      at::autocast::set_cpu_enabled(false);
      at::autocast::clear_cache();
    };
  };
  std::vector<Variant> variants;
  variants.push_back({"predict (shipped)", [&] { shipped.predict(data.data(), proprio.data(), grids); }, {}});
  for (int chunk : {16, 64})
    variants.push_back({"NCDHW chunk " + std::to_string(chunk), chunked(nchw, chunk, false, false), {}});
  for (int chunk : {16, 32})
    variants.push_back({"NDHWC chunk " + std::to_string(chunk), chunked(nhwc, chunk, true, false), {}});
  variants.push_back({"NCDHW chunk 32 inference mode", chunked(nchw, 32, false, true), {}});
  variants.push_back({"NCDHW chunk 32 inference, bf16 autocast", chunked(nchw, 32, false, true, true), {}});
  variants.push_back({"NDHWC chunk 32 inference, bf16 autocast", chunked(nhwc, 32, true, true, true), {}});
  for (auto& variant : variants) variant.run();  // warm-up
  for (int r = 0; r < reps; ++r)
    for (auto& variant : variants) {
      const auto t0 = Clock::now();
      variant.run();
      variant.seconds.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
  std::printf("%s%s, %d grids, %d thread(s), median of %d\n", arch.c_str(), last ? " (last depth)" : "", grids,
              threads, reps);
  const double base = median(variants.front().seconds);
  for (const auto& variant : variants) {
    const double s = median(variant.seconds);
    std::printf("  %-38s %7.3f s  %6.2f ms/grid  %.2fx shipped\n", variant.name.c_str(), s, 1000 * s / grids,
                s / base);
  }
}
