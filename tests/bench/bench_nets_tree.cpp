// Prints the cost of acting with tree expansion: K = 1 (greedy C2F-ARM), and K = 10 with the
// branches batched into one forward (ours) against one forward per branch (the published
// code's sequential expansion), and K = 5, for both architectures, 2 threads.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>

#include "qattention/tree_expansion.hpp"

using namespace qte;
using Clock = std::chrono::steady_clock;

int main(int, char** argv) {
  qte::nets::prepare_process_for_networks(argv);  // fair figures while other programs run
  nets::set_torch_threads(2);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (int i = 0; i < 128 * 128; ++i) {
    xyz.insert(xyz.end(), {-0.3f + u(rng), -0.5f + u(rng), 0.6f + 0.3f * u(rng)});
    rgb.insert(rgb.end(), {100, 120, 140});
  }
  const voxels::PointCloud cloud{xyz.data(), rgb.data(), rgb.size() / 3};
  const std::vector<float> proprio = {1, 0.04f, 0.04f, -1};
  voxels::CoarseToFine hierarchy;
  for (auto architecture : {nets::Architecture::light, nets::Architecture::arm}) {
    nets::seed_torch(1);
    nets::NetConfig config;
    config.architecture = architecture;
    config.base_channels = nets::default_base_channels(architecture);
    const auto networks = nets::make_coarse_to_fine_nets(config, 2);
    const auto batched = qattention::network_evaluator(networks);
    // The sequential expansion: the same networks, one grid per forward.
    const qattention::DepthEvaluator sequential = [&](int depth, const float* grids, const float* p, int batch) {
      nets::QValues all;
      all.batch = batch;
      const std::size_t floats = 16 * 16 * 16 * voxels::kChannels;
      for (int i = 0; i < batch; ++i) {
        const nets::QValues one = networks[depth].predict(grids + i * floats, p + i * 4, 1);
        all.translation.insert(all.translation.end(), one.translation.begin(), one.translation.end());
        all.rotation.insert(all.rotation.end(), one.rotation.begin(), one.rotation.end());
        all.gripper.insert(all.gripper.end(), one.gripper.begin(), one.gripper.end());
      }
      return all;
    };
    auto time = [&](const qattention::DepthEvaluator& evaluate, int k) {
      qattention::expand(evaluate, hierarchy, cloud, proprio, k);  // warm-up
      std::vector<double> t;
      for (int rep = 0; rep < (architecture == nets::Architecture::arm ? 3 : 10); ++rep) {
        const auto t0 = Clock::now();
        qattention::expand(evaluate, hierarchy, cloud, proprio, k);
        t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
      }
      std::sort(t.begin(), t.end());
      return t[t.size() / 2];
    };
    const double greedy = time(batched, 1), five = time(batched, 5), tree = time(batched, 10),
                 loop = time(sequential, 10);
    std::printf("%s act (voxelize + forwards), 2 threads: K=1 %.1f ms; K=5 %.1f ms (%.2fx K=1); K=10 batched %.1f ms "
                "(%.2fx K=1); K=10 one forward per branch, every head %.1f ms (batched %.2fx faster)\n",
                nets::architecture_name(architecture), greedy * 1e3, five * 1e3, five / greedy, tree * 1e3,
                tree / greedy, loop * 1e3, loop / tree);
  }
}
