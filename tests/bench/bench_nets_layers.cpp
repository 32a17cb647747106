// Where a learner step's time goes, layer by layer: each convolution and linear layer of the
// `light` network (16 base channels, 10 input channels, a 16^3 grid; the dense head of the
// last depth), as LibTorch runs it, timed alone with its input and output shapes of the real
// network: the forward and the backward at the training batch (32), the Adam update of its
// parameters, and the no-gradient forward at the batch sizes of acting (2: a single grid runs
// as a pair) and of the targets (32 next states; 320 with K = 10 branches each), on 1 and 2
// threads. For each: milliseconds, GFLOP/s (2 FLOPs a multiply-accumulate; the backward
// computes input and weight gradients, twice the forward's, except the first layer's: its
// input is the grid, which needs no gradient) and the share of the machine's fp32 peak
// measured on as many threads (machine_peak.hpp). The backward is the networks' own (the weight
// gradient by oneDNN's own kernel where it has a vectorised one, swapped otherwise:
// nets/conv3d.hpp, nets/onednn.hpp); LibTorch's backward of the same layer is timed beside it
// (last column). Element-wise layers (LeakyReLU,
// pooling, upsampling) are not listed: their cost is the difference between the sum here and
// bench_nets_learner's step.
// Options: --threads N (only N), --reps R (median of R, default 5), --batch B (default 32).
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "light_layers.hpp"
#include "machine_peak.hpp"
#include "nets/conv3d.hpp"
#include "nets/qattention_net.hpp"

using Clock = std::chrono::steady_clock;

namespace {

using qte::bench::Layer;
using qte::bench::light_layers;

torch::nn::AnyModule make(const Layer& l) {
  if (l.kernel == 0) return torch::nn::AnyModule(torch::nn::Linear(l.in, l.out));
  return torch::nn::AnyModule(
      qte::nets::Conv3dLayer(torch::nn::Conv3dOptions(l.in, l.out, l.kernel).padding(l.kernel / 2)));
}

torch::Tensor input_for(const Layer& l, int batch) {
  if (l.kernel == 0) return torch::randn({batch, l.in});
  return torch::randn({batch, l.in, l.voxels, l.voxels, l.voxels});
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <typename F>
double seconds(int reps, F&& f) {
  f();  // warm-up: allocations, kernels chosen
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return median(t);
}

struct Totals {
  double forward = 0, backward = 0, adam = 0;
};

void run(int threads, int reps, int batch) {
  qte::nets::set_torch_threads(threads);
  const qte::bench::Peak peak = qte::bench::measure_fp32_peak(threads);
  std::printf("\n%d thread(s): machine peak %.0f GFLOP/s fp32 (%s, measured); training batch %d\n", threads, peak.gflops,
              peak.isa.c_str(), batch);
  std::printf("%-15s %9s | %9s %7s %5s | %9s %7s %5s | %8s | %-28s | LibTorch's bwd ms\n", "layer", "MMAC/smp",
              "fwd ms", "GFLOP/s", "peak", "bwd ms", "GFLOP/s", "peak", "adam ms", "no-grad fwd ms, batch 2/32/320");
  const auto share = [&](double gflops) { return 100 * gflops / peak.gflops; };
  Totals total;
  double total_gflop = 0, total_bwd_gflop = 0, total_torch_backward = 0;
  const std::vector<Layer> layers = light_layers();
  for (const Layer& l : layers) {
    torch::nn::AnyModule m = make(l);
    auto parameters = m.ptr()->parameters();
    torch::optim::Adam adam(parameters, torch::optim::AdamOptions(1e-4));
    const bool first = &l == &layers.front();  // its input is the grid: no input gradient
    const torch::Tensor x = input_for(l, batch).requires_grad_(!first);
    torch::Tensor y;
    const double fwd = seconds(reps, [&] { y = m.forward(x); });
    const torch::Tensor grad = torch::ones_like(y);
    const auto forward_backward = [&](bool swapped) {
      qte::nets::use_swapped_weight_gradient(swapped);
      return seconds(reps, [&] {
        adam.zero_grad();
        m.forward(x).backward(grad);
      });
    };
    const double torch_fwd_bwd = forward_backward(false), fwd_bwd = forward_backward(true);
    const double step = seconds(reps, [&] { adam.step(); });
    std::vector<double> inference;
    for (int b : {2, 32, 320}) {
      torch::NoGradGuard no_grad;
      const torch::Tensor xi = input_for(l, b);
      inference.push_back(seconds(reps, [&] { m.forward(xi); }));
    }
    const double bwd = std::max(1e-9, fwd_bwd - fwd), torch_bwd = std::max(1e-9, torch_fwd_bwd - fwd);
    const double gflop = static_cast<double>(l.macs_per_sample()) * 2 * batch / 1e9;
    const double bwd_gflop = (first ? 1 : 2) * gflop;
    char no_grad[64];
    std::snprintf(no_grad, sizeof no_grad, "%.2f / %.2f / %.2f", inference[0] * 1e3, inference[1] * 1e3,
                  inference[2] * 1e3);
    std::printf("%-15s %9.2f | %9.2f %7.1f %4.0f%% | %9.2f %7.1f %4.0f%% | %8.3f | %-28s | %.2f\n", l.name.c_str(),
                l.macs_per_sample() / 1e6, fwd * 1e3, gflop / fwd, share(gflop / fwd), bwd * 1e3, bwd_gflop / bwd,
                share(bwd_gflop / bwd), step * 1e3, no_grad, torch_bwd * 1e3);
    total.forward += fwd, total.backward += bwd, total.adam += step;
    total_gflop += gflop, total_bwd_gflop += bwd_gflop, total_torch_backward += torch_bwd;
  }
  std::printf("%-15s %9s | %9.2f %7.1f %4.0f%% | %9.2f %7.1f %4.0f%% | %8.3f | %-28s | %.2f\n", "all layers", "",
              total.forward * 1e3, total_gflop / total.forward, share(total_gflop / total.forward), total.backward * 1e3,
              total_bwd_gflop / total.backward, share(total_bwd_gflop / total.backward), total.adam * 1e3, "",
              total_torch_backward * 1e3);
  const double trunk_gflop = total_gflop + total_bwd_gflop;
  std::printf("trunk layers, forward + backward: %.1f GFLOP/s, %.0f%% of peak; with LibTorch's backward %.1f GFLOP/s, "
              "%.0f%% (one depth's network, batch %d; the learner step runs one per depth, plus the element-wise "
              "layers and the targets)\n",
              trunk_gflop / (total.forward + total.backward), share(trunk_gflop / (total.forward + total.backward)),
              trunk_gflop / (total.forward + total_torch_backward),
              share(trunk_gflop / (total.forward + total_torch_backward)), batch);
}

}  // namespace

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);
  int only_threads = 0, reps = 5, batch = 32;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--threads")) only_threads = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--reps")) reps = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--batch")) batch = std::max(1, std::atoi(argv[i + 1]));
  }
  torch::manual_seed(0);
  std::printf("light (16 base channels, 10 channels in, 16^3 grid): each layer timed alone, median of %d\n", reps);
  for (int threads : {1, 2})
    if (only_threads == 0 || only_threads == threads) run(threads, reps, batch);
  return 0;
}
