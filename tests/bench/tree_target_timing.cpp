// Prints what adaptive K costs in the tree-expanded bootstrap target against fixed K, with the
// networks of a trained learner checkpoint (its online networks rank, its target networks
// value, as in qattn-train): the same minibatches, drawn uniformly from REPLAY's transitions,
// go through every setting, interleaved batch by batch so that a noisy machine slows all of
// them alike. Per setting: the median seconds of one target computation (the next states'
// voxelization included), the mean grids expanded per node at depth 1, and the mean absolute
// difference of the depth-0 target from K = 10's (every sample bootstrapping, terminal or
// not); then what each setting's targets are worth on average, per depth and for the last
// depth's rotation and gripper heads (does a deeper tree pull the finest depth's targets down?).
// bench_adaptive_k runs it after the acting figures, on the same checkpoint.
//
// Usage: tree_target_timing CHECKPOINT REPLAY [BATCHES [THREADS]]   (defaults 10 batches of 32, 2 threads)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "learner/minibatch.hpp"
#include "learner/targets.hpp"
#include "nets/checkpoint.hpp"
#include "qattention/tree_expansion.hpp"
#include "replay/replay_buffer.hpp"
#include "stream/reader.hpp"
#include "voxels/grid_fields.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

namespace {

struct Setting {
  std::string name;
  int tree_target_k;  // 0: the double-DQN target; else K, or K_max of an adaptive rule
  qattention::Branching branching;
  std::vector<double> seconds, branches;
  double target_difference = 0;
  std::vector<double> mean_targets;  // per depth, then rotation (all axes) and gripper
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

template <typename T>
double mean(const std::vector<T>& v) {
  double sum = 0;
  for (T x : v) sum += x;
  return v.empty() ? 0 : sum / static_cast<double>(v.size());
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::fprintf(stderr, "usage: tree_target_timing CHECKPOINT REPLAY [BATCHES [THREADS]]\n");
    return 2;
  }
  nets::prepare_process_for_networks(argv);
  const std::string checkpoint = argv[1], replay_path = argv[2];
  const int batches = argc > 3 ? std::atoi(argv[3]) : 10, threads = argc > 4 ? std::atoi(argv[4]) : 2;
  nets::set_torch_threads(threads);

  // The learner checkpoint: online networks (with the hierarchy), then the target networks.
  stream::RecordReader checkpoint_reader(checkpoint);
  const auto online_record = checkpoint_reader.next(), target_record = checkpoint_reader.next();
  if (!online_record || !target_record) throw Error(checkpoint + ": expected a learner checkpoint (online and target networks)");
  const nets::CheckpointConfig saved = nets::checkpoint_config(*online_record);
  learner::LearnerConfig config;
  config.net = saved.net;
  if (auto hierarchy = voxels::hierarchy_of(*online_record)) config.hierarchy = *hierarchy;
  auto online = nets::make_coarse_to_fine_nets(saved.net, saved.depths);
  auto target = nets::make_coarse_to_fine_nets(saved.net, saved.depths);
  nets::load_checkpoint_record(*online_record, online, nullptr);
  nets::load_checkpoint_record(*target_record, target, nullptr);
  const auto rank = qattention::network_evaluator(online), value = qattention::network_evaluator(target);

  replay::ReplayBuffer replay;
  stream::RecordReader replay_reader(replay_path);
  while (auto record = replay_reader.next()) {
    if (record->type() == "transition") learner::check_transition(*record, config);
    replay.add(*record);
  }
  std::printf("%s: %zu transitions; %d batches of %d, %d threads, settings interleaved per batch\n",
              replay_path.c_str(), replay.size(), batches, config.batch, threads);

  std::vector<Setting> settings;
  settings.push_back({"K = 10", 10, qattention::Branching(10), {}, {}, 0, {}});
  settings.push_back({"K = 1", 1, qattention::Branching(1), {}, {}, 0, {}});
  settings.push_back({"double DQN", 0, qattention::Branching(1), {}, {}, 0, {}});
  for (float margin : {0.01f, 0.02f, 0.05f})
    settings.push_back({"margin " + std::to_string(margin).substr(0, 4), 10,
                        qattention::Branching::within_margin(margin, 10), {}, {}, 0, {}});

  for (int b = 0; b <= batches; ++b) {  // batch 0 warms up
    std::mt19937_64 rng(b);
    learner::Minibatch batch = learner::assemble_minibatch(replay, replay.sample(config.batch, 0.0, rng), config);
    // Every sample bootstraps (a demonstration's last transition would not: its target is the
    // reward alone), so that the targets compared below are the trees' values.
    batch.discount.assign(batch.discount.size(), static_cast<float>(config.gamma));
    std::vector<float> reference;
    for (Setting& s : settings) {
      config.tree_target_k = s.tree_target_k;
      config.tree_branching = s.branching;
      const auto t0 = Clock::now();
      const learner::Targets targets = learner::bootstrap_targets(rank, value, config, batch);
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      if (b == 0) continue;
      s.seconds.push_back(seconds);
      s.branches.push_back(targets.mean_branches.empty() ? 1.0 : targets.mean_branches[0]);
      if (reference.empty()) reference = targets.translation[0];  // K = 10 comes first
      const std::size_t depths = targets.translation.size();
      s.mean_targets.resize(depths + 2, 0.0);
      for (std::size_t d = 0; d < depths; ++d) s.mean_targets[d] += mean(targets.translation[d]) / batches;
      s.mean_targets[depths] += mean(targets.rotation) / batches;
      s.mean_targets[depths + 1] += mean(targets.gripper) / batches;
      for (std::size_t i = 0; i < reference.size(); ++i)
        s.target_difference += std::fabs(targets.translation[0][i] - reference[i]) / (reference.size() * batches);
    }
  }
  std::printf("%-12s %12s %10s %12s %22s\n", "setting", "s/target", "x K=10", "branches d1", "|target_d0 - K=10's|");
  const double k10 = median(settings[0].seconds);
  for (const Setting& s : settings)
    std::printf("%-12s %12.3f %10.2f %12.2f %22.4f\n", s.name.c_str(), median(s.seconds), median(s.seconds) / k10,
                mean(s.branches), s.target_difference);
  std::printf("\nmean target %s\n", "(per depth, then the last depth's rotation and gripper heads)");
  for (const Setting& s : settings) {
    std::printf("%-12s", s.name.c_str());
    for (double m : s.mean_targets) std::printf(" %9.4f", m);
    std::printf("\n");
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "tree_target_timing: %s\n", e.what());
  return 1;
}
