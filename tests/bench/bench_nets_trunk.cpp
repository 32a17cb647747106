// `light`'s convolutional trunk (lib/nets/qattention_modules.cpp, LightNet) three ways, alternated
// run by run in one process: LibTorch's layers; LibTorch's layers with the swapped weight
// gradient (nets/conv3d.hpp); the trunk run by oneDNN alone (nets/light_trunk.hpp, the default),
// and, where oneDNN has its own vectorised weight-gradient kernel here (AVX-512), the trunk
// with the swapped weight gradient instead (nets/onednn.hpp).
// For each: the training forward, forward + backward (the backward reaching every parameter, as
// in a learner step: a loss on the Q values and, at the last depth, on the head's levels) and
// the no-gradient forward, at the training batch (32), a tree expansion's branches (20) and
// acting (2: a single grid runs as a pair), for depth 0 and the last depth, on --threads.
// For the oneDNN trunk's forward + backward at batch 32, where the time goes (forward
// convolutions, input gradients, weight gradients, layout conversions, the rest: element-wise
// work, pooling, upsampling, sums) with each convolution kind's GFLOP/s, and the line
// `trunk: N GFLOP/s, P% of peak` against the machine's fp32 peak measured on as many threads.
// Options: --reps R (median of R, default 7), --threads N (default 2), --only-onednn (the oneDNN
// trunk alone: with ONEDNN_VERBOSE=1, each of its primitives' times).
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "light_layers.hpp"
#include "machine_peak.hpp"
#include "nets/conv3d.hpp"
#include "nets/light_trunk.hpp"
#include "nets/onednn.hpp"
#include "nets/qattention_modules.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Way {
  const char* name;
  bool swapped, onednn, native;
  std::vector<double> forward, training, inference;
};

// The oneDNN trunk's training passes by kind of work (nets/light_trunk.hpp), one entry a rep.
struct Breakdown {
  std::vector<double> convolutions, backward_data, weight_gradients, layouts, other, total;
  void add(const qte::nets::TrunkTime& a, const qte::nets::TrunkTime& b) {
    convolutions.push_back(b.forward_convolutions_s - a.forward_convolutions_s);
    backward_data.push_back(b.backward_data_s - a.backward_data_s);
    weight_gradients.push_back(b.weight_gradients_s - a.weight_gradients_s);
    layouts.push_back(b.layouts_s - a.layouts_s);
    other.push_back(b.other_s - a.other_s);
    total.push_back(b.training_forward_s + b.backward_s - a.training_forward_s - a.backward_s);
  }
};

