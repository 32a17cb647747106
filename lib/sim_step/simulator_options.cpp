#include "sim_step/simulator_options.hpp"

#include <unistd.h>

#include <memory>

#include "stream/reader.hpp"
#include "stream/writer.hpp"
#include "tasks/task.hpp"
#include "cli/stream_options.hpp"

namespace qte::sim_step {

std::vector<cli::OptionSpec> camera_options() {
  return {
      {"cameras", "LIST", "comma-separated cameras: front, wrist, overhead", "front"},
      {"image-size", "WxH", "camera resolution, e.g. 128x128 or 256x256", "128x128"},
      {"compress", "", "zstd-compress images and point clouds (for files on disk)", ""},
      cli::no_points_option(),
      {"objects", "", "also write every task object's name, role (target, distractor, other), pose, bounding box "
                      "and whether the gripper holds it in observations (objects.*: for analyses of where an agent "
                      "went and why it failed; agents never read them)", ""},
  };
}

SimulatorOptions parse_camera_options(const cli::Arguments& args) {
  const auto [width, height] = args.size("image-size", 8, 8, 4096, 4096);
  SimulatorOptions options = options_for_cameras(args.list("cameras"), width, height);
  options.point_clouds = !args.flag("no-points");
  options.compress_images = args.flag("compress");
  options.object_poses = args.flag("objects");
  return options;
}

std::vector<cli::OptionSpec> episode_options(int default_episodes, SceneSet default_scenes) {
  return {
      cli::integer_option("episodes", "N", "episodes to run", std::to_string(default_episodes), 1, 10000000),
      {"variation", "V", "task variation, or 'random' for one per episode", "0"},
      {"scenes", "SET", "the scene set episodes are drawn from: demo, explore, eval (disjoint for every --seed) or any",
       scene_set_name(default_scenes)},
  };
}

EpisodePlan parse_episode_plan(const cli::Arguments& args, const std::string& task) {
  const auto made = tasks::make_task(task);  // an unknown task fails before anything is written
  EpisodePlan plan;
  plan.task = task;
  plan.episodes = static_cast<int>(args.integer("episodes"));
  // The task's own range: a usage error naming the option, before any input is read.
  plan.variation = args.text("variation") == "random"
                       ? -1
                       : static_cast<int>(args.integer("variation", 0, made->variation_count() - 1));
  plan.seed = args.seed();
  plan.scenes = scene_set_from_name(args.text("scenes"));
  return plan;
}

std::vector<cli::OptionSpec> chunk_options() {
  return {
      cli::integer_option("chunk-episodes", "N",
                          "with --task: run episodes in chunks of N, chunk c drawn as --seed S + c "
                          "would draw them (an actor that stays up for a whole learning run); needs --gate",
                          "0", 0, 10000000),
      cli::integer_option("first-chunk", "C", "the first chunk this process runs", "0", 0, 100000000),
      cli::integer_option("chunk-stride", "S", "the chunks this process runs: C, C + S, C + 2S, ...", "1", 1, 1000000),
      {"gate", "DIR",
       "chunk c starts once DIR/cccc.go exists (c with at least four digits); none starts "
       "once DIR/stop exists; DIR/cccc.steps gets the environment steps of chunk c when it ends",
       ""},
  };
}

void run_episodes(const cli::Arguments& args, EpisodeStage& env, std::optional<EpisodePlan> plan) {
  const std::string input = args.input();
  std::unique_ptr<stream::RecordReader> reader;
  stream::RecordWriter writer(args.text("output"));
  const int chunk_episodes = static_cast<int>(args.integer("chunk-episodes"));
  if (chunk_episodes > 0 && (!plan || args.text("gate").empty()))
    throw UsageError("--chunk-episodes needs --task and --gate");
  DirectoryGate gate(args.text("gate"));
  SimStep stage = chunk_episodes > 0 ? SimStep(env, *plan,
                                               {chunk_episodes, static_cast<int>(args.integer("first-chunk")),
                                                static_cast<int>(args.integer("chunk-stride"))},
                                               gate)
                                     : SimStep(env, plan);
  stream::run_stage(
      stage,
      [&]() -> std::optional<stream::Record> {
        // Opened on demand: opening a FIFO blocks until its writer appears, and in the actor
        // loop that writer waits for our first observation.
        if (!reader) reader = std::make_unique<stream::RecordReader>(input);
        return reader->next();
      },
      [&](const stream::Record& obs) { writer.write(obs); });
  writer.close();
  if (!plan) return;
  // The last episode is over, but in a FIFO loop its last records are still on their way
  // back to us. Closing standard output lets the programs downstream see the end of the
  // stream, finish and close the FIFO; reading our input to its end meanwhile spares them
  // a broken pipe (exit 141) on the records they still pass on.
  if (args.text("output") == "-") ::close(STDOUT_FILENO);
  if (input == "-" && ::isatty(STDIN_FILENO)) return;
  if (!reader) reader = std::make_unique<stream::RecordReader>(input);
  while (reader->next()) {
  }
}

}  // namespace qte::sim_step
