#include "nets/qattention_net.hpp"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>

#include "common/error.hpp"
#include "nets/light_trunk.hpp"
#include "nets/qattention_modules.hpp"

namespace qte::nets {

const char* architecture_name(Architecture architecture) { return architecture == Architecture::arm ? "arm" : "light"; }

Architecture architecture_from_name(const std::string& name) {
  if (name == "arm") return Architecture::arm;
  if (name == "light") return Architecture::light;
  throw Error("unknown network architecture '" + name + "' (expected arm or light)");
}

const char* head_input_name(HeadInput input) { return input == HeadInput::voxel ? "voxel" : "pooled"; }

HeadInput head_input_from_name(const std::string& name) {
  if (name == "pooled") return HeadInput::pooled;
  if (name == "voxel") return HeadInput::voxel;
  throw Error("unknown head input '" + name + "' (expected pooled or voxel)");
}

int default_base_channels(Architecture architecture) { return architecture == Architecture::arm ? 64 : 16; }

void NetConfig::validate() const {
  const auto refuse = [](const std::string& what) { throw Error("network config: " + what); };
  if (depth < 0) refuse("depth must be >= 0, got " + std::to_string(depth));
  if (voxels < 4 || voxels % 4 != 0)
    refuse("voxels must be a positive multiple of 4 (the U-Net halves the grid twice), got " + std::to_string(voxels));
  if (channels < 1) refuse("channels must be >= 1, got " + std::to_string(channels));
  if (proprio < 1) refuse("proprio must be >= 1, got " + std::to_string(proprio));
  // The arm's inception blocks split their width 1/2 + 1/4 + 1/4.
  const int multiple = architecture == Architecture::arm ? 4 : 1;
  if (base_channels < 1 || base_channels % multiple != 0)
    refuse("base_channels of the " + std::string(architecture_name(architecture)) +
           " network must be a positive multiple of " + std::to_string(multiple) + ", got " +
           std::to_string(base_channels));
  if (head_input == HeadInput::voxel && architecture != Architecture::light)
    refuse("head input 'voxel' is built for the light architecture only");
}

QAttentionNet::QAttentionNet(const NetConfig& config) : config_(config), module_(make_qattention_module(config)) {}
QAttentionNet::~QAttentionNet() = default;
QAttentionNet::QAttentionNet(QAttentionNet&&) noexcept = default;
QAttentionNet& QAttentionNet::operator=(QAttentionNet&&) noexcept = default;

int64_t QAttentionNet::parameter_count() const {
  int64_t count = 0;
  for (const auto& p : module_->parameters()) count += p.numel();
  return count;
}

namespace {

void append(std::vector<float>& to, const torch::Tensor& t) {
  const auto c = t.contiguous();
  to.insert(to.end(), c.data_ptr<float>(), c.data_ptr<float>() + c.numel());
}

// Rows' rotation and gripper Q values into the [batch, ...] arrays of `into` (zeros elsewhere),
// from the trunks of predict_leaves's chunks.
void heads_of_rows(QAttentionModule& module, const std::vector<Trunk>& chunks, int batch, const std::vector<int>& rows,
                   QValues& into) {
  for (int row : rows)
    if (row < 0 || row >= batch)
      throw Error("network heads asked for row " + std::to_string(row) + " of " + std::to_string(batch));
  constexpr int kRotations = kRotationAxes * kRotationBins;
  into.rotation.assign(static_cast<std::size_t>(batch) * kRotations, 0.0f);
  into.gripper.assign(static_cast<std::size_t>(batch) * kGripperActions, 0.0f);
  torch::NoGradGuard no_grad;
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    const int first = static_cast<int>(c) * kPredictChunk;
    std::vector<int> wanted;  // rows of this chunk
    for (int row : rows)
      if (row >= first && row < first + kPredictChunk) wanted.push_back(row);
    if (wanted.empty()) continue;
    std::vector<int64_t> local;
    for (int row : wanted) local.push_back(row - first);
    const auto index = torch::tensor(local, torch::kLong);
    std::vector<torch::Tensor> levels;
    for (const auto& level : chunks[c].levels) levels.push_back(level.index_select(0, index));
    QOutputs out;
    module.heads(levels, out);
    const auto rotation = out.rotation.contiguous(), gripper = out.gripper.contiguous();
    for (std::size_t i = 0; i < wanted.size(); ++i) {
      std::copy_n(rotation.data_ptr<float>() + i * kRotations, kRotations, into.rotation.begin() + wanted[i] * kRotations);
      std::copy_n(gripper.data_ptr<float>() + i * kGripperActions, kGripperActions,
                  into.gripper.begin() + wanted[i] * kGripperActions);
    }
  }
}

int64_t level_bytes(const Trunk& trunk) {
  int64_t bytes = 0;
  for (const auto& level : trunk.levels) bytes += level.numel() * static_cast<int64_t>(sizeof(float));
  return bytes;
}

char** program_arguments = nullptr;  // kept by prepare_process_for_networks for the re-execution

// Executes this program again with the same arguments (by its own path, so that it keeps its
// name for ps, pgrep and perf: "qte-select", not "exe"); returns only if that fails.
void execute_again() {
  char self[4096];
  const ssize_t length = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (length > 0) {
    self[length] = '\0';
    ::execv(self, program_arguments);
  }
  ::execv("/proc/self/exe", program_arguments);
}

}  // namespace

