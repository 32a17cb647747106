// qte-select: the acting agent. Observations in, next-best poses chosen by coarse-to-fine
// Q-attention with tree expansion (C2F-ARM+QTE) out, with optional exploration.

#include <cmath>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "nets/qattention_net.hpp"
#include "point_clouds/cloud_filters.hpp"
#include "qattention/branching_options.hpp"
#include "qattention/keyframe_stage.hpp"
#include "qattention/select_stage.hpp"
#include "robot/rotation_bins.hpp"
#include "stream/reader.hpp"
#include "stream/stage.hpp"
#include "stream/writer.hpp"
#include "voxels/hierarchy_options.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "qte-select";
  u.summary = "choose next-best poses with coarse-to-fine Q-attention and tree expansion (C2F-ARM+QTE)";
  u.description = {
      "The acting agent of the learning loop, a long-running filter. Every record passes through "
      "unchanged and in order; after each 'obs' record that is not terminal qte-select writes an "
      "'action' record: the next-best gripper pose for plan-path (pose, gripper_open, "
      "ignore_collisions) and what chose it: per depth the voxel, its grid's bounds, its centre "
      "and its Q-value; the rotation bins; the tree's value; the checkpoint's training step.",
      "The networks, one per depth, come from --checkpoint, with the scene bounds and offsets "
      "they were trained on (a learner's checkpoint keeps them; --bounds and --offset that "
      "differ are refused). The observation's point cloud (every "
      "camera's points, or points rebuilt from depth; pixels without a return are ignored) is "
      "voxelized at depth 0 over the bounds, and at each deeper depth d over the cube of "
      "centre +- offset d around a voxel chosen above. Tree expansion keeps the --k best voxels of every "
      "non-leaf grid and expands each: all the grids of a depth are voxelized in one pass over "
      "the cloud and evaluated in one batched forward. A branch is worth (its voxel's Q + the "
      "value of the best branch below it) / 2, a last-depth grid its largest Q, and the agent "
      "acts on the best path (Algorithm 2 of the QTE paper); --k 1 is C2F-ARM's greedy choice. "
      "--k auto spends branches where a node is unsure: every voxel whose Q is within --k-margin "
      "of the node's best, or the fewest best voxels holding --k-mass of its softmax, at least "
      "1 and at most --k-max; the action's 'branches' field says how many each depth expanded. "
      "The pose is the centre of the last depth's voxel, turned by the last network's best "
      "rotation bins (Euler 'xyz', 72 bins of 5 degrees); the gripper command is the better of "
      "open and close.",
      "Exploration is off by default (evaluation). --epsilon E goes top-down and at each depth, "
      "with probability E, replaces the chosen voxel by a uniformly random voxel of that depth's "
      "grid and chooses the deeper depths below it again by tree expansion; --index-noise adds "
      "Gaussian noise (in voxels) to the last depth's index, --rotation-noise to the three "
      "rotation bins (wrapped around), and --gripper-flip flips the gripper command. An action "
      "that exploration changed has explored = 1; the Q-values and value it carries are those "
      "of the voxels taken. The random choices of the n-th action are drawn from --seed and n: "
      "same inputs and seed give the same bytes (unless --reload loads new weights).",
      "With --reload the checkpoint file is checked at the start of every episode (an "
      "observation with step 0) and loaded again when it changed (qattn-train replaces its "
      "DIR/latest.rec by an atomic rename while it learns), with a line on standard error; "
      "every action's checkpoint_step says which weights chose it.",
      "With --png DIR a picture of every depth's grid is saved for each action as "
      "DIR/<n>.depth<d>.png (n the action's index, from 000000): the occupied voxels coloured "
      "by Q (blue low, red high) and the chosen voxel outlined in red. It costs one more forward "
      "per depth.",
      "With --keyframes FILE instead of --checkpoint there are no networks: the agent acts with "
      "the demonstrated keyframes of FILE (keyframe's output), each as keyframe discretized it "
      "for the learner: the voxel per depth, the rotation bins and the gripper command the "
      "networks are trained to choose. The n-th episode of the input takes FILE's n-th "
      "demonstration and its step s that demonstration's keyframe s (the last again after its "
      "end); ignore_collisions is --ignore-collisions', as for networks (which never choose "
      "it), not the expert's. Run on the demonstrations' own scenes (demo-record and sim-step "
      "with the same --task, --variation, --scenes and --seed; keyframe with the networks' "
      "--depths and --offset, --keep-failed so that every scene has its demonstration, and "
      "--no-crop-augmentation for the grids an acting network uses), it is the discretized "
      "expert acting open-loop: a reference for what this grid, planner and task allow, the "
      "ceiling of learning, though not a strict bound (a network acts closed-loop and may "
      "retry). The action's Q-values and value are 0 and its checkpoint_step is -1; the "
      "network options (--k, exploration, --png, --reload) are refused. --rotation-offset X,Y,Z "
      "adds X, Y and Z bins to every keyframe's rotation bins (wrapped around): the same "
      "rotation error in every action, to measure how precisely a task needs its rotations "
      "(the ceiling at 0,0,1 is that of a rotation head whose yaw is one bin off).",
  };
  u.arguments = {cli::input_file()};
  u.options = {
      {"checkpoint", "FILE",
       "the networks: a 'checkpoint' record as qattn-train writes it (required unless --keyframes)", ""},
      {"keyframes", "FILE", "act with FILE's demonstrated keyframes (keyframe's transitions) instead of networks", ""},
      {"rotation-offset", "X,Y,Z", "with --keyframes: bins (5 degrees each) added to every keyframe's rotation bins", ""},
      {"k", "K",
       "voxels expanded per non-leaf grid; 1 is C2F-ARM's greedy choice; 'auto': as many as the "
       "node's Q volume asks for (--k-margin or --k-mass, at most --k-max)",
       "10"},
      cli::real_option("epsilon", "E", "probability, per depth, of a random voxel instead of the chosen one", "0", 0,
                       1),
      cli::real_option("index-noise", "SIGMA",
                       "standard deviation of Gaussian noise on the last depth's voxel index, voxels", "0", 0, 1e6),
      cli::real_option("rotation-noise", "BINS",
                       "standard deviation of Gaussian noise on the rotation bins (5 degrees each)", "0", 0, 1e6),
      cli::real_option("gripper-flip", "P", "probability of flipping the gripper command", "0", 0, 1),
      {"ignore-collisions", "", "set ignore_collisions in every action (straight-line moves)", ""},
      {"reload", "", "at the start of each episode, load the checkpoint again when the file changed", ""},
      nets::torch_threads_option(2),
      nets::precision_option(),
      {"png", "DIR",
       "save the Q-values of every depth's grid as DIR/<n>.depth<d>.png (all at the end of the input, or none)", ""},
  };
  u.options.push_back(cli::output_file());
  u.add_options(voxels::checkpoint_hierarchy_options());
  u.add_options(qattention::branching_options());
  u.add_options(point_clouds::cloud_filter_options());
  u.uses_randomness = true;
  u.examples = {
      {"sim-step --task reach_target --episodes 10 < fifo | qte-select --checkpoint ckpt.rec | plan-path > fifo",
       "evaluate the networks on 10 episodes: the acting loop closed by a FIFO (mkfifo fifo)"},
      {"sim-step --task pick_and_lift --episodes 100 < fifo | qte-select --checkpoint run/latest.rec --reload "
       "--epsilon 0.1 --rotation-noise 2 | tee -a episodes.rec | plan-path > fifo",
       "an exploring actor that takes up the learner's newest weights at every episode and keeps "
       "what it saw and did"},
      {"demo-record --task stack_wine --episodes 50 --scenes eval --output e.rec && "
       "keyframe --keep-failed --no-crop-augmentation --output e.kf e.rec && "
       "sim-step --task stack_wine --episodes 50 --scenes eval < fifo | qte-select --keyframes e.kf | plan-path > fifo",
       "the ceiling of learning: the demonstrations' keyframes, discretized as the networks' targets, acted on "
       "their own scenes"},
      {"sim-step --task lift_numbered_block < /dev/null | qte-select --checkpoint ckpt.rec --k 1 --png q/ "
       "| stream-dump --type action",
       "the greedy C2F-ARM choice for one observation, and pictures of its Q-values"},
  };
  u.see_also = {"qattn-train(1)", "plan-path(1)", "sim-step(1)", "voxelize(1)", "qte-stream(5)"};
  return u;
}

