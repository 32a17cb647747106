// Prints the cost of the Q-attention networks on 2 threads: parameters, one training step
// (forward + backward + Adam) at batch 32 and 128, one batch-1 forward, and the achieved
// GFLOP/s. FLOPs are counted from the convolution and linear multiply-accumulates
// (QAttentionModule::multiply_accumulates): forward = 2 x MACs; a training step ~ 3 x forward
// (the backward pass computes both input and weight gradients, each as costly as the forward).
// Element-wise work (activations, pooling, upsampling, Adam) is not counted.
//
// Compare with the PyTorch reference of ARM's published Q-attention network (its `Net`
// module; not part of this repository), run back to back with 2 threads.
// Options: --quick (skip arm at batch 128), --sweep (light at 8..32 base channels),
//          --light (one line: light's b32 step at depth 0 and the last, for bench_light_vs_torch),
//          --threads N (default 2), --export DIR (files for torch_reference_step.py, which
//          checks our arm network against the reference's forward pass and training step).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "machine_peak.hpp"
#include "nets/checkpoint.hpp"
#include "nets/qattention_modules.hpp"
#include "stream/writer.hpp"

using namespace qte::nets;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The reference's loss: mean Q plus the mean of the 218 head outputs.
torch::Tensor reference_loss(const QOutputs& out) {
  auto loss = out.translation.mean();
  if (out.rotation.defined()) loss = loss + torch::cat({out.rotation.flatten(1), out.gripper}, 1).mean();
  return loss;
}

// Median seconds of `reps` training steps after one warm-up step, with the reference's loss.
bool channels_last = false;  // --channels-last: weights and inputs in oneDNN's NDHWC layout

void to_channels_last(QAttentionNet& net) {
  torch::NoGradGuard no_grad;
  for (auto& p : net.module().parameters())
    if (p.dim() == 5) p.set_data(p.contiguous(torch::MemoryFormat::ChannelsLast3d));
}

double train_step_seconds(QAttentionNet& net, int batch, int reps) {
  const NetConfig& c = net.config();
  auto grids = torch::randn({batch, c.channels, c.voxels, c.voxels, c.voxels});
  if (channels_last) {
    to_channels_last(net);
    grids = grids.contiguous(torch::MemoryFormat::ChannelsLast3d);
  }
  const auto proprio = torch::randn({batch, c.proprio});
  torch::optim::Adam adam(net.module().parameters(), torch::optim::AdamOptions(5e-4));
  const auto step = [&] {
    const auto loss = reference_loss(net.module().forward(grids, proprio));
    adam.zero_grad();
    loss.backward();
    adam.step();
  };
  step();
  std::vector<double> times;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    step();
    times.push_back(seconds_since(t0));
  }
  return median(times);
}

double forward_seconds(QAttentionNet& net, int reps) {
  const NetConfig& c = net.config();
  const auto grids = torch::randn({1, c.channels, c.voxels, c.voxels, c.voxels});
  const auto proprio = torch::randn({1, c.proprio});
  torch::NoGradGuard no_grad;
  net.module().forward(grids, proprio);
  std::vector<double> times;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    net.module().forward(grids, proprio);
    times.push_back(seconds_since(t0));
  }
  return median(times);
}

struct Figures {
  double train32 = 0, train128 = 0, forward1 = 0;
};

double peak_gflops = 0;  // the machine's measured fp32 peak on the benchmark's threads (main)

Figures bench(Architecture architecture, int base_channels, bool last, bool with_batch_128, int proprio) {
  NetConfig config;
  config.architecture = architecture;
  config.base_channels = base_channels;
  config.is_last = last;
  config.depth = last ? 1 : 0;
  config.proprio = proprio;
  QAttentionNet net(config);
  const bool heavy = architecture == Architecture::arm && base_channels >= 32;
  const double macs = static_cast<double>(net.module().multiply_accumulates());
  Figures f;
  f.train32 = train_step_seconds(net, 32, heavy ? 2 : 5);
  if (with_batch_128) f.train128 = train_step_seconds(net, 128, heavy ? 1 : 3);
  f.forward1 = forward_seconds(net, heavy ? 10 : 50);
  const auto train_gflops = [&](int batch, double t) { return macs * 2 * 3 * batch / t / 1e9; };
  std::printf("%-5s k=%-2d %-10s %8lld params %6.3f GMAC/sample | train b32 %7.3f s (%5.1f GFLOP/s, %2.0f%% of peak)",
              architecture_name(architecture), base_channels, last ? "last depth" : "depth 0",
              static_cast<long long>(net.parameter_count()), macs / 1e9, f.train32, train_gflops(32, f.train32),
              100 * train_gflops(32, f.train32) / peak_gflops);
  if (with_batch_128) std::printf(" | b128 %7.3f s (%5.1f GFLOP/s)", f.train128, train_gflops(128, f.train128));
  std::printf(" | fwd b1 %7.2f ms (%5.1f GFLOP/s)\n", f.forward1 * 1e3, macs * 2 / f.forward1 / 1e9);
  std::fflush(stdout);
  return f;
}