QValues QAttentionNet::predict(const float* grids, const float* proprio, int batch) const {
  return predict_leaves(grids, proprio, batch, 0);  // nothing kept: every head at once
}

QValues QAttentionNet::predict_leaves(const float* grids, const float* proprio, int batch, double keep_bytes) const {
  const int64_t v = config_.voxels;
  const std::size_t grid_floats = static_cast<std::size_t>(v * v * v * config_.channels);
  torch::NoGradGuard no_grad;
  QValues values;
  values.batch = batch;
  auto kept = std::make_shared<std::vector<Trunk>>();
  bool heads_later = false;
  // Large batches (tree-expanded targets: batch x K grids) go through in chunks: LibTorch's
  // 3D convolutions cost more per sample beyond a few dozen samples (measured with light:
  // 2.3 ms per sample at 32-128, 4.1 ms at 352).
  for (int first = 0; first < batch; first += kPredictChunk) {
    const int n = std::min(kPredictChunk, batch - first);
    // from_blob does not copy; channels_first makes the one copy the convolutions need.
    const auto grid = torch::from_blob(const_cast<float*>(grids + first * grid_floats), {n, v, v, v, config_.channels});
    const auto state = torch::from_blob(const_cast<float*>(proprio + static_cast<std::size_t>(first) * config_.proprio),
                                        {n, config_.proprio});
    Trunk trunk = module_->trunk(channels_first(grid), state);
    append(values.translation, trunk.translation);
    // Q values that are not finite, or absurd (the rewards are 0..1; beyond 1e30 sums overflow),
    // cannot be ranked: the networks are at fault, damaged or diverged weights, not the input.
    const double largest = trunk.translation.abs().max().item<double>();
    if (!(largest <= 1e30))
      throw Error("the depth-" + std::to_string(config_.depth) + " network's Q values reach " + std::to_string(largest) +
                  ": its checkpoint's weights are damaged or diverged");
    if (!config_.is_last) continue;
    // Kept activations are bounded: a larger batch (a deep tree's leaves) gets its heads now.
    if (first == 0) heads_later = static_cast<double>(level_bytes(trunk)) / n * batch <= keep_bytes;
    if (!heads_later) {
      QOutputs out;
      module_->heads(trunk.levels, out);
      append(values.rotation, out.rotation);
      append(values.gripper, out.gripper);
    } else {
      trunk.translation = torch::Tensor();  // copied out above; only the levels wait
      kept->push_back(std::move(trunk));
    }
  }
  if (heads_later)
    values.heads_for = [module = module_, kept, batch](const std::vector<int>& rows, QValues& into) {
      heads_of_rows(*module, *kept, batch, rows, into);
    };
  return values;
}

