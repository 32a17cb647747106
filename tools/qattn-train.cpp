// qattn-train: the learner. Replayed transitions in, Q-attention network checkpoints out.
#include <filesystem>
#include <iostream>

#include "cli/command.hpp"
#include "learner/learner_options.hpp"
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
      "loss, mean and max Q per depth, mean TD error, steps per second; last, how well the "
      "rotation and gripper head agrees with the batches' own actions: agree_rotation_x, _y, "
      "_z and agree_gripper, the share of samples whose greedy bin is the transition's, and "
      "loss_rotation, the mean Huber loss of the rotation terms; on demonstrations alone these "
      "say whether the head fits them); a progress line goes to standard error. A non-finite "
      "loss stops the run with the step and the records of the batch; the last checkpoint stays the last good one. Transitions of "
      "another voxel size, depth count or grid edge (keyframed with another --offset or "
      "scene) are refused with their position.",
      "Architectures: 'light' (default; plain 3x3x3 convolutions, 16 base channels, about 0.25 "
      "M parameters per depth, 0.09 GMAC per sample) and 'arm' (the published inception U-Net, "
      "64 base channels, 0.88 M / 1.19 M parameters, 1.8 GMAC per sample: 20 times the work "
      "per step on a CPU).",
  };
  // FILE and --checkpoint-dir are needed for training, not for the --steps-allowed and
  // --print-precision queries.
  u.arguments = {{"FILE", "frame and transition records; '-' is standard input (at least one)", true, true}};
  u.options = {
      {"checkpoint-dir", "DIR", "where checkpoints go (required)", ""},
      {"resume", "", "continue from DIR/latest.rec when it exists", ""},
      {"overwrite", "",
       "start over in a DIR that holds a run (its checkpoints are replaced); without it or "
       "--resume such a DIR is refused",
       ""},
      cli::integer_option("steps-allowed", "N",
                          "print the gradient steps --follow allows after N agent transitions (with --pretrain and "
                          "--replay-ratio) and exit: the pacing rule, for scripts that wait on the learner",
                          "", 0, INT64_MAX),
      cli::integer_option("keep", "N", "numbered checkpoints to keep", "3", 1, 100000),
      nets::precision_option(),
      {"print-precision", "",
       "print what the networks run in here with these options (fp32 or bf16, then why "
       "fp32 where bf16 was asked for) and exit; the progress lines end with it too",
       ""},
  };
  u.add_options(learner::loop_options());
  u.add_options(learner::learner_config_options());
  u.add_options(learner::replay_options());
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
  const learner::LearnerConfig config = learner::learner_config_from(args);
  learner::LoopOptions loop = learner::loop_options_from(args);
  if (args.has("steps-allowed")) {
    std::cout << learner::allowed_steps(loop, args.integer("steps-allowed")) << "\n";
    return;
  }
  if (args.flag("print-precision")) {
    nets::use_precision_option(args);
    std::cout << nets::precision_in_use(config.net, config.hierarchy.voxels(), config.batch) << "\n";
    return;
  }
  if (!args.has("checkpoint-dir")) throw UsageError("--checkpoint-dir is required");
  if (args.positional().empty()) throw UsageError("missing argument FILE");
  const std::string run_checkpoint = args.text("checkpoint-dir") + "/latest.rec";
  if (args.flag("resume") && args.flag("overwrite")) throw UsageError("--resume and --overwrite exclude each other");
  if (!args.flag("resume") && !args.flag("overwrite") && std::filesystem::exists(run_checkpoint))
    throw UsageError("--checkpoint-dir " + args.text("checkpoint-dir") + " holds a run (" + run_checkpoint +
                     "): --resume continues it, --overwrite starts over");
  const replay::ReplayOptions replay_options = learner::replay_options_from(args);

  nets::set_torch_threads(loop.threads);
  nets::use_precision_option(args);
  const std::string in_use = nets::precision_in_use(config.net, config.hierarchy.voxels(), config.batch);
  loop.networks_in = in_use.substr(0, in_use.find(' '));
  nets::seed_torch(loop.seed);
  learner::QLearner learner(config);
  replay::ReplayBuffer replay(replay_options);
  learner::InputFollower inputs(args.positional(), loop.follow);  // a missing input fails before any directory is made
  learner::CheckpointDirectory checkpoints(args.text("checkpoint-dir"), static_cast<int>(args.integer("keep")));
  learner::TrainingLoop training(learner, replay, inputs, checkpoints, loop, std::cerr);
  training.start(args.flag("resume"));
  training.run();
}

int main(int argc, char** argv) {
  nets::prepare_process_for_networks(argv);
  return cli::run_tool(argc, argv, usage(), run);
}
