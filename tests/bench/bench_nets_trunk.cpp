// `light`'s convolutional trunk (lib/nets/qattention_modules.cpp, LightNet) three ways, alternated
// run by run in one process: LibTorch's layers; LibTorch's layers with the swapped weight
// gradient (nets/conv3d.hpp); the trunk run by oneDNN alone (nets/light_trunk.hpp, the default).
// For each: the training forward, forward + backward (the backward reaching every parameter, as
// in a learner step: a loss on the Q values and, at the last depth, on the head's levels) and
// the no-gradient forward, at the training batch (32), a tree expansion's branches (20) and
// acting (2: a single grid runs as a pair), for depth 0 and the last depth, on --threads.
// Options: --reps R (median of R, default 7), --threads N (default 2).
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include "nets/conv3d.hpp"
#include "nets/light_trunk.hpp"
#include "nets/qattention_modules.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Way {
  const char* name;
  bool swapped, onednn;
  std::vector<double> forward, training, inference;
};

}  // namespace

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);
  int reps = 7, threads = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--reps")) reps = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--threads")) threads = std::max(1, std::atoi(argv[i + 1]));
  }
  qte::nets::set_torch_threads(threads);
  torch::manual_seed(0);
  std::printf("light's trunk (16^3 grid, 10 channels, 16 base channels), %d threads, median of %d, alternated\n",
              threads, reps);
  for (const bool last : {false, true}) {
    qte::nets::NetConfig config;
    config.is_last = last;
    const auto net = qte::nets::make_qattention_module(config);
    for (const int batch : {32, 20, 2}) {
      const auto grid = torch::rand({batch, config.channels, config.voxels, config.voxels, config.voxels});
      const auto proprio = torch::rand({batch, config.proprio});
      std::vector<Way> ways{{"LibTorch's layers", false, false, {}, {}, {}},
                            {"+ swapped weight gradient", true, false, {}, {}, {}},
                            {"oneDNN trunk", true, true, {}, {}, {}}};
      for (int r = 0; r <= reps; ++r)  // r = 0 warms up (primitives created, buffers allocated)
        for (Way& w : ways) {
          qte::nets::use_swapped_weight_gradient(w.swapped);
          qte::nets::use_onednn_trunk(w.onednn);
          net->zero_grad();
          auto t0 = Clock::now();
          const qte::nets::Trunk trunk = net->trunk(grid, proprio);
          const double forward = std::chrono::duration<double>(Clock::now() - t0).count();
          auto loss = trunk.translation.sum();
          for (const auto& level : trunk.levels) loss = loss + level.mean();
          loss.backward();
          const double training = std::chrono::duration<double>(Clock::now() - t0).count();
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
    }
  }
  qte::nets::use_swapped_weight_gradient(true);
  qte::nets::use_onednn_trunk(true);
  return 0;
}