std::vector<QAttentionNet> make_coarse_to_fine_nets(NetConfig config, int depths) {
  if (depths < 1) throw Error("network config: depths must be >= 1, got " + std::to_string(depths));
  std::vector<QAttentionNet> nets;
  for (int d = 0; d < depths; ++d) {
    config.depth = d;
    config.is_last = d == depths - 1;
    nets.emplace_back(config);
  }
  return nets;
}

void seed_torch(uint64_t seed) { torch::manual_seed(seed); }


cli::OptionSpec torch_threads_option(int default_threads) {
  return cli::integer_option(
      "threads", "N",
      "LibTorch threads; with more than 1 the program sets OMP_WAIT_POLICY=PASSIVE for itself unless it is set "
      "(OpenMP threads that spin while they wait make a forward about 50 times slower when another busy process "
      "shares the cores), at the price of a second start (~0.4 s). Outputs are the same bytes for the same "
      "--threads; another count sums in another order, so values may differ in their last bit (measured: the "
      "same voxels in 19 of 19 actions, 3 Q values 1e-7 apart). The networks' layers run in oneDNN directly where "
      "the processor has AVX2 or wider; the environment variable QTE_NETWORK_LAYERS=libtorch runs LibTorch's layers "
      "instead (values equal within fp32 rounding, other bytes)",
      cli::default_text(default_threads), 1, 256);
}

cli::OptionSpec precision_option() {
  return {"precision", "P",
          "the networks' convolutions: fp32, or bf16 (bf16 inputs and weights, fp32 sums: up to twice the fp32 rate "
          "where the processor has AVX-512 BF16 or AMX; parameters, optimiser, Q values and checkpoints stay fp32, so "
          "a checkpoint trained either way acts either way); auto: bf16 where the processor has it natively, fp32 "
          "elsewhere. Only the 'light' architecture's oneDNN trunk has a bf16 path; the rest runs fp32",
          "auto"};
}

void use_precision_option(const cli::Arguments& args) { use_precision(precision_from_name(args.text("precision"))); }

std::string precision_in_use(const NetConfig& config, int voxels, int batch) {
  const bool light = config.architecture == Architecture::light;
  if (precision_requested() == Precision::fp32) return "fp32";
  if (!light || !onednn_trunk_in_use()) return "fp32 (bf16 runs only in the light architecture's oneDNN trunk)";
  return precision_running(batch, config.channels, config.base_channels, voxels) == Precision::bf16
             ? "bf16"
             : "fp32 (oneDNN has no native bf16 kernels for these layers on this processor)";
}

void prepare_process_for_networks(char** argv) {
  program_arguments = argv;
  // A forward allocates and frees megabytes of activations. glibc maps blocks that large
  // with mmap and trims the heap on free, so every forward faulted its pages in anew: acting
  // with K = 10 on one thread spent 2.5 s of system time in 67 actions, as much again as
  // the arithmetic. Kept in the heap and not trimmed, the blocks are reused (qte-select on
  // those 67 observations: 7.6 s -> 3.4 s; the learner's step on 2 threads is unchanged).
  ::mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest
  ::mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

void set_torch_threads(int threads) {
  if (threads < 1) throw Error("torch threads must be >= 1, got " + std::to_string(threads));
  // One thread starts no OpenMP workers, so only more than one needs passive waits; failing
  // the re-execution, carry on with spinning waits.
  if (threads > 1 && program_arguments != nullptr && std::getenv("OMP_WAIT_POLICY") == nullptr) {
    ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
    execute_again();
  }
  torch::set_num_threads(threads);
}

}  // namespace qte::nets
