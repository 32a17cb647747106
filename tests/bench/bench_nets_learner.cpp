// Prints the cost of one full learner step of qattn-train on 2 threads, and what it is made
// of: sampling, voxelization of the batch (current grids at every depth), the bootstrap
// targets (next-state grids and no-grad forwards of online and target networks, or tree
// expansion with --tree-target), and the forward + backward + Adam + soft update. The
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
  }
  nets::set_torch_threads(threads);
  nets::seed_torch(1);

  learner::LearnerConfig config;
  config.net.architecture = nets::architecture_from_name(arch);
  config.net.base_channels = nets::default_base_channels(config.net.architecture);
  config.batch = batch;
  config.tree_target_k = tree;

  replay::ReplayBuffer replay;
  keyframes::TransitionOptions transition_options;
  transition_options.hierarchy = config.hierarchy;
  keyframes::EpisodeConverter converter(transition_options);
  const stream::Emit to_replay = [&](const stream::Record& r) { replay.add(r); };
  demos::DemoOptions demo_options;
  demo_options.episodes = {"pick_and_lift", 0, 10, 1};
  demos::record_demos(robot::RobotModel::xarm7(), demo_options, [&](const stream::Record& r) { converter.handle(r, to_replay); },
                      [](const std::string&) {});
  converter.finish(to_replay);
  std::printf("replay: %zu transitions, %zu frames (10 pick_and_lift demos)\n", replay.size(), replay.frame_count());

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

  learner::QLearner learner(config);
  // The peak before and after the steps, the larger: a virtual machine's varies by a fifth.
  const bench::Peak peak_before = bench::measure_fp32_peak(threads);
  std::vector<double> sample_s, assemble_s, target_s, full_s, trunk_training_s;
  for (int step = 0; step <= steps; ++step) {  // step 0 warms up
    std::mt19937_64 rng(step);
    const auto t0 = Clock::now();
    const replay::Sample sample = replay.sample(batch, 1.0, rng);
    const double t_sample = since(t0);
    const auto t1 = Clock::now();
    const learner::Minibatch mb = learner::assemble_minibatch(replay, sample, config);
    const double t_assemble = since(t1);
    const auto t2 = Clock::now();
    learner.targets(mb);  // timed alone; train_step computes them again
    const double t_targets = since(t2);
    const nets::TrunkTime trunk_before = nets::light_trunk_time();
    const auto t3 = Clock::now();
    const learner::StepStats stats = learner.train_step(mb);
    const nets::TrunkTime trunk_after = nets::light_trunk_time();
    replay.update_priorities(sample.indices, stats.td_errors);
    const double t_train = since(t3);
    if (step == 0) continue;
    sample_s.push_back(t_sample);
    assemble_s.push_back(t_assemble);
    target_s.push_back(t_targets);
    full_s.push_back(t_sample + t_assemble + t_train);
    trunk_training_s.push_back(trunk_after.training_forward_s + trunk_after.backward_s -
                               trunk_before.training_forward_s - trunk_before.backward_s);
  }
  const double full = median(full_s), targets = median(target_s), assemble = median(assemble_s);
  std::printf("%s batch %d, %d depths, tree target K=%d, %d threads, median of %d steps, %s:\n", arch.c_str(), batch,
              config.hierarchy.depths, tree, threads, steps,
              nets::onednn_trunk_in_use() ? "oneDNN trunk where supported" : "LibTorch's layers");
  std::printf("  full step        %.3f s  (sampling %.4f, voxelizing the batch %.3f, targets %.3f, "
              "forward+backward+Adam of all depths %.3f)\n",
              full, median(sample_s), assemble, targets, full - median(sample_s) - assemble - targets);
  std::printf("  per depth        %.3f s  (full step / depths: compare with the reference's bare step per depth)\n",
              full / config.hierarchy.depths);
  // The trunk's share of the machine: FLOPs from the layers' multiply-accumulates (x2) of the
  // forward, the input gradients (none for the grid) and the weight gradients, over the time the
  // oneDNN trunk's forwards with gradients and backwards take in the step (nets/light_trunk.hpp);
  // with LibTorch's layers, which have no such clock, over the forward+backward+Adam time above.
  const bool own_clock = median(trunk_training_s) > 0;
  const double trunk_s = own_clock ? median(trunk_training_s) : full - median(sample_s) - assemble - targets;
  double macs = 0;  // arm: every layer's, the backward counted as twice the forward
  for (const nets::QAttentionNet& net : learner.online()) macs += static_cast<double>(net.module().multiply_accumulates());
  const double trunk_gflop = (arch == "light" ? bench::light_trunk_flops().training() * config.hierarchy.depths
                                              : macs * 2 * 3) * batch / 1e9;
  bench::Peak peak = bench::measure_fp32_peak(threads);  // and before the steps: the larger
  peak.gflops = std::max(peak.gflops, peak_before.gflops);
  std::printf("trunk: %.1f GFLOP/s, %.0f%% of peak (forward + backward of all depths: %.1f GFLOP in %.3f s, %s; "
              "peak %.0f GFLOP/s fp32 on %d threads, %s)\n",
              trunk_gflop / trunk_s, 100 * trunk_gflop / trunk_s / peak.gflops, trunk_gflop, trunk_s,
              own_clock ? "the trunk's own time in the step" : "the step's forward+backward+Adam", peak.gflops, threads,
              peak.isa.c_str());
  return 0;
}
