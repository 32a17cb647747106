// The Q-attention network of one coarse-to-fine depth (C2F-ARM): a 3D U-Net over a voxel grid
// with proprioception tiled over the voxels, giving a Q value per voxel; the last depth also
// gives rotation and gripper Q values from a dense head on pooled U-Net features.
//
// This header is free of LibTorch so that code which only runs networks compiles fast; the
// learning code reaches the torch module through nets/qattention_modules.hpp.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "robot/rotation_bins.hpp"

namespace qte::nets {

enum class Architecture {
  arm,    // the published inception-style U-Net (64 base channels): ~1.8 GMAC per sample
  light,  // the CPU default: plain 3x3x3 convolutions, two downsamplings, 16 base channels
};

const char* architecture_name(Architecture architecture);      // "arm", "light"
Architecture architecture_from_name(const std::string& name);  // throws Error
int default_base_channels(Architecture architecture);          // arm 64, light 16

// What the last depth's dense head (rotation and gripper Q values) reads.
enum class HeadInput {
  pooled,  // as published: every U-Net level pooled over the whole grid (maximum, soft-argmax position)
  voxel,   // our variation: those, and the finest level's features at the chosen voxel (light only)
};

const char* head_input_name(HeadInput input);        // "pooled", "voxel"
HeadInput head_input_from_name(const std::string& name);  // throws Error

// Rotation Q values: 3 Euler axes x 72 bins of 5 degrees; gripper: open / close.
constexpr int kRotationAxes = 3;
using robot::kRotationBins;  // the action encoding's bins (robot/rotation_bins.hpp)
constexpr int kGripperActions = 2;

struct NetConfig {
  int depth = 0;         // coarse-to-fine depth this network serves (0 = scene bounds)
  bool is_last = false;  // the last depth also outputs rotation and gripper Q values
  int voxels = 16;       // grid of voxels^3 (a multiple of 4: the U-Net halves it twice)
  int channels = 10;     // per-voxel channels (voxels::kChannels)
  // Proprioception: gripper open, the two finger positions (opening / 2 each), time in
  // [-1, 1]. The reference script uses 11.
  int proprio = 4;
  Architecture architecture = Architecture::light;
  int base_channels = 16;  // kernels of the first U-Net level (default_base_channels())
  HeadInput head_input = HeadInput::pooled;

  // Throws Error naming the first setting a network cannot be built with.
  void validate() const;
};

// Outputs of a batch, as plain arrays (C order).
struct QValues {
  int batch = 0;
  std::vector<float> translation;  // [batch, voxels, voxels, voxels], index order x, y, z
  std::vector<float> rotation;     // [batch, 3, 72] (last depth only, otherwise empty)
  std::vector<float> gripper;      // [batch, 2] (last depth only, otherwise empty)
  // Set by predict_leaves instead of `rotation` and `gripper`: computes those two for `rows`
  // only (the other rows hold 0) from the activations it keeps.
  std::function<void(const std::vector<int>& rows, QValues& into)> heads_for;
};

class QAttentionModule;  // the torch module (nets/qattention_modules.hpp)

constexpr int kPredictChunk = 32;
constexpr double kDeferredHeadsBytes = 256.0 * (1 << 20);  // predict_leaves's kept activations, at most

class QAttentionNet {
 public:
  // Fresh weights drawn from torch's generator: call seed_torch() first to reproduce them.
  explicit QAttentionNet(const NetConfig& config);
  ~QAttentionNet();
  QAttentionNet(QAttentionNet&&) noexcept;
  QAttentionNet& operator=(QAttentionNet&&) noexcept;

  const NetConfig& config() const { return config_; }
  int64_t parameter_count() const;

  // Inference without gradients. `grids`: [batch, voxels, voxels, voxels, channels], channels
  // last as voxels::voxelize writes them; `proprio`: [batch, proprio]. Evaluated in chunks of
  // kPredictChunk samples.
  QValues predict(const float* grids, const float* proprio, int batch) const;
  // The same for the leaves of a tree, which need every grid's translation Q but the dense
  // head only for the few leaves chosen from them: the head (pooled features and three linear
  // layers, ~15% of a last-depth forward) waits for `heads_for`, holding the trunk's
  // activations until the QValues are gone — up to kDeferredHeadsBytes of them (light at 16^3:
  // 0.6 MB a grid, so 2 depths of K = 10 at batch 32 wait; beyond, heads come at once, as from
  // predict, which is keep_bytes 0). Without a head (not is_last): predict.
  QValues predict_leaves(const float* grids, const float* proprio, int batch,
                         double keep_bytes = kDeferredHeadsBytes) const;

  QAttentionModule& module() { return *module_; }
  const QAttentionModule& module() const { return *module_; }

 private:

  NetConfig config_;
  std::shared_ptr<QAttentionModule> module_;
};

// One network per depth, depth 0 first, the last marked is_last.
std::vector<QAttentionNet> make_coarse_to_fine_nets(NetConfig config, int depths);

// Seeds torch's CPU generator: the same seed gives the same initial weights.
void seed_torch(uint64_t seed);
// Intra-op threads of LibTorch (its default is every core). More than one, in a program that
// called prepare_process_for_networks: unless the user has set OMP_WAIT_POLICY, this sets it
// to PASSIVE and executes the program again (same arguments), because LibTorch's OpenMP
// threads spin while they wait for work and libgomp reads the policy only once, when it loads.
// When two programs share the cores (the learner and the actor of the learning loop on 2
// cores), a spinning thread takes the core its partner needs: we measured steps 5x and acting
// 50x slower. One thread starts no workers and is not executed again: a start of LibTorch
// costs ~0.4 s of processor time, and the actor starts once per chunk of episodes.
void set_torch_threads(int threads);
// --threads, the option of set_torch_threads (qte-select, qattn-train).
cli::OptionSpec torch_threads_option(int default_threads);

// --precision, the networks' arithmetic (qte-select, qattn-train): auto, fp32 or bf16
// (nets/light_trunk.hpp). use_precision_option sets it for the process from the arguments.
cli::OptionSpec precision_option();
void use_precision_option(const cli::Arguments& args);
// What the networks of `config` run in here, for a program's log: "bf16", or "fp32" with why
// when bf16 was asked for and is not available.
std::string precision_in_use(const NetConfig& config, int voxels, int batch);

// Programs that run networks call this first thing in main(): it keeps argv for
// set_torch_threads and keeps freed activations in the heap for the next forward (see the .cpp).
void prepare_process_for_networks(char** argv);

}  // namespace qte::nets
