// demo-record: expert demonstrations of a task, executed through the planner in the simulator.
#include <iostream>

#include "cli/command.hpp"
#include "demos/demo_recorder.hpp"
#include "planning/planner_options.hpp"
#include "robot/robot_model.hpp"
#include "sim_step/simulator_options.hpp"
#include "stream/field_names.hpp"
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
      {"task", "T", "one of: " + tasks::task_list(), "", false, true},
      cli::integer_option("retries", "N", "new seeds to try for an episode whose expert failed",
                          cli::default_text(demos::DemoOptions{}.retries), 0, 1000),
  };
  u.options.push_back(planning::time_budget_option());
  u.options.push_back(cli::output_file());
  u.add_options(sim_step::episode_options(10, sim_step::SceneSet::demo));
  u.add_options(sim_step::camera_options());
  u.uses_randomness = true;
  u.examples = {
      {"demo-record --task reach_target --episodes 10 --seed 0 --output demos.rec",
       "ten demonstrations, as the paper uses"},
      {"demo-record --task lift_numbered_block --variation random --image-size 256x256 --compress > demos.rec",
       "demonstrations of every variation at the resolution of the coarse-ambiguity tasks"},
  };
  u.see_also = {"sim-step(1)", "plan-path(1)", "keyframe(1)", "qte-stream(5)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static void run(const cli::Arguments& args) {
  demos::DemoOptions options;
  options.episodes = sim_step::parse_episode_plan(args, args.text("task"));
  options.retries = static_cast<int>(args.integer("retries"));
  options.planner = planning::planner_options_from(args);
  options.simulator = sim_step::parse_camera_options(args);
  options.simulator.point_clouds = true;  // the planner needs them; dropped on output with --no-points

  const robot::RobotModel robot = robot::RobotModel::xarm7();
  stream::RecordWriter writer(args.text("output"));
  const bool drop_points = args.flag("no-points");
  const auto summary = demos::record_demos(
      robot, options,
      [&](const stream::Record& r) {
        if (!drop_points || r.type() != record_type::obs) return writer.write(r);
        stream::Record slim = r;
        for (const auto& camera : options.simulator.cameras) slim.remove(camera.name + fields::per_camera::points);
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
