// demo-record: expert demonstrations of a task, executed through the planner in the simulator.
#include <iostream>

#include "cli/command.hpp"
#include "demos/demo_recorder.hpp"
#include "stream/writer.hpp"
#include "tasks/task.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "demo-record";
  u.summary = "record expert demonstrations of a simulated task";
  u.description = {
      "Runs --episodes episodes of --task: each is reset from its own seed (derived from --seed), "
      "the task's scripted expert waypoints are planned with plan-path's planner and executed by "
      "sim-step's simulator, and an 'obs' record is written at every 50 ms control step, as "
      "RLBench stores demonstrations. Each episode ends with an 'episode' record (task, "
      "variation, seed, success, frames, attempts, failure).",
      "The expert's success rate is reported on standard error. An episode whose expert failed "
      "is kept as it is (marked success 0) unless --retries asks for new seeds, which is then "
      "said per episode.",
  };
  u.options = {
      {"task", "T", "one of: " + tasks::task_list(), ""},
      {"episodes", "N", "number of demonstrations", "10"},
      {"variation", "V", "task variation, or 'random' for one per episode", "0"},
      {"scenes", "SET", "the scene set episodes are drawn from: demo (disjoint from sim-step's explore and eval "
                        "scenes for every --seed), explore, eval or any", "demo"},
      {"retries", "N", "new seeds to try for an episode whose expert failed", "0"},
      {"cameras", "LIST", "comma-separated cameras: front, wrist, overhead", "front"},
      {"image-size", "WxH", "camera resolution", "128x128"},
      {"no-points", "", "leave point clouds out of the recorded observations (the planner still uses them)", ""},
      {"compress", "", "zstd-compress images and point clouds", ""},
      {"time-budget", "S", "planner time budget per move, seconds", "2"},
      {"output", "FILE", "where to write; '-' is standard output", "-"},
  };
  u.uses_randomness = true;
  u.examples = {
      {"demo-record --task reach_target --episodes 10 --seed 0 --output demos.rec",
       "ten demonstrations, as the paper uses"},
      {"demo-record --task lift_numbered_block --variation random --image-size 256x256 --compress > demos.rec",
       "demonstrations of every variation at the resolution of the coarse-ambiguity tasks"},
  };
  u.see_also = {"sim-step(1)", "plan-path(1)", "keyframe(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  if (!args.has("task")) throw UsageError("--task is required");
  demos::DemoOptions options;
  options.episodes.task = args.text("task");
  options.episodes.episodes = static_cast<int>(args.integer("episodes", 1, 1000000));
  options.episodes.variation = args.text("variation") == "random" ? -1 : static_cast<int>(args.integer("variation", 0, 1000));
  options.episodes.seed = args.seed();
  options.episodes.scenes = sim_step::scene_set_from_name(args.text("scenes"));
  options.retries = static_cast<int>(args.integer("retries", 0, 1000));
  options.planner.time_budget_s = args.real("time-budget", 0.001, 600);
  options.planner.seed = args.seed();
  options.simulator = sim_step::options_from_camera_arguments(args.text("cameras"), args.text("image-size"));
  options.simulator.point_clouds = true;  // the planner needs them; dropped on output with --no-points
  options.simulator.compress_images = args.flag("compress");
  if (options.episodes.episodes < 1 || options.retries < 0) throw UsageError("--episodes >= 1 and --retries >= 0");
  tasks::make_task(options.episodes.task);  // an unknown task fails before anything is written

  const robot::RobotModel robot = robot::RobotModel::xarm7();
  stream::RecordWriter writer(args.text("output"));
  const bool drop_points = args.flag("no-points");
  const auto summary = demos::record_demos(
      robot, options,
      [&](const stream::Record& r) {
        if (!drop_points || r.type() != "obs") return writer.write(r);
        stream::Record slim = r;
        for (const auto& camera : options.simulator.cameras) slim.remove(camera.name + ".points");
        writer.write(slim);
      },
      [](const std::string& line) { std::cerr << "demo-record: " << line << "\n"; });
  writer.close();
  std::cerr << "demo-record: expert success " << summary.successes << "/" << summary.episodes << " ("
            << 100.0 * summary.successes / summary.episodes << "%), " << summary.seconds / summary.episodes
            << " s per episode" << (summary.retried ? ", " + std::to_string(summary.retried) + " episodes retried" : "")
            << "\n";
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
