// Prints the cost of one full learner step of qattn-train on 2 threads, and what it is made
// of: sampling, the point clouds (kept by the replay: warmed before the timed steps, as in a
// run where every frame has been sampled once), voxelization of the batch (current grids at
// every depth), the bootstrap targets (next-state grids and no-grad forwards of online and
// target networks, or tree expansion with --tree-target), the forwards with gradients and the
// loss, the backward and clipping, Adam and the soft target update: in ms and as shares of the
// step, for fp32 and, where the processor runs it natively, bf16 convolutions. The
// transitions are pick_and_lift demonstrations recorded in-process (10 episodes, 128x128).
//
// The reference's bare network step (forward + backward + Adam at one depth, no data) is
// printed by the PyTorch reference of ARM's published Q-attention network (its `Net` module;
// not part of this repository) with 2 threads; run it back to back (tests/bench/torch_light_ref.py is the same for `light`).
// Options: --arch light|arm, --batch B, --tree-target K, --steps N, --threads N.
//   --compare K: instead, full steps with plain (double-DQN) and tree-expanded (K) targets
//   interleaved step by step, so that a noisy machine hits both alike; prints the ratio.
//   --compare-layers 1: instead, plain full steps with LibTorch's layers, with LibTorch's layers
//   but the swapped weight gradient (nets/conv3d.hpp), and with the oneDNN trunk
//   (nets/light_trunk.hpp, the default; where it uses oneDNN's own weight-gradient kernel,
//   AVX-512, also with the swapped one), interleaved step by step; prints the ratios.
//   --compare-main 1: instead, full steps as the learner ran them before this toolkit kept the
//   replay's point clouds, ran the targets' forwards on inference primitives and padded the
//   grid's channels for the weight gradient ("fp32 as before"); as it runs them now in fp32
//   ("fp32"); and with bf16 convolutions ("bf16", where the processor has AVX-512 BF16 or AMX),
//   interleaved step by step; prints the ratios and what --precision auto picks here.
//   --depths 2|3: the published grid (offset 0.15) or the 3-depth one (0.15,0.05).
//   --precision fp32|bf16|auto: the step's table in that precision only (default: fp32, then
//   bf16 where the processor runs it natively).
//   --every-sample-bootstraps 1: every sample its own next state (discount gamma, no shared
//   states), the targets' worst case; by default the demonstrations' chains end and share
//   keyframes, and the targets evaluate each next state once (the mean count is printed).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "demos/demo_recorder.hpp"
#include "keyframes/transitions.hpp"
#include "learner/q_learner.hpp"
#include "learner/targets.hpp"
#include "machine_peak.hpp"
#include "nets/conv3d.hpp"
#include "light_layers.hpp"
#include "nets/light_trunk.hpp"
#include "nets/onednn.hpp"
#include "nets/qattention_modules.hpp"
#include "replay/replay_buffer.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