namespace {

qattention::Exploration exploration_from(const cli::Arguments& args) {
  qattention::Exploration exploration;
  exploration.epsilon = args.real("epsilon");
  exploration.index_noise = args.real("index-noise");
  exploration.rotation_noise = args.real("rotation-noise");
  exploration.gripper_flip = args.real("gripper-flip");
  return exploration;
}

}  // namespace

// The agent without networks (--keyframes).
static void run_keyframes(const cli::Arguments& args) {
  for (const char* option : {"checkpoint", "k", "epsilon", "index-noise", "rotation-noise", "gripper-flip", "reload", "png"})
    if (args.has(option))
      throw UsageError(std::string("--keyframes acts without networks: leave out --") + option);
  const std::string path = args.text("keyframes");
  Eigen::Vector3i offset = Eigen::Vector3i::Zero();
  if (args.has("rotation-offset")) {
    const std::vector<double> bins = args.reals("rotation-offset", 3);
    for (int axis = 0; axis < 3; ++axis) {
      if (bins[axis] != std::round(bins[axis]) || std::abs(bins[axis]) >= robot::kRotationBins)
        throw UsageError("--rotation-offset: whole numbers of bins, each between -71 and 71 (got " +
                         args.text("rotation-offset") + ")");
      offset[axis] = static_cast<int>(bins[axis]);
    }
  }
  qattention::KeyframeStage stage(qattention::demonstrated_keyframes(path), path, args.flag("ignore-collisions"),
                                  offset);
  stream::RecordReader reader(args.input());
  stream::RecordWriter writer(args.text("output"));
  stream::run_stage(stage, reader, writer);
}