void set_tensor(qte::stream::Record& record, const std::string& name, const torch::Tensor& t) {
  const auto c = t.detach().contiguous();
  record.set<float>(name, qte::stream::Shape(c.sizes().begin(), c.sizes().end()), c.data_ptr<float>());
}

// The arm stack as the reference builds it (11 proprio inputs) from seed 0, its outputs on a
// random batch, and its weights and Adam state after one step with the reference's loss.
void export_reference_check(const std::string& dir) {
  seed_torch(0);
  NetConfig config;
  config.architecture = Architecture::arm;
  config.base_channels = 64;
  config.proprio = 11;
  auto nets = make_coarse_to_fine_nets(config, 2);
  save_checkpoint(dir + "/arm_before.rec", nets, nullptr, 0);
  torch::manual_seed(1);
  const auto grids = torch::randn({2, 10, 16, 16, 16});
  const auto proprio = torch::randn({2, 11});
  qte::stream::Record io("net_check");
  set_tensor(io, "grid", grids);
  set_tensor(io, "proprio", proprio);
  torch::optim::Adam adam(parameters_of(nets), torch::optim::AdamOptions(5e-4));
  torch::Tensor loss = torch::zeros({});
  for (auto& net : nets) {
    const QOutputs out = net.module().forward(grids, proprio);
    const std::string prefix = "depth" + std::to_string(net.config().depth) + ".";
    set_tensor(io, prefix + "translation", out.translation);
    if (out.rotation.defined())
      set_tensor(io, prefix + "rotation", out.rotation), set_tensor(io, prefix + "gripper", out.gripper);
    loss = loss + reference_loss(out);
  }
  adam.zero_grad();
  loss.backward();
  adam.step();
  save_checkpoint(dir + "/arm_after.rec", nets, &adam, 1);
  qte::stream::RecordWriter writer(dir + "/arm_io.rec");
  writer.write(io);
  writer.close();
  std::printf("wrote %s/arm_before.rec, arm_io.rec, arm_after.rec\n", dir.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);  // fair figures while other programs run
  bool quick = false, sweep = false, light_only = false;
  int threads = 2;
  std::string export_dir;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick"))
      quick = true;
    else if (!std::strcmp(argv[i], "--sweep"))
      sweep = true;
    else if (!std::strcmp(argv[i], "--light"))
      light_only = true;
    else if (!std::strcmp(argv[i], "--channels-last"))
      channels_last = true;
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--export") && i + 1 < argc)
      export_dir = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_nets [--quick] [--sweep] [--light] [--threads N] [--export DIR]\n");
      return 2;
    }
  }
  set_torch_threads(threads);
  if (!export_dir.empty()) {
    export_reference_check(export_dir);
    return 0;
  }
  seed_torch(0);
  if (light_only) {  // one line, for bench_light_vs_torch (the PyTorch peer's format)
    NetConfig config;
    config.architecture = Architecture::light;
    config.base_channels = 16;
    QAttentionNet depth0(config);
    config.is_last = true;
    QAttentionNet last(config);
    const double t0 = train_step_seconds(depth0, 32, 5), t1 = train_step_seconds(last, 32, 5);
    std::printf("ours light train step b32 (%d threads): depth 0 %.4f s, last depth %.4f s\n", threads, t0, t1);
    return 0;
  }
  std::printf("threads=%d, grid 16^3 x 10 channels, proprio 4 (arm also with the reference's 11)\n", threads);
  const qte::bench::Peak peak = qte::bench::measure_fp32_peak(threads);
  peak_gflops = peak.gflops;
  std::printf("machine peak: %.0f GFLOP/s fp32 on %d threads (%s, measured)\n", peak.gflops, threads, peak.isa.c_str());
  if (sweep || channels_last) {
    for (int k : {8, 16, 24, 32}) bench(Architecture::light, k, false, false, 4);
    return 0;
  }
  const Figures light0 = bench(Architecture::light, 16, false, true, 4);
  const Figures light1 = bench(Architecture::light, 16, true, true, 4);
  const Figures arm0 = bench(Architecture::arm, 64, false, !quick, 11);
  const Figures arm1 = bench(Architecture::arm, 64, true, !quick, 11);
  std::printf("arm / light, train step b32: depth 0 %.1fx, last depth %.1fx; forward b1: %.1fx, %.1fx\n",
              arm0.train32 / light0.train32, arm1.train32 / light1.train32, arm0.forward1 / light0.forward1,
              arm1.forward1 / light1.forward1);
  if (!quick)
    std::printf("arm / light, train step b128: depth 0 %.1fx, last depth %.1fx\n", arm0.train128 / light0.train128,
                arm1.train128 / light1.train128);
}