static double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);  // fair figures while other programs run
  std::string arch = "light";
  int batch = 32, tree = 0, steps = 5, threads = 2, compare = 0, every_sample = 0, compare_layers = 0;
  int compare_main = 0, depths = 2;
  std::string precision;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--arch") arch = argv[i + 1];
    else if (a == "--batch") batch = std::atoi(argv[i + 1]);
    else if (a == "--tree-target") tree = std::atoi(argv[i + 1]);
    else if (a == "--steps") steps = std::atoi(argv[i + 1]);
    else if (a == "--threads") threads = std::atoi(argv[i + 1]);
    else if (a == "--compare") compare = std::atoi(argv[i + 1]);
    else if (a == "--every-sample-bootstraps") every_sample = std::atoi(argv[i + 1]);
    else if (a == "--compare-layers") compare_layers = std::atoi(argv[i + 1]);
    else if (a == "--compare-main") compare_main = std::atoi(argv[i + 1]);
    else if (a == "--depths") depths = std::atoi(argv[i + 1]);
    else if (a == "--precision") precision = argv[i + 1];
  }
  nets::set_torch_threads(threads);
  nets::seed_torch(1);

  learner::LearnerConfig config;
  config.net.architecture = nets::architecture_from_name(arch);
  config.net.base_channels = nets::default_base_channels(config.net.architecture);
  config.batch = batch;
  config.tree_target_k = tree;
  config.hierarchy.depths = depths;
  config.hierarchy.offsets_m = voxels::CoarseToFine::parse_offsets(depths == 3 ? "0.15,0.05" : "0.15", depths);

  replay::ReplayBuffer replay;
  replay::ReplayOptions every_step_options;
  every_step_options.cloud_memory_bytes = 0;
  replay::ReplayBuffer every_step_replay(every_step_options);  // keeps no cloud: computed at every use
  keyframes::TransitionOptions transition_options;
  transition_options.hierarchy = config.hierarchy;
  keyframes::EpisodeConverter converter(transition_options);
  const stream::Emit to_replay = [&](const stream::Record& r) {
    replay.add(r);
    every_step_replay.add(r);
  };
  demos::DemoOptions demo_options;
  demo_options.episodes = {"pick_and_lift", 0, 10, 1};
  demos::record_demos(robot::RobotModel::xarm7(), demo_options, [&](const stream::Record& r) { converter.handle(r, to_replay); },
                      [](const std::string&) {});
  converter.finish(to_replay);
  std::printf("replay: %zu transitions, %zu frames (10 pick_and_lift demos)\n", replay.size(), replay.frame_count());
  for (std::size_t i = 0; i < replay.size(); ++i) replay.cloud_of(i), replay.next_cloud_of(i);  // every frame sampled once
  std::printf("point clouds kept: %.0f MiB (%.2f MiB a frame)\n", replay.cloud_memory_used() / 1048576.0,
              replay.cloud_memory_used() / 1048576.0 / replay.frame_count());

  if (compare_main) {
    struct Variant {
      const char* name;
      bool as_before;
      nets::Precision precision;
      std::unique_ptr<learner::QLearner> learner;
      std::vector<double> seconds;
    };
    std::vector<Variant> variants;
    const auto add = [&](const char* name, bool as_before, nets::Precision p) {
      nets::seed_torch(1);
      variants.push_back({name, as_before, p, std::make_unique<learner::QLearner>(config), {}});
    };
    add("fp32 as before", true, nets::Precision::fp32);
    add("fp32", false, nets::Precision::fp32);
    if (nets::bf16_native_here()) add("bf16", false, nets::Precision::bf16);
    for (int step = 0; step <= steps; ++step)  // step 0 warms up
      for (Variant& v : variants) {
        std::mt19937_64 rng(step);
        nets::use_precision(v.precision);
        nets::use_inference_primitives(!v.as_before);
        nets::onednn::use_padded_weight_gradient(!v.as_before);
        const replay::ReplayBuffer& r = v.as_before ? every_step_replay : replay;
        const auto t0 = Clock::now();
        const replay::Sample sample = r.sample(batch, 1.0, rng);
        const learner::Minibatch mb = learner::assemble_minibatch(r, sample, config);
        v.learner->train_step(mb);
        if (step > 0) v.seconds.push_back(since(t0));
      }
    nets::use_inference_primitives(true);
    nets::onednn::use_padded_weight_gradient(true);
    std::printf("%s batch %d, %d depths, tree target K=%d, %d threads, full steps interleaved, median of %d "
                "(--precision auto is %s here):\n",
                arch.c_str(), batch, depths, tree, threads, steps,
                nets::precision_name(nets::precision_from_name("auto")));
    for (const Variant& v : variants)
      std::printf("  %-26s %.3f s  (%.2fx the first; %.2fx as fast)\n", v.name, median(v.seconds),
                  median(v.seconds) / median(variants[0].seconds), median(variants[0].seconds) / median(v.seconds));
    return 0;
  }

  if (compare > 0 || compare_layers) {
    struct Variant {
      const char* name;
      int tree;
      bool swapped, onednn, native;
      std::unique_ptr<learner::QLearner> learner;
      std::vector<double> seconds;
    };
    std::vector<Variant> variants;
    const auto add = [&](const char* name, int k, bool swapped, bool onednn, bool native) {
      learner::LearnerConfig c = config;
      c.tree_target_k = k;
      nets::seed_torch(1);
      variants.push_back({name, k, swapped, onednn, native, std::make_unique<learner::QLearner>(c), {}});
    };
    if (compare_layers) {
      add("LibTorch's layers", tree, false, false, false);
      add("+ swapped weight gradient", tree, true, false, false);
      add("oneDNN trunk", tree, true, true, true);
      if (bench::native_weight_gradient_here())
        add("oneDNN trunk, swapped dW", tree, true, true, false);
    } else {
      add("plain targets", 0, true, true, true);
      add("tree targets", compare, true, true, true);
    }
    double states = 0;  // next states the targets evaluate, summed over the timed steps
    for (int step = 0; step <= steps; ++step)  // step 0 warms up
      for (Variant& v : variants) {
        std::mt19937_64 rng(step);
        nets::use_swapped_weight_gradient(v.swapped);
        nets::use_onednn_trunk(v.onednn);
        nets::onednn::use_native_weight_gradient(v.native);
        const auto t0 = Clock::now();
        const replay::Sample sample = replay.sample(batch, 1.0, rng);
        learner::Minibatch mb = learner::assemble_minibatch(replay, sample, config);
        if (every_sample) {
          mb.discount.assign(mb.size, static_cast<float>(config.gamma));
          mb.next_state.clear();
        }
        v.learner->train_step(mb);
        if (step == 0) continue;
        v.seconds.push_back(since(t0));
        if (v.tree > 0) states += learner::next_states_evaluated(mb);
      }
    std::printf("%s batch %d, %d threads, full steps interleaved, median of %d; %.1f next states evaluated per batch%s:\n",
                arch.c_str(), batch, threads, steps, states / steps,
                every_sample ? " (every sample its own)" : " (chains that end need none, shared ones once)");
    for (const Variant& v : variants)
      std::printf("  %-26s K=%-2d %.3f s  (%.2fx the first; %.2fx as fast)\n", v.name, v.tree, median(v.seconds),
                  median(v.seconds) / median(variants[0].seconds), median(variants[0].seconds) / median(v.seconds));
    nets::onednn::use_native_weight_gradient(true);
    return 0;
  }

  // The peaks before and after the steps, the larger: a virtual machine's varies by a fifth.
  const bench::Peak fp32_before = bench::measure_fp32_peak(threads), bf16_before = bench::measure_bf16_peak(threads);
  std::vector<nets::Precision> precisions;
  if (!precision.empty()) precisions.push_back(nets::precision_from_name(precision));
  else {
    precisions.push_back(nets::Precision::fp32);
    if (nets::bf16_native_here()) precisions.push_back(nets::Precision::bf16);
  }
  struct Table {
    nets::Precision precision;
    double full, sampling, clouds, voxelizing, targets, forward, backward, optimiser, trunk_s, targets_trunk_s;
  };
  std::vector<Table> tables;
  for (const nets::Precision p : precisions) {
    nets::use_precision(p);
    nets::seed_torch(1);
    learner::QLearner learner(config);
    std::vector<double> sample_s, clouds_s, voxelize_s, target_s, forward_s, backward_s, optimiser_s, full_s, trunk_s,
        targets_trunk_s;
    for (int step = 0; step <= steps; ++step) {  // step 0 warms up
      std::mt19937_64 rng(step);
      const auto t0 = Clock::now();
      const replay::Sample sample = replay.sample(batch, 1.0, rng);
      const double t_sample = since(t0);
      const auto t1 = Clock::now();
      learner::Minibatch mb = learner::assemble_minibatch(replay, sample, config);
      if (every_sample) {
        mb.discount.assign(mb.size, static_cast<float>(config.gamma));
        mb.next_state.clear();
      }
      const double t_assemble = since(t1);
      const nets::TrunkTime trunk_before = nets::light_trunk_time();
      const learner::StepStats stats = learner.train_step(mb);
      const nets::TrunkTime trunk_after = nets::light_trunk_time();
      const double t_full = since(t0);
      if (step == 0) continue;
      sample_s.push_back(t_sample);
      clouds_s.push_back(mb.clouds_s);
      voxelize_s.push_back(t_assemble - mb.clouds_s);
      target_s.push_back(stats.targets_s);
      forward_s.push_back(stats.forward_s);
      backward_s.push_back(stats.backward_s);
      optimiser_s.push_back(stats.optimiser_s);
      full_s.push_back(t_full);
      targets_trunk_s.push_back(trunk_after.inference_s - trunk_before.inference_s);
      trunk_s.push_back(trunk_after.training_forward_s + trunk_after.backward_s - trunk_before.training_forward_s -
                        trunk_before.backward_s);
    }
    tables.push_back({p, median(full_s), median(sample_s), median(clouds_s), median(voxelize_s), median(target_s),
                      median(forward_s), median(backward_s), median(optimiser_s), median(trunk_s),
                      median(targets_trunk_s)});
  }
  bench::Peak fp32_peak = bench::measure_fp32_peak(threads), bf16_peak = bench::measure_bf16_peak(threads);
  fp32_peak.gflops = std::max(fp32_peak.gflops, fp32_before.gflops);
  bf16_peak.gflops = std::max(bf16_peak.gflops, bf16_before.gflops);

  std::printf("%s batch %d, %d depths, tree target K=%d, %d threads, median of %d steps, %s%s:\n", arch.c_str(), batch,
              depths, tree, threads, steps, nets::onednn_trunk_in_use() ? "oneDNN trunk where supported" : "LibTorch's layers",
              every_sample ? ", every sample its own next state" : "");
  std::printf("  %-10s", "part");
  for (const Table& t : tables) std::printf("  %8s ms  share", nets::precision_name(t.precision));
  std::printf("\n");
  const auto row = [&](const char* name, double Table::*part) {
    std::printf("  %-10s", name);
    for (const Table& t : tables) std::printf("  %11.1f  %4.0f%%", 1e3 * (t.*part), 100 * (t.*part) / t.full);
    std::printf("\n");
  };
  row("sampling", &Table::sampling);
  row("clouds", &Table::clouds);
  row("voxelizing", &Table::voxelizing);
  row("targets", &Table::targets);
  row("forward", &Table::forward);
  row("backward", &Table::backward);
  row("Adam", &Table::optimiser);
  row("full step", &Table::full);
  row("(targets'", &Table::targets_trunk_s);
  std::printf("  (the targets' trunk forwards, oneDNN's clock: the rest of the targets is voxelizing the next\n"
              "   states' grids, the dense head, the tree's bookkeeping and LibTorch's layout copies)\n");
  if (tables.size() == 2)
    std::printf("  bf16 step / fp32 step: %.2f (%.2fx as fast)\n", tables[1].full / tables[0].full,
                tables[0].full / tables[1].full);
  // The trunk's share of the machine: FLOPs from the layers' multiply-accumulates (x2) of the
  // forward, the input gradients (none for the grid) and the weight gradients, over the time the
  // oneDNN trunk's forwards with gradients and backwards take in the step (nets/light_trunk.hpp);
  // with LibTorch's layers, which have no such clock, over the forward and backward times above.
  double macs = 0;  // arm: every layer's, the backward counted as twice the forward
  {
    learner::QLearner learner(config);
    for (const nets::QAttentionNet& net : learner.online()) macs += static_cast<double>(net.module().multiply_accumulates());
  }
  const double trunk_gflop = (arch == "light" ? bench::light_trunk_flops().training() * depths : macs * 2 * 3) * batch / 1e9;
  for (const Table& t : tables) {
    const bool own_clock = t.trunk_s > 0;
    const double trunk_s = own_clock ? t.trunk_s : t.forward + t.backward;
    const bench::Peak& peak = t.precision == nets::Precision::bf16 ? bf16_peak : fp32_peak;
    std::printf("trunk %s: %.1f GFLOP/s, %.0f%% of the %s peak (%.0f GFLOP/s on %d threads, %s), %.0f%% of the fp32 "
                "peak (%.1f GFLOP in %.3f s, %s)\n",
                nets::precision_name(t.precision), trunk_gflop / trunk_s, 100 * trunk_gflop / trunk_s / peak.gflops,
                nets::precision_name(t.precision), peak.gflops, threads, peak.isa.c_str(),
                100 * trunk_gflop / trunk_s / fp32_peak.gflops, trunk_gflop, trunk_s,
                own_clock ? "the trunk's own time in the step" : "the step's forward and backward");
  }
  return 0;
}
