#include "learner/learner_options.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdint>

#include "nets/qattention_net.hpp"
#include "qattention/branching_options.hpp"
#include "voxels/hierarchy_options.hpp"

namespace qte::learner {

using cli::default_text;

namespace {
constexpr int64_t kMaxSteps = 1000000000000;  // counts of steps and transitions: no value wraps
}  // namespace

std::vector<cli::OptionSpec> learner_config_options() {
  const LearnerConfig d;
  return {
      {"architecture", "A", "network per depth: light or arm", nets::architecture_name(d.net.architecture)},
      cli::integer_option("base-channels", "C", "first-level kernels (default: light 16, arm 64)", "", 1, 512),
      {"head-input", "I",
       "what the last depth's rotation and gripper head reads: pooled (every U-Net level pooled over the grid, as "
       "published) or voxel (also the finest level's features at the voxel taken; light only; our variation, "
       "docs/design.md)",
       nets::head_input_name(d.net.head_input)},
      cli::integer_option("batch", "B", "transitions per step (published: 128)", default_text(d.batch), 1, 100000),
      cli::real_option("gamma", "G", "discount", default_text(d.gamma), 0, 1),
      cli::real_option("reward-scale", "F", "reward multiplier in the target", default_text(d.reward_scale), 1e-9, 1e9),
      cli::real_option("tau", "T", "soft target update rate per step", default_text(d.tau), 0, 1),
      // Any positive rate (a test diverges on purpose).
      cli::real_option("lr", "R", "Adam learning rate", default_text(d.learning_rate), 1e-12, 1e30),
      cli::real_option("weight-decay", "W", "Adam weight decay", default_text(d.weight_decay), 0, 1e3),
      cli::real_option("grad-clip-value", "C", "clip every gradient element to +-C, per depth (published; 0: none)",
                       default_text(d.grad_clip_value), 0, 1e12),
      cli::real_option("grad-clip-norm", "N", "clip each depth's gradient L2 norm to N (0: none)",
                       default_text(d.grad_clip_norm), 0, 1e12),
      cli::real_option("q-reg", "L", "lambda of the lambda * mean|Q| regularisation", default_text(d.q_regularisation),
                       0, 1e6),
      cli::real_option("huber-delta", "D", "Huber loss threshold", default_text(d.huber_delta), 1e-9, 1e9),
      {"tree-target", "K",
       "bootstrap with tree expansion of K branches per non-leaf grid, ranked by the online and valued by the "
       "target networks (0: double DQN down the greedy path); 'auto': as many as each node's Q volume asks for "
       "(--k-margin or --k-mass, at most --k-max)",
       default_text(d.tree_target_k)},
      cli::integer_option("n-step", "N", "bootstrap after N transitions of a chain, summing their discounted rewards",
                          default_text(d.n_step), 1, 10),
      cli::real_option("demo-margin", "M",
                       "DQfD's large-margin loss on the demonstrations: each head's demonstrated action's Q "
                       "pushed M above every other's (0: none, as published)",
                       default_text(d.demo_margin), 0, 1e3),
      cli::real_option("demo-cross-entropy", "W",
                       "our variation: W times the cross-entropy of the rotation and gripper head's Q values "
                       "against the demonstrated bins, on the demonstrations (0: none, as published)",
                       default_text(d.demo_cross_entropy), 0, 1e3),
      cli::real_option("demo-share", "F",
                       "our variation: a share F of each batch from the demonstrations, the rest from the "
                       "agent's transitions, each part prioritised within its kind (0: one draw over all, as "
                       "published)",
                       default_text(d.demo_share), 0, 1),
  };
}

LearnerConfig learner_config_from(const cli::Arguments& args) {
  LearnerConfig config;
  config.net.architecture = nets::architecture_from_name(args.text("architecture"));
  config.net.base_channels = args.has("base-channels") ? static_cast<int>(args.integer("base-channels"))
                                                       : nets::default_base_channels(config.net.architecture);
  config.net.head_input = nets::head_input_from_name(args.text("head-input"));
  config.hierarchy = voxels::parse_hierarchy(args, 4, 128);  // the networks' smallest and largest grids
  config.batch = static_cast<int>(args.integer("batch"));
  config.gamma = args.real("gamma");
  config.reward_scale = args.real("reward-scale");
  config.tau = args.real("tau");
  config.learning_rate = args.real("lr");
  config.weight_decay = args.real("weight-decay");
  config.grad_clip_value = args.real("grad-clip-value");
  config.grad_clip_norm = args.real("grad-clip-norm");
  config.q_regularisation = args.real("q-reg");
  config.huber_delta = args.real("huber-delta");
  config.tree_branching = qattention::parse_branching(args, "tree-target", 0);
  config.tree_target_k = config.tree_branching.k;
  config.n_step = static_cast<int>(args.integer("n-step"));
  config.demo_margin = args.real("demo-margin");
  config.demo_cross_entropy = args.real("demo-cross-entropy");
  config.demo_share = args.real("demo-share");
  config.validate();
  config.check_memory(static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGE_SIZE)));
  return config;
}

