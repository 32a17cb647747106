// plan-path: next-best poses to collision-free joint trajectories on the sensed scene.
#include "cli/command.hpp"
#include "planning/motion_planner.hpp"
#include "planning/planner_options.hpp"
#include "point_clouds/cloud_filters.hpp"
#include "robot/robot_model.hpp"
#include "stream/reader.hpp"
#include "stream/stage.hpp"
#include "stream/writer.hpp"
#include "world/scene_layout.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "plan-path";
  u.summary = "plan collision-free xArm 7 trajectories to next-best poses on an OctoMap of the sensed scene";
  u.description = {
      "A filter between the agent and the simulator. Every record passes through; 'obs' records "
      "are remembered, and after each 'action' record (pose x, y, z, qx, qy, qz, qw in the world "
      "frame; gripper_open; ignore_collisions) plan-path writes a 'trajectory' record: time-stamped "
      "joint waypoints within the joint velocity and acceleration limits and the gripper command, "
      "or only a 'failure' with the reason: invalid_pose, outside_workspace, ik_failed, "
      "start_in_collision, goal_in_collision, no_path, timeout or (with --approach) approach_blocked.",
      "The scene is an OctoMap built from the last observation's point clouds (every camera's "
      "<camera>.points, inserted as rays from the camera so free space is known; unknown space "
      "counts as free), with the robot's own links and a held object filtered out, and an exact "
      "Euclidean distance field over its occupied voxels; those follow from the rays' endpoints, "
      "so the rays are traced only for --octomap. Points within 6 cm of the goal are left out: the "
      "agent chose to go there (a reach target, a success zone, the object it grasps). The robot is "
      "a set of spheres checked against that field and against itself. Inverse kinematics is damped least squares with joint limits "
      "and seeded restarts, taking the collision-free solution nearest the current joints "
      "(accuracy 0.5 mm, 0.23 degrees). The direct joint-space line is tried first, then "
      "OMPL's RRT-Connect within --time-budget, then deterministic shortcutting. Moves with "
      "ignore_collisions set follow a straight line of the gripper instead (grasp approaches). With "
      "--approach, a grasp (a move that ends closing the open gripper) is planned to the pose that "
      "distance back along the tool axis with nothing left out of the map, so the path cannot sweep "
      "through the object it goes for, and ends in a straight line to the grasp; its method is then "
      "direct+approach or rrt_connect+approach.",
      "Same inputs and --seed give the same bytes, unless a plan hits the time budget.",
  };
  u.arguments = {cli::input_file()};
  u.options = {
      {"octomap", "FILE.bt", "write the scene map of the last planned action (opens in octovis)", ""},
  };
  u.options.push_back(cli::output_file());
  u.add_options(planning::planner_options());
  u.add_options(point_clouds::cloud_filter_options());
  u.uses_randomness = true;
  u.examples = {
      {"sim-step --task reach_target < fifo | qte-select --checkpoint ckpt/latest.rec | plan-path > fifo",
       "the planner in the actor loop"},
      {"plan-path --octomap scene.bt < episode.rec | stream-dump --type trajectory",
       "re-plan a saved episode and look at the map"},
  };
  u.see_also = {"sim-step(1)", "demo-record(1)", "qte-stream(5)", "octovis(1)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static void run(const cli::Arguments& args) {
  const planning::PlannerOptions options = planning::planner_options_from(args);
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  const Eigen::Isometry3d world_from_base = world::SceneLayout{}.robot_base_pose();
  planning::PlanPathFilter filter(robot, world_from_base, options);
  filter.observe_through(point_clouds::observation_filter(point_clouds::parse_cloud_filters(args)));
  stream::RecordReader reader(args.input());
  stream::RecordWriter writer(args.text("output"));
  // The map before the stream is committed: a map that cannot be written leaves no --output.
  stream::run_stage(filter, reader, [&](const stream::Record& r) { writer.write(r); });
  if (args.has("octomap")) {
    if (!filter.last_scene()) throw Error("--octomap: no action was planned, so there is no scene map");
    filter.last_scene()->write_binary(args.text("octomap"));
  }
  writer.close();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
