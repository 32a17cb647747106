// keyframe: demonstrations to replay transitions (keyframes, demo and crop augmentation).
#include <array>
#include <iostream>

#include "cli/command.hpp"
#include "keyframes/transitions.hpp"
#include "stream/reader.hpp"
#include "cli/stream_options.hpp"
#include "stream/writer.hpp"
#include "voxels/hierarchy_options.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "keyframe";
  u.summary = "turn demonstrations into C2F-ARM replay transitions";
  u.description = {
      "Reads demonstrations (obs records at every control step, as demo-record writes them; an "
      "episode ends at an 'episode' record or where an obs with frame 0 starts the next) and "
      "writes the replay transitions C2F-ARM learns from. Keyframes follow the published rule: "
      "a frame where the gripper opens or closes, the last frame, or a frame where the arm has "
      "stopped (every joint velocity within +-0.1 rad/s, the gripper unchanged around it, no "
      "stop in the 4 frames before, not the second-to-last frame); of two adjacent final "
      "keyframes the first is dropped.",
      "Besides the chain from the first frame, a chain starts at every --augment-every-th frame (demo "
      "augmentation), each leading through the keyframes after it, its steps (the time input) counted "
      "as --chain-steps says. A transition's action is its "
      "next keyframe's gripper pose: the voxel index at every depth (depth d inside the grid "
      "centred on depth d-1's voxel, shifted by U(-0.75, 0.75) * offset per axis with crop "
      "augmentation; an --offset too small for the shift to keep the keyframe inside is refused), rotation bins (Euler 'xyz', 72 bins of 5 degrees), gripper open/close, "
      "ignore-collisions; reward 100 on the final transition of a successful episode, else 0.",
      "Observations are written once each as compact 'frame' records (RGB and depth in uint16 "
      "millimetres, zstd-compressed, camera matrices, proprioception) ahead of the 'transition' "
      "records that refer to them by (episode_key, frame). Episodes that are empty, unsuccessful "
      "(unless --keep-failed), have frames out of order, no keyframe, or a keyframe outside the "
      "scene bounds are skipped and counted on standard error.",
      "With --agent the input is the learning loop's own stream instead: observations with "
      "qte-select's 'action' record after each non-terminal one (other records, such as "
      "plan-path's trajectories, are ignored). Every action becomes one transition, from the "
      "observation it was chosen for to the one it led to, whose reward and terminal flag it "
      "takes; the voxel indices and bounds are the action's own, exploration included. Every "
      "episode is kept, successful or not, and written as soon as it ends (terminal "
      "observation), so with --append a learner following the file sees it at once.",
  };
  u.arguments = {cli::input_file("demonstrations")};
  u.options = {
      cli::integer_option("augment-every", "N", "start a demo-augmentation chain at every N-th frame; 0 for none",
                          cli::default_text(keyframes::TransitionOptions{}.augmentation_every_n), 0, 100000),
      {"chain-steps", "S",
       "the step a demo-augmentation chain counts from, which sets its samples' time input: reset (each chain "
       "from 0, as the published code) or episode (the keyframes at or before its first frame, as an agent "
       "acting in that phase)",
       "reset"},
      {"no-crop-augmentation", "", "use the unshifted centres for the deeper grids", ""},
      {"keep-failed", "", "also convert unsuccessful episodes (reward 0 throughout)", ""},
      {"not-demo", "", "mark the transitions as the agent's own, not demonstrations", ""},
      {"agent", "", "convert the agent's episodes (obs and action records) instead of demonstrations", ""},
  };
  u.add_options(cli::append_options());
  u.options.push_back(cli::output_file());
  u.add_options(voxels::hierarchy_options());
  u.uses_randomness = true;
  u.examples = {
      {"demo-record --task reach_target --episodes 10 | keyframe > demo_transitions.rec",
       "the demonstrations of a run, ready for qattn-train"},
      {"sim-step --task reach_target < loop | qte-select --checkpoint c.rec | plan-path | tee loop | keyframe --agent --append --output replay.rec",
       "the actor of the learning loop: every finished episode is appended to the learner's replay"},
  };
  u.see_also = {"demo-record(1)", "voxelize(1)", "qattn-train(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  keyframes::TransitionOptions options;
  options.augmentation_every_n = static_cast<int>(args.integer("augment-every"));
  options.chain_steps = std::array{keyframes::ChainSteps::reset,
                                   keyframes::ChainSteps::episode}[args.choice("chain-steps", {"reset", "episode"})];
  options.hierarchy = voxels::parse_hierarchy(args);
  options.crop_augmentation = !args.flag("no-crop-augmentation");
  options.keep_failed = args.flag("keep-failed");
  options.demo = !args.flag("not-demo");
  options.seed = args.seed();

  const stream::WriteOptions write_options = cli::write_options_from(args, {args.input()});
  stream::RecordReader reader(args.input());
  stream::RecordWriter writer(args.text("output"), write_options);
  const auto convert_all = [&](auto&& converter) {
    stream::run_stage(converter, reader, writer);
    std::cerr << "keyframe: " << converter.counts().summary() << "\n";
  };
  if (args.flag("agent")) convert_all(keyframes::AgentEpisodeConverter(options));
  else convert_all(keyframes::EpisodeConverter(options));
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