std::vector<cli::OptionSpec> loop_options() {
  const LoopOptions d;
  return {
      cli::integer_option("steps", "N", "gradient steps to reach (0: write the initial networks and exit)",
                          default_text(d.steps), 0, kMaxSteps),
      {"follow", "", "keep reading the inputs as they grow; pace training by --replay-ratio", ""},
      {"stop-file", "FILE", "with --follow: finish once FILE exists and the allowed steps are done", ""},
      cli::real_option("replay-ratio", "R", "with --follow: gradient steps per agent transition",
                       default_text(d.replay_ratio), 0, 1e6),
      cli::integer_option("pretrain", "N",
                          "with --follow: steps allowed before any agent transition, on the demonstrations even below "
                          "--start-after",
                          default_text(d.pretrain), 0, kMaxSteps),
      cli::integer_option("start-after", "N", "train once the replay holds N transitions (demos included)",
                          default_text(d.start_after), 0, kMaxSteps),
      cli::integer_option("checkpoint-every", "N", "steps between checkpoints", default_text(d.checkpoint_every), 1,
                          kMaxSteps),
      {"metrics", "FILE", "CSV of training figures", ""},
      cli::integer_option("log-every", "N", "steps between metrics rows and progress lines", default_text(d.log_every),
                          1, kMaxSteps),
      cli::real_option("beta", "B",
                       "importance-weight exponent: (N p)^-B over its batch maximum (published: 1/sqrt(p), B = 0.5)",
                       default_text(d.beta), 0, 1),
      nets::torch_threads_option(d.threads),
  };
}

LoopOptions loop_options_from(const cli::Arguments& args) {
  LoopOptions loop;
  loop.steps = args.integer("steps");
  loop.start_after = args.integer("start-after");
  loop.pretrain = args.integer("pretrain");
  loop.replay_ratio = args.real("replay-ratio");
  loop.beta = args.real("beta");
  loop.follow = args.flag("follow");
  loop.stop_file = args.text("stop-file");
  loop.checkpoint_every = args.integer("checkpoint-every");
  loop.log_every = args.integer("log-every");
  loop.metrics_path = args.text("metrics");
  loop.seed = args.seed();
  loop.threads = static_cast<int>(args.integer("threads"));
  return loop;
}

std::vector<cli::OptionSpec> replay_options() {
  const replay::ReplayOptions d;
  return {
      {"uniform", "", "uniform replay sampling instead of prioritised", ""},
      cli::real_option("alpha", "A", "priority exponent", default_text(d.alpha), 0, 10),
      cli::integer_option("capacity", "N", "replay capacity in transitions (demos always kept)",
                          default_text(d.capacity), 1, 1000000000),
      cli::integer_option("cloud-memory", "MIB",
                          "memory for the replay's point clouds, each computed once when its frame is first sampled "
                          "(about 1 MiB a frame of 4 cameras at 128x128); frames beyond it have theirs computed at "
                          "every use",
                          default_text(d.cloud_memory_bytes >> 20), 0, int64_t{1} << 30),
  };
}

replay::ReplayOptions replay_options_from(const cli::Arguments& args) {
  replay::ReplayOptions options;
  options.capacity = static_cast<std::size_t>(args.integer("capacity"));
  options.prioritised = !args.flag("uniform");
  options.alpha = args.real("alpha");
  options.cloud_memory_bytes = static_cast<std::size_t>(args.integer("cloud-memory")) << 20;
  return options;
}

}  // namespace qte::learner
