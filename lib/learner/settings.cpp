#include "learner/settings.hpp"

#include "learner/learner_options.hpp"
#include "qattention/branching_options.hpp"
#include "voxels/hierarchy_options.hpp"

#include <algorithm>
#include <sstream>

#include "common/error.hpp"

namespace qte::learner {

std::string LearnerConfig::json() const {
  std::ostringstream s;
  s.precision(17);
  const voxels::GridBounds& scene = hierarchy.scene;
  s << "{\"architecture\": \"" << nets::architecture_name(net.architecture) << "\", \"base_channels\": " << net.base_channels
    << ", \"voxels\": " << hierarchy.voxels() << ", \"depths\": " << hierarchy.depths << ", \"offsets\": [";
  for (std::size_t i = 0; i < hierarchy.offsets_m.size(); ++i) s << (i ? ", " : "") << hierarchy.offsets_m[i];
  s << "], \"bounds\": [" << scene.min_corner.x() << ", " << scene.min_corner.y() << ", " << scene.min_corner.z() << ", "
    << scene.size_m << "], \"batch\": " << batch << ", \"gamma\": " << gamma << ", \"reward_scale\": " << reward_scale
    << ", \"tau\": " << tau << ", \"learning_rate\": " << learning_rate << ", \"weight_decay\": " << weight_decay
    << ", \"grad_clip_value\": " << grad_clip_value << ", \"grad_clip_norm\": " << grad_clip_norm
    << ", \"q_regularisation\": " << q_regularisation << ", \"huber_delta\": " << huber_delta
    << ", \"tree_target_k\": " << tree_target_k << ", \"n_step\": " << n_step;
  if (demo_margin > 0) s << ", \"demo_margin\": " << demo_margin;  // only then: older checkpoints still resume
  if (demo_cross_entropy > 0) s << ", \"demo_cross_entropy\": " << demo_cross_entropy;  // likewise
  if (demo_share > 0) s << ", \"demo_share\": " << demo_share;  // likewise
  if (net.head_input != nets::HeadInput::pooled)  // only then, likewise
    s << ", \"head_input\": \"" << nets::head_input_name(net.head_input) << "\"";
  if (tree_branching.adaptive())  // only then: checkpoints from before adaptive K still resume
    s << ", \"tree_target\": \"" << qattention::describe(tree_branching) << "\"";
  s << "}";
  return s.str();
}

void LearnerConfig::validate() const {
  // The ranges are the options' own (learner_config_options): a configuration from the command
  // line has passed them already; one from elsewhere (a checkpoint) is held to them here.
  const std::vector<cli::OptionSpec> options = learner_config_options();
  const std::pair<const char*, double> values[] = {
      {"batch", batch},
      {"gamma", gamma},
      {"reward-scale", reward_scale},
      {"tau", tau},
      {"lr", learning_rate},
      {"weight-decay", weight_decay},
      {"grad-clip-value", grad_clip_value},
      {"grad-clip-norm", grad_clip_norm},
      {"q-reg", q_regularisation},
      {"huber-delta", huber_delta},
      {"n-step", static_cast<double>(n_step)},
      {"demo-margin", demo_margin},
      {"demo-cross-entropy", demo_cross_entropy},
      {"demo-share", demo_share},
  };
  for (const auto& [name, value] : values) cli::check_range(options, name, value, "the learner's settings");
  if (net.head_input == nets::HeadInput::voxel && net.architecture != nets::Architecture::light)
    throw UsageError("--head-input voxel is built for --architecture light only");
  if (tree_target_k < 0) throw Error("the learner's settings: tree_target_k must be >= 0, got " + std::to_string(tree_target_k));
  cli::check_range(voxels::hierarchy_options(), "depths", hierarchy.depths, "the learner's settings");
  try {
    hierarchy.validate();
  } catch (const Error& e) {
    throw UsageError(std::string("--offset: ") + e.what());
  }
}

double LearnerConfig::step_memory_bytes() const {
  const double v = hierarchy.voxels(), cells = v * v * v;
  const double grid_bytes = cells * (voxels::kChannels + 1) * sizeof(float);  // a grid and its Q volume
  const bool arm = net.architecture == nets::Architecture::arm;
  const double per_sample = (arm ? 80e6 : 6e6) * (cells / 4096.0) *
                            (static_cast<double>(net.base_channels) / nets::default_base_channels(net.architecture));
  double branches = 1, target_grids = 0;  // per sample: grids of every depth of the target's tree
  for (int d = 0; d < hierarchy.depths; ++d) {
    target_grids += branches;
    branches *= std::min<double>(std::max(1, tree_target_k), cells);
  }
  // 2: online and target networks (their outputs, and the leaves' activations kept for the heads).
  return batch * (per_sample + 2 * target_grids * grid_bytes) + 2 * nets::kDeferredHeadsBytes + 4e8;  // 0.4 GB base
}

void LearnerConfig::check_memory(double available_bytes) const {
  const double need = step_memory_bytes();
  if (need <= 0.8 * available_bytes) return;
  std::ostringstream s;
  s.precision(3);
  s << "--batch " << batch << " with --tree-target " << tree_target_k << " (" << hierarchy.depths << " depths of "
    << hierarchy.voxels() << "^3, " << nets::architecture_name(net.architecture) << " networks) needs about "
    << need / 1e9 << " GB per step; this machine has " << available_bytes / 1e9 << " GB";
  throw UsageError(s.str());
}

}  // namespace qte::learner
