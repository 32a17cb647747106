// qattn-train: the learner. Replayed transitions in, Q-attention network checkpoints out.
#include <unistd.h>

#include <iostream>

#include "cli/command.hpp"
#include "learner/q_learner.hpp"
#include "learner/training_files.hpp"
#include "learner/training_loop.hpp"
#include "nets/qattention_net.hpp"
#include "qattention/branching_options.hpp"
#include "replay/replay_buffer.hpp"
#include "voxels/hierarchy_options.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "qattn-train";
  u.summary = "train the coarse-to-fine Q-attention networks from replayed transitions";
  u.description = {
      "Reads 'frame' and 'transition' records (keyframe's output: demonstrations, and with "
      "--agent the agent's own episodes) into a prioritised replay buffer and trains one "
      "Q-attention network per coarse-to-fine depth (LibTorch on the CPU) as C2F-ARM (+QTE) is "
      "published: per depth a 1-step bootstrap target r * 0.01 + 0.99 * Q'(s', a'), clamped at "
      "0, where the online networks choose a' and the target networks value it (double DQN). "
      "With --tree-target 0, a' is the online networks' greedy coarse-to-fine path and each "
      "depth's Q' the target network's Q of its voxel; with --tree-target K, a' is the best "
      "path of Q-attention tree expansion in which the online networks rank the K best voxels "
      "of every non-leaf grid and pick the leaf voxel and the rotation and gripper bins, and "
      "the target networks value them: branch values (q + q') / 2 and the max over branches "
      "on the target values (all of a batch's branches in one forward per depth). Huber loss "
      "on the Q of the transition's voxel at every depth, at the last depth one mean over "
      "translation, the three rotation axes and the gripper; lambda * mean|Q| over the "
      "translation volume and the head's 218 outputs; both weighted by the importance weights "
      "1/sqrt(p) over the batch maximum; Adam; gradients clipped to +-0.01 per depth; a soft "
      "target update after every step. Priorities are the mean over depths of the absolute "
      "TD error.",
      "Every default is the published value except the batch (32, published 128: a quarter of "
      "the time per step on a CPU) and the network (light, published arm: a twentieth of the cost "
      "per step); priorities count each depth once (the public code counts depth 0 twice). "
      "The table of settings in docs/learner.md gives each with its reason.",
      "Checkpoints go to DIR/step-NNNNNNNN.rec every --checkpoint-every steps (the last --keep "
      "kept) and DIR/latest.rec always names the newest; each is written whole or not at "
      "all. The first record of a checkpoint holds the online networks and the bounds and "
      "offsets they were trained on (what qte-select loads), then the target networks, then the learner's state (replay priorities, "
      "transitions read). With --resume a run continues from DIR/latest.rec: the same inputs "
      "are read up to where the checkpoint was taken, and the same seed gives the same "
      "steps as an uninterrupted run; a kill loses only the steps since the last checkpoint. "
      "A checkpoint with other settings is refused with the difference. --steps 0 writes the "
      "initial networks (for an actor to start with) and exits.",
      "With --follow the inputs are followed as they grow (files appended by keyframe "
      "--append, FIFOs until closed) and training is paced by --replay-ratio gradient steps "
      "per agent transition (demonstrations are not counted), starting once the replay holds "
      "--start-after transitions. Step s learns from exactly the agent transitions the pacing "
      "needs for it (the fewest n with pretrain + floor(ratio * n) > s), never from ones that "
      "happened to arrive early: a followed run is a function of its inputs and seed, and a "
      "killed one resumes to the same bytes. The run ends at --steps, or when --stop-file "
      "exists and the steps the transitions allow are done.",
      "Metrics go to --metrics as CSV (step, transitions, replay size, loss and per-depth "
      "loss, mean and max Q per depth, mean TD error, steps per second); a progress line "
      "goes to standard error. A non-finite loss stops the run with the step and the "
      "records of the batch; the last checkpoint stays the last good one. Transitions of "
      "another voxel size or depth count are refused with their position.",
      "Architectures: 'light' (default; plain 3x3x3 convolutions, 16 base channels, about 0.25 "
      "M parameters per depth, 0.09 GMAC per sample) and 'arm' (the published inception U-Net, "
      "64 base channels, 0.88 M / 1.19 M parameters, 1.8 GMAC per sample: 20 times the work "
      "per step on a CPU).",
  };
  // FILE and --checkpoint-dir are needed for training, not for the --steps-allowed query.
  u.arguments = {{"FILE", "frame and transition records; '-' is standard input (at least one)", true, true}};
  u.options = {
      {"checkpoint-dir", "DIR", "where checkpoints go (required)", ""},
      {"steps", "N", "gradient steps to reach (0: write the initial networks and exit)", "1000"},
      {"resume", "", "continue from DIR/latest.rec when it exists", ""},
      {"follow", "", "keep reading the inputs as they grow; pace training by --replay-ratio", ""},
      {"stop-file", "FILE", "with --follow: finish once FILE exists and the allowed steps are done", ""},
      {"replay-ratio", "R", "with --follow: gradient steps per agent transition", "1"},
      {"steps-allowed", "N", "print the gradient steps --follow allows after N agent transitions (with --pretrain and "
                             "--replay-ratio) and exit: the pacing rule, for scripts that wait on the learner", ""},
      {"pretrain", "N", "with --follow: steps allowed before any agent transition, on the demonstrations even below --start-after", "0"},
      {"start-after", "N", "train once the replay holds N transitions (demos included)", "200"},
      {"checkpoint-every", "N", "steps between checkpoints", "100"},
      {"keep", "N", "numbered checkpoints to keep", "3"},
      {"metrics", "FILE", "CSV of training figures", ""},
      {"log-every", "N", "steps between metrics rows and progress lines", "10"},
      {"architecture", "A", "network per depth: light or arm", "light"},
      {"base-channels", "C", "first-level kernels (default: light 16, arm 64)", ""},
      {"batch", "B", "transitions per step (published: 128)", "32"},
      {"gamma", "G", "discount", "0.99"},
      {"reward-scale", "F", "reward multiplier in the target", "0.01"},
      {"tau", "T", "soft target update rate per step", "0.0025"},
      {"lr", "R", "Adam learning rate", "0.0005"},
      {"weight-decay", "W", "Adam weight decay", "0.000001"},
      {"grad-clip-value", "C", "clip every gradient element to +-C, per depth (published; 0: none)", "0.01"},
      {"grad-clip-norm", "N", "clip each depth's gradient L2 norm to N (0: none)", "0"},
      {"q-reg", "L", "lambda of the lambda * mean|Q| regularisation", "1"},
      {"huber-delta", "D", "Huber loss threshold", "1"},
      {"tree-target", "K", "bootstrap with tree expansion of K branches per non-leaf grid, ranked by the online and valued by the target networks (0: double DQN down the greedy path); 'auto': as many as each node's Q volume asks for (--k-margin or --k-mass, at most --k-max)", "0"},
      {"n-step", "N", "bootstrap after N transitions of a chain, summing their discounted rewards", "1"},
      {"uniform", "", "uniform replay sampling instead of prioritised", ""},
      {"alpha", "A", "priority exponent", "0.7"},
      {"beta", "B", "importance-weight exponent: (N p)^-B over its batch maximum (published: 1/sqrt(p), B = 0.5)", "0.5"},
      {"capacity", "N", "replay capacity in transitions (demos always kept)", "100000"},
      {"threads", "N",
       "LibTorch threads; with more than 1 the program sets OMP_WAIT_POLICY=PASSIVE for itself unless it is set "
       "(spinning OpenMP threads slow a program sharing the cores), at the price of a second start (~0.4 s)",
       "2"},
  };
  u.add_options(voxels::hierarchy_options());
  u.add_options(qattention::branching_options());
  u.uses_randomness = true;
  u.examples = {
      {"qattn-train --checkpoint-dir ckpt --steps 2000 --metrics train.csv demos.rec",
       "train on demonstrations alone"},
      {"qattn-train --follow --stop-file actor.done --replay-ratio 1 --checkpoint-dir ckpt replay.rec &",
       "the learner of the online loop: trains as the actor appends episodes to replay.rec"},
      {"qattn-train --resume --checkpoint-dir ckpt --steps 5000 demos.rec", "continue a run after a kill"},
  };
  u.see_also = {"keyframe(1)", "qte-select(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  learner::LearnerConfig config;
  config.net.architecture = nets::architecture_from_name(args.text("architecture"));
  config.net.base_channels = args.has("base-channels") ? static_cast<int>(args.integer("base-channels", 1, 512))
                                                       : nets::default_base_channels(config.net.architecture);
  config.hierarchy = voxels::parse_hierarchy(args, 4, 128);  // the networks' smallest and largest grids
  config.batch = static_cast<int>(args.integer("batch", 1, 100000));
  config.gamma = args.real("gamma", 0, 1);
  config.reward_scale = args.real("reward-scale", 1e-9, 1e9);
  config.tau = args.real("tau", 0, 1);
  config.learning_rate = args.real("lr", 1e-12, 1e30);  // any positive rate (a test diverges on purpose)
  config.weight_decay = args.real("weight-decay", 0, 1e3);
  config.grad_clip_value = args.real("grad-clip-value", 0, 1e12);
  config.grad_clip_norm = args.real("grad-clip-norm", 0, 1e12);
  config.q_regularisation = args.real("q-reg", 0, 1e6);
  config.huber_delta = args.real("huber-delta", 1e-9, 1e9);
  config.tree_branching = qattention::parse_branching(args, "tree-target", 0);
  config.tree_target_k = config.tree_branching.k;
  config.n_step = static_cast<int>(args.integer("n-step", 1, 10));
  config.validate();
  config.check_memory(static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGE_SIZE)));

  learner::LoopOptions loop;
  loop.steps = args.integer("steps", 0, 1000000000000);
  loop.start_after = args.integer("start-after", 0, 1000000000000);
  loop.pretrain = args.integer("pretrain", 0, 1000000000000);
  loop.replay_ratio = args.real("replay-ratio", 0, 1e6);
  loop.beta = args.real("beta", 0, 1);
  loop.follow = args.flag("follow");
  loop.stop_file = args.text("stop-file");
  loop.checkpoint_every = args.integer("checkpoint-every", 1, 1000000000000);
  loop.log_every = args.integer("log-every", 1, 1000000000000);
  loop.metrics_path = args.text("metrics");
  loop.seed = args.seed();
  loop.threads = static_cast<int>(args.integer("threads", 1, 256));
  if (args.has("steps-allowed")) {
    std::cout << learner::allowed_steps(loop, args.integer("steps-allowed", 0, INT64_MAX)) << "\n";
    return;
  }
  if (!args.has("checkpoint-dir")) throw UsageError("--checkpoint-dir is required");
  if (args.positional().empty()) throw UsageError("missing argument FILE");
  replay::ReplayOptions replay_options;
  replay_options.capacity = static_cast<std::size_t>(std::max<int64_t>(1, args.integer("capacity", 1, 1000000000)));
  replay_options.prioritised = !args.flag("uniform");
  replay_options.alpha = args.real("alpha", 0, 10);

  nets::set_torch_threads(loop.threads);
  nets::seed_torch(loop.seed);
  learner::QLearner learner(config);
  replay::ReplayBuffer replay(replay_options);
  learner::InputFollower inputs(args.positional(), loop.follow);  // a missing input fails before any directory is made
  learner::CheckpointDirectory checkpoints(args.text("checkpoint-dir"), static_cast<int>(args.integer("keep", 1, 100000)));
  learner::TrainingLoop training(learner, replay, inputs, checkpoints, loop, std::cerr);
  training.start(args.flag("resume"));
  training.run();
}

int main(int argc, char** argv) {
  nets::prepare_process_for_networks(argv);
  return cli::run_tool(argc, argv, usage(), run);
}