static void run(const cli::Arguments& args) {
  if (args.has("keyframes")) return run_keyframes(args);
  if (args.has("rotation-offset")) throw UsageError("--rotation-offset is for --keyframes (networks choose their own bins)");
  if (!args.has("checkpoint")) throw UsageError("--checkpoint FILE is required (or --keyframes FILE)");
  const std::string checkpoint = args.text("checkpoint");
  qattention::SelectOptions options;
  options.branching = qattention::parse_branching(args, "k", 1);
  options.exploration = exploration_from(args);
  options.ignore_collisions = args.flag("ignore-collisions");
  options.reload = args.flag("reload");
  options.seed = args.seed();
  options.prepare = point_clouds::observation_filter(point_clouds::parse_cloud_filters(args));

  nets::set_torch_threads(static_cast<int>(args.integer("threads")));
  nets::use_precision_option(args);
  qattention::CheckpointNetworks networks(checkpoint);
  options.hierarchy = voxels::checkpoint_hierarchy(args, networks.hierarchy(), networks.config().net.voxels,
                                                   networks.config().depths, checkpoint);
  std::unique_ptr<OutputDirectory> pictures;  // all or none, when the input ends
  if (args.has("png")) pictures = std::make_unique<OutputDirectory>(args.text("png"));
  if (pictures) options.png_dir = pictures->staging();

  qattention::SelectStage stage(networks, options);
  stream::RecordReader reader(args.input());
  stream::RecordWriter writer(args.text("output"));
  stream::run_stage(stage, reader, writer);
  if (pictures) pictures->commit();
}

int main(int argc, char** argv) {
  nets::prepare_process_for_networks(argv);
  return cli::run_tool(argc, argv, usage(), run);
}