void print_breakdown(const Breakdown& b, int batch, const qte::bench::Peak& peak) {
  const qte::bench::TrunkFlops f = qte::bench::light_trunk_flops();
  const auto row = [&](const char* what, const std::vector<double>& t, double flops_per_sample) {
    const double s = median(t);
    std::printf("    %-22s %7.2f ms  %3.0f%%", what, 1e3 * s, 100 * s / median(b.total));
    if (flops_per_sample > 0) {
      const double gflops = flops_per_sample * batch / 1e9 / s;
      std::printf("  %6.1f GFLOP/s, %3.0f%% of peak", gflops, 100 * gflops / peak.gflops);
    }
    std::printf("\n");
  };
  std::printf("oneDNN trunk, forward + backward, where the time goes (median of each):\n");
  row("forward convolutions", b.convolutions, f.forward);
  row("input gradients", b.backward_data, f.backward_data);
  row("weight gradients", b.weight_gradients, f.weight_gradients);
  row("layout conversions", b.layouts, 0);
  row("the rest", b.other, 0);
  row("all", b.total, f.training());
}

}  // namespace

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);
  int reps = 7, threads = 2;
  bool only_onednn = false;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--only-onednn")) only_onednn = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--reps")) reps = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--threads")) threads = std::max(1, std::atoi(argv[i + 1]));
  }
  qte::nets::set_torch_threads(threads);
  torch::manual_seed(0);
  // The peak, before and after the timings (the larger: a virtual machine's varies by a fifth).
  qte::bench::Peak peak = qte::bench::measure_fp32_peak(threads);
  const int depths = 2;
  const bool native_here = qte::bench::native_weight_gradient_here();
  double trunk_s = 0;
  std::vector<std::pair<std::string, Breakdown>> breakdowns;  // printed at the end, against the peak
  std::printf("light's trunk (16^3 grid, 10 channels, 16 base channels), %d threads, median of %d, alternated\n",
              threads, reps);
  for (const bool last : {false, true}) {
    qte::nets::NetConfig config;
    config.is_last = last;
    const auto net = qte::nets::make_qattention_module(config);
    for (const int batch : {32, 20, 2}) {
      const auto grid = torch::rand({batch, config.channels, config.voxels, config.voxels, config.voxels});
      const auto proprio = torch::rand({batch, config.proprio});
      Breakdown breakdown;
      std::vector<Way> ways{{"LibTorch's layers", false, false, false, {}, {}, {}},
                            {"+ swapped weight gradient", true, false, false, {}, {}, {}},
                            {"oneDNN trunk", true, true, true, {}, {}, {}}};
      if (native_here) ways.push_back({"oneDNN trunk, swapped dW", true, true, false, {}, {}, {}});
      if (only_onednn) ways.erase(ways.begin(), ways.begin() + 2);
      for (int r = 0; r <= reps; ++r)  // r = 0 warms up (primitives created, buffers allocated)
        for (Way& w : ways) {
          qte::nets::use_swapped_weight_gradient(w.swapped);
          qte::nets::use_onednn_trunk(w.onednn);
          qte::nets::onednn::use_native_weight_gradient(w.native);
          net->zero_grad();
          const qte::nets::TrunkTime before = qte::nets::light_trunk_time();
          auto t0 = Clock::now();
          const qte::nets::Trunk trunk = net->trunk(grid, proprio);
          const double forward = std::chrono::duration<double>(Clock::now() - t0).count();
          auto loss = trunk.translation.sum();
          for (const auto& level : trunk.levels) loss = loss + level.mean();
          loss.backward();
          const double training = std::chrono::duration<double>(Clock::now() - t0).count();
          if (w.onednn && w.native && r > 0) breakdown.add(before, qte::nets::light_trunk_time());
          t0 = Clock::now();
          {
            torch::NoGradGuard no_grad;
            net->trunk(grid, proprio);
          }
          const double inference = std::chrono::duration<double>(Clock::now() - t0).count();
          if (r == 0) continue;
          w.forward.push_back(forward), w.training.push_back(training), w.inference.push_back(inference);
        }
      std::printf("%s, batch %d:\n", last ? "last depth" : "depth 0", batch);
      for (const Way& w : ways)
        std::printf("  %-26s forward %7.2f ms, forward+backward %7.2f ms (%.2fx as fast), no-grad forward %7.2f ms "
                    "(%.2fx)\n",
                    w.name, 1e3 * median(w.forward), 1e3 * median(w.training),
                    median(ways[0].training) / median(w.training), 1e3 * median(w.inference),
                    median(ways[0].inference) / median(w.inference));
      if (batch == 32 && !breakdown.total.empty()) {
        breakdowns.emplace_back(last ? "last depth" : "depth 0", breakdown);
        trunk_s += median(breakdown.total) * (last ? 1 : depths - 1);
      }
    }
  }
  peak.gflops = std::max(peak.gflops, qte::bench::measure_fp32_peak(threads).gflops);
  for (const auto& [depth, breakdown] : breakdowns) {
    std::printf("%s, batch 32, ", depth.c_str());
    print_breakdown(breakdown, 32, peak);
  }
  // A learner step's trunk: depth 0's network at every depth but the last, then the last's.
  const double gflop = qte::bench::light_trunk_flops().training() * 32 * depths / 1e9;
  std::printf("trunk: %.1f GFLOP/s, %.0f%% of peak (forward + backward at batch 32 of %d depths' networks: %.1f GFLOP "
              "in %.3f s; peak %.0f GFLOP/s fp32 on %d threads, %s)\n",
              gflop / trunk_s, 100 * gflop / trunk_s / peak.gflops, depths, gflop, trunk_s, peak.gflops, threads,
              peak.isa.c_str());
  qte::nets::use_swapped_weight_gradient(true);
  qte::nets::use_onednn_trunk(true);
  qte::nets::onednn::use_native_weight_gradient(true);
  return 0;
}
