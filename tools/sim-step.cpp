// sim-step: the simulator as a filter: reset and trajectory records in, observations out.
#include <iostream>

#include "cli/command.hpp"
#include "robot/robot_model.hpp"
#include "sim_step/simulator.hpp"
#include "sim_step/simulator_options.hpp"
#include "tasks/task.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "sim-step";
  u.summary = "simulate the xArm 7 and a task in Bullet: trajectories in, RGB-D observations out";
  u.description = {
      "A long-running filter around a Bullet world: a table, the UFACTORY xArm 7 with its "
      "parallel gripper (lib/robot/xarm7.urdf), and the objects of a task. It reads 'reset' "
      "records (task, variation, seed) and 'trajectory' records (time-stamped joint waypoints "
      "and a gripper command, as plan-path writes them) and writes an 'obs' record after each: "
      "every camera's RGB, metric depth, intrinsics, extrinsics and world-frame point cloud; "
      "joint positions and velocities, gripper open flag and pose, step index; reward (100 on "
      "success), terminal, success, and the failure reason of the last action if any.",
      "A trajectory that does not start at the current joint positions, holds NaNs, lasts "
      "longer than 60 s, leaves the joint limits, exceeds the joint speed limit, or makes the "
      "arm touch the table or itself "
      "fails: the episode ends with reward 0 and the reason in the observation's 'failure' "
      "field, as an invalid action does in RLBench. An episode also ends after the task's "
      "episode length in next-best poses (10 as published; more where its expert needs more; "
      "the observations' episode_length). With --task, sim-step starts episodes by itself (the next one after each terminal "
      "observation) until --episodes have run; reset records on the input start one at any "
      "time. Other record types are ignored. After the last of --episodes it closes its "
      "output and reads its input to the end, so that an actor loop closed by a FIFO "
      "winds down without broken pipes.",
      "Cameras are rendered without a GPU, one ray per pixel against Bullet's collision world, "
      "with per-object colours, diffuse shading and textures (the digits of lift_numbered_block, "
      "the board of setup_checkers). Tasks: " + tasks::task_list() + ".",
  };
  u.arguments = {cli::input_file()};
  u.options = {
      {"task", "T", "run episodes of task T by itself (--episodes, --variation and --scenes apply to them)", ""},
      {"every-step", "",
       "also write an observation at every 50 ms control step of a trajectory "
       "(full demonstrations)",
       ""},
      cli::integer_option("threads", "N", "rendering threads", cli::default_text(sim_step::SimulatorOptions{}.render_threads), 1, 256),
      {"list-tasks", "",
       "print the tasks, one a line: name, variations, episode length and what variation 0 asks "
       "(tab-separated), and exit",
       ""},
  };
  u.options.push_back(cli::output_file());
  u.add_options(sim_step::chunk_options());
  u.add_options(sim_step::episode_options(1, sim_step::SceneSet::any));
  u.add_options(sim_step::camera_options());
  u.uses_randomness = true;
  u.examples = {
      {"sim-step --task reach_target --seed 3 < /dev/null | stream-png --dir frames/",
       "one reset, its first front image saved as PNG"},
      {"sim-step --task pick_and_lift --episodes 100 < fifo | qte-select --checkpoint ckpt/latest.rec | plan-path > fifo",
       "an actor: the learning loop closed by a FIFO"},
      {"sim-step --task reach_target --episodes 1000000 --chunk-episodes 10 --gate gate --scenes explore < fifo | ...",
       "an actor paced by its learning loop: touch gate/0000.go, gate/0001.go, ... to start each chunk, gate/stop to end"},
      {"stream-pack reset task=lift_numbered_block variation:i32=1 seed:i64=5 | sim-step --image-size 256x256",
       "one explicit reset, 256x256 images"},
  };
  u.see_also = {"qte-stream(5)", "plan-path(1)", "stream-png(1)", "stream-dump(1)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static void run(const cli::Arguments& args) {
  if (args.flag("list-tasks")) {
    for (const std::string& name : tasks::task_names()) {
      const auto task = tasks::make_task(name);
      std::cout << name << '\t' << task->variation_count() << '\t' << task->episode_length() << '\t'
                << task->description(0) << '\n';
    }
    return;
  }
  sim_step::SimulatorOptions options = sim_step::parse_camera_options(args);
  options.observe_every_step = args.flag("every-step");
  options.render_threads = static_cast<int>(args.integer("threads"));

  const robot::RobotModel robot = robot::RobotModel::xarm7();
  sim_step::Simulator simulator(robot, options);
  std::optional<sim_step::EpisodePlan> plan;
  if (args.has("task")) plan = sim_step::parse_episode_plan(args, args.text("task"));
  sim_step::run_episodes(args, simulator, plan);
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
