// robot-step: the real robot as a filter, a drop-in for sim-step: trajectories in, observations
// out, with the arm, the camera and the reward behind a spool directory and a judge.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "camera_recordings/camera_options.hpp"
#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "robot/robot_model.hpp"
#include "robot_step/robot_world.hpp"
#include "sim_step/simulator_options.hpp"
#include "tasks/task.hpp"

using namespace qte;

// The options' defaults are RobotOptions' own (lib/robot_step/robot_world.hpp).
static std::string workspace_text(const Eigen::AlignedBox3d& box) {
  std::string text;
  for (const Eigen::Vector3d& corner : {box.min(), box.max()})
    for (int k = 0; k < 3; ++k) text += (text.empty() ? "" : ",") + cli::default_text(corner[k]);
  return text;
}

static cli::Usage usage() {
  const robot_step::RobotOptions defaults;
  cli::Usage u;
  u.name = "robot-step";
  u.summary = "run a real robot and camera as sim-step runs the simulator: trajectories in, observations out";
  u.description = {
      "A drop-in for sim-step in the actor loop, with a real arm, a real RGB-D camera and a person "
      "(or a command) behind it. It reads 'reset' and 'trajectory' records, as plan-path writes "
      "them, and writes the 'obs' records sim-step writes (camera images and points, joint state, "
      "reward 100 on success, terminal, success, failure reason), so keyframe --agent, qattn-train "
      "--follow, episode-stats and examples/learn.sh work on them unchanged.",
      "The robot is reached through a spool directory (--spool; formats/robot-spool.md): each "
      "motion is written there as the joint file xarm-export writes, and an arm driver answers "
      "with the joints it reached or a fault; after each motion a camera recorder answers a "
      "capture request with a colour and a 16-bit depth PNG, read as obs-pack reads them with "
      "the camera's calibration (--intrinsics, --camera-pose or --extrinsics, in the "
      "simulation's world frame). examples/robot/xarm_driver.py and examples/robot/realsense_recorder.py "
      "are such drivers.",
      "Safety first: every motion is checked before it is written: finite, starting where the "
      "arm is, within the joint limits, no joint faster than --speed of its limit (slower "
      "motions are stretched in time to fit), and the whole arm, every link and both fingers "
      "(the planner's collision spheres), inside --workspace and above the table along the whole "
      "path; the move to --home is checked the same way along the straight joint-space line the "
      "driver takes from where the arm last was. A motion that fails a check is not sent, and ends the episode with reward 0 and the "
      "reason, as an invalid action does in sim-step. The stop file (--stop-file), a 'stop' a "
      "person writes in the spool, or a driver that does not answer in time ends robot-step with "
      "exit status 1; an interrupt (SIGINT, SIGTERM) ends it by the signal. Each writes 'stop' in "
      "the spool, which halts the drivers at once, and withdraws the motion not yet answered. "
      "--dry-run sends nothing: it prints each motion and takes it as reached.",
      "A driver is not trusted: answers are read only from regular files of at most 64 KiB; "
      "reached joints that are not finite or lie outside the robot's joint limits (by more than "
      "1 degree) stop the robot as an unreadable answer does; reached joints further than "
      "--reach-tolerance from the motion's last row end the episode as a driver fault naming "
      "both poses; when a request has both a fault and another answer, the fault wins; fault "
      "text and a judge's failure reason go into observations as valid UTF-8 of at most 200 "
      "bytes. An outcomes file is read a line of at most 4 KiB at a time (16 MiB in all), a "
      "judge command's output up to 64 KiB.",
      "Episodes: each reset asks for the scene to be set up, then moves the arm to --home with "
      "the gripper open. After each step the outcome comes from a person at the terminal (s "
      "success, f failure, Enter go on; q stops), from a file (--outcomes), or from a command "
      "(--judge CMD: 'CMD reset' before each episode, 'CMD outcome' after each step printing "
      "success, failure [reason] or continue; QTE_TASK, QTE_VARIATION, QTE_SEED, QTE_EPISODE, "
      "QTE_STEP, QTE_EPISODE_LENGTH, QTE_MOTION and QTE_FRAME in its environment, /dev/null as its input). An episode ends on success, on failure, or "
      "after --episode-length steps. With --task, episodes start by themselves as in sim-step "
      "(--episodes, chunks behind --gate); the reset records carry the scene seed a stand-in "
      "world can rebuild the scene from.",
  };
  u.arguments = {cli::input_file()};
  u.options = {
      {"spool", "DIR", "the directory the arm driver and camera recorder answer in", ""},
      {"task", "T", "run episodes of task T by itself (its episode length; --episodes, --variation, --scenes apply)",
       ""},
      {"judge", "CMD", "outcomes and resets from a command (default: a person at --terminal)", ""},
      {"outcomes", "FILE", "outcomes from a file, one a line: success, failure [reason], continue", ""},
      {"terminal", "TTY", "the terminal a person judges at", "/dev/tty"},
      {"home", "J1,...,J7",
       "start pose of every episode, joint angles in degrees (default: the simulation's, "
       "0,-20.05,0,42.97,0,63.03,0: the gripper above the table, pointing down)",
       ""},
      {"workspace", "X0,Y0,Z0,X1,Y1,Z1",
       "box the whole arm must stay in (world frame, m, within 10 m of the origin; the base excepted)",
       workspace_text(defaults.workspace)},
      cli::real_option("reach-tolerance", "DEG",
                       "largest difference between a motion's last row and the joints the driver reports",
                       cli::default_text(defaults.reach_tolerance_deg), 0.01, 30),
      cli::real_option("speed", "F", "fraction of each joint's speed limit a motion may use (faster ones are slowed)",
                       cli::default_text(defaults.speed_fraction), 0.01, 1.0),
      cli::real_option("rate", "HZ", "rows per second of the motions handed to the arm (its servo rate)",
                       cli::default_text(defaults.timing.rate_hz), robot::XarmTiming::kMinRate_hz,
                       robot::XarmTiming::kMaxRate_hz),
      cli::real_option("settle", "S", "seconds after a motion's end before its gripper command",
                       cli::default_text(defaults.timing.settle_s), robot::XarmTiming::kMinSettle_s,
                       robot::XarmTiming::kMaxSettle_s),
      cli::integer_option("episode-length", "N", "steps per episode (default: the task's, 10 without --task)", "", 1,
                          1000),
      {"stop-file", "FILE", "stop the robot at once when FILE exists", ""},
      cli::real_option("motion-timeout", "S", "longest wait for the arm driver's answer", "120", 0.1, 86400),
      cli::real_option("capture-timeout", "S", "longest wait for the camera recorder's answer", "10", 0.1, 86400),
      {"dry-run", "", "send nothing: print each motion on stderr and take it as reached", ""},
      {"compress", "", "zstd-compress images and point clouds (for files on disk)", ""},
  };
  u.options.push_back(cli::output_file());
  u.add_options(camera_recordings::camera_setup_options());
  u.add_options(sim_step::chunk_options());
  u.add_options(sim_step::episode_options(1, sim_step::SceneSet::any));
  u.uses_randomness = true;
  u.examples = {
      {"robot-step --spool spool --task reach_prism --episodes 6 --intrinsics 615.2,615.0,320.5,240.1 "
       "--camera-pose 1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383 < fifo | qte-select --checkpoint "
       "run/ckpt/latest.rec | plan-path | tee fifo | episode-stats",
       "6 greedy trials on the real robot, a person judging each step at the terminal"},
      {"robot-step --dry-run --spool spool --task reach_prism --outcomes outcomes.txt ... < fifo | ...",
       "check what would be sent, the camera live, the arm still"},
  };
  u.see_also = {"sim-step(1)", "xarm-export(1)", "obs-pack(1)", "plan-path(1)", "qte-stream(5)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static robot::JointVector home_from(const cli::Arguments& args) {
  const std::vector<double> degrees = args.reals("home", 7);
  robot::JointVector home;
  for (int k = 0; k < robot::kArmJoints; ++k) home[k] = degrees[k] * M_PI / 180.0;
  return home;
}

static Eigen::AlignedBox3d workspace_from(const cli::Arguments& args) {
  const std::vector<double> v = args.reals("workspace", 6);
  for (double x : v)  // bounded like every other number: a box of 1e300 m checks nothing
    if (std::abs(x) > 10) throw UsageError("--workspace: coordinates within 10 m of the world origin, got " + args.text("workspace"));
  if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) throw UsageError("--workspace: expected X0 < X1, Y0 < Y1, Z0 < Z1");
  return Eigen::AlignedBox3d(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
}

static void run(const cli::Arguments& args) {
  if (!args.has("spool")) throw UsageError("give --spool DIR, the directory the robot's drivers answer in");
  if (args.has("judge") && args.has("outcomes")) throw UsageError("--judge and --outcomes: give one");
  // An empty command would run whatever the shell makes of its arguments alone (the system's reset).
  if (args.has("judge") && args.text("judge").find_first_not_of(" \t") == std::string::npos)
    throw UsageError("--judge: give the command that judges (empty: the person at --terminal judges without it)");
  std::optional<sim_step::EpisodePlan> plan;
  if (args.has("task")) plan = sim_step::parse_episode_plan(args, args.text("task"));

  robot_step::RobotOptions options;
  options.camera = camera_recordings::camera_setup_from(args);
  if (!options.camera.intrinsics) throw UsageError("depth images need --intrinsics");
  if (args.has("home")) options.home = home_from(args);
  options.workspace = workspace_from(args);
  options.speed_fraction = args.real("speed");
  options.reach_tolerance_deg = args.real("reach-tolerance");
  options.timing.rate_hz = args.real("rate");
  options.timing.settle_s = args.real("settle");
  options.episode_length = args.has("episode-length") ? static_cast<int>(args.integer("episode-length"))
                           : plan                     ? tasks::make_task(plan->task)->episode_length()
                                                      : 10;
  options.dry_run = args.flag("dry-run");
  options.compress = args.flag("compress");
  options.log = &std::cerr;

  const std::string stop_file = args.text("stop-file");
  auto should_stop = [stop_file]() -> std::string {
    return !stop_file.empty() && std::filesystem::exists(stop_file) ? "the stop file " + stop_file + " exists" : "";
  };
  robot_step::Spool spool(args.text("spool"), static_cast<long>(::getpid()),
                          std::chrono::milliseconds(static_cast<int64_t>(args.real("motion-timeout") * 1000)),
                          std::chrono::milliseconds(static_cast<int64_t>(args.real("capture-timeout") * 1000)),
                          should_stop);
  // An interrupted robot-step halts the arm: the drivers stop at the spool's `stop`.
  write_on_fatal_signal(spool.directory() + "/stop", "robot-step was interrupted\n");
  std::unique_ptr<robot_step::Judge> judge = args.has("judge")      ? robot_step::command_judge(args.text("judge"))
                                             : args.has("outcomes") ? robot_step::file_judge(args.text("outcomes"))
                                                                    : robot_step::person_judge(args.text("terminal"));
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  robot_step::RobotWorld world(robot, options, spool, *judge);
  sim_step::run_episodes(args, world, plan);
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
