#include "sim_step/simulator_options.hpp"

#include "tasks/task.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::sim_step {

std::vector<cli::OptionSpec> camera_options() {
  return {
      {"cameras", "LIST", "comma-separated cameras: front, wrist, overhead", "front"},
      {"image-size", "WxH", "camera resolution, e.g. 128x128 or 256x256", "128x128"},
      {"compress", "", "zstd-compress images and point clouds (for files on disk)", ""},
      voxels::no_points_option(),
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
      {"episodes", "N", "episodes to run", std::to_string(default_episodes)},
      {"variation", "V", "task variation, or 'random' for one per episode", "0"},
      {"scenes", "SET", "the scene set episodes are drawn from: demo, explore, eval (disjoint for every --seed) or any",
       scene_set_name(default_scenes)},
  };
}

EpisodePlan parse_episode_plan(const cli::Arguments& args, const std::string& task) {
  tasks::make_task(task);  // an unknown task fails before anything is written
  EpisodePlan plan;
  plan.task = task;
  plan.episodes = static_cast<int>(args.integer("episodes", 1, 10000000));
  plan.variation = args.text("variation") == "random" ? -1 : static_cast<int>(args.integer("variation", 0, 1000));
  plan.seed = args.seed();
  plan.scenes = scene_set_from_name(args.text("scenes"));
  return plan;
}

}  // namespace qte::sim_step
