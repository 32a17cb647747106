#include "planning/motion_planner.hpp"

#include <ompl/base/samplers/UniformValidStateSampler.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include <chrono>
#include <cmath>

#include "common/random.hpp"
#include "planning/time_parametrization.hpp"
#include "robot/pose_values.hpp"
#include "stream/field_names.hpp"

namespace qte::planning {
namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

using Clock = std::chrono::steady_clock;

// Uniform joint sampling with its own seed, so a plan depends only on its inputs and seed
// (OMPL's default samplers draw seeds from a process-wide sequence).
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, uint64_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(static_cast<std::uint_fast32_t>(seed & 0xffffffffu));
  }
};

// Straight TCP lines take a step at least every this much rotation (their translation step
// is the straight_step_m option): small enough that IK follows one solution branch.
constexpr double kStraightStep_rad = 0.05;
// An IK solution more than this away from the previous step's, in any joint, has jumped to
// another branch: the TCP would not move in a straight line there.
constexpr double kBranchJump_rad = 0.3;
// RRT-Connect's longest edge in joint space (rad, Euclidean over the 7 joints). OMPL's default,
// 0.2 of the space's extent, is about 3 rad here; shorter edges extend the trees in steps a
// collision check along the edge rarely rejects. Chosen, not tuned by a measurement here.
constexpr double kRrtRange_rad = 0.5;
// An empty gripper opened wider than this can close on something: a move ending in a close is
// a grasp (the xArm gripper opens 8.5 cm).
constexpr double kOpenGripper_m = 0.02;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

PlanResult failed(const std::string& reason, Clock::time_point t0) {
  PlanResult result;
  result.failure = reason;
  result.planning_time_s = seconds_since(t0);
  return result;
}

robot::JointVector to_joints(const ob::State* state) {
  const auto* v = state->as<ob::RealVectorStateSpace::StateType>();
  robot::JointVector q;
  for (int k = 0; k < robot::kArmJoints; ++k) q[k] = v->values[k];
  return q;
}

}  // namespace

StartState start_state_from(const stream::Record& obs) {
  StartState start;
  const auto q = obs.array<double>(fields::joint_positions);
  if (q.size() != robot::kArmJoints) obs.fail(fields::joint_positions, "7 joint positions");
  for (int k = 0; k < robot::kArmJoints; ++k) {
    if (!std::isfinite(q[k])) obs.fail(fields::joint_positions, "finite values");
    start.joints[k] = q[k];
  }
  start.opening_m = obs.scalar<double>(fields::gripper_opening_m);
  start.holding = obs.scalar<uint8_t>(fields::gripper_open) == 0 && start.opening_m > robot::kHoldingOpening_m;
  return start;
}

Goal goal_from(const stream::Record& action) {
  const auto pose = action.array<double>(fields::pose);
  if (pose.size() != robot::kPoseValues) action.fail(fields::pose, "float64 [7]: x, y, z, qx, qy, qz, qw");
  Goal goal;
  goal.tcp_pose.translation() << pose[0], pose[1], pose[2];
  goal.pose_valid = robot::pose_values_valid(pose.data);
  if (goal.pose_valid) goal.tcp_pose = robot::pose_from_values(pose.data);
  goal.gripper_open = action.has(fields::gripper_open) ? action.scalar<uint8_t>(fields::gripper_open) != 0 : true;
  goal.ignore_collisions =
      action.has(fields::ignore_collisions) && action.scalar<uint8_t>(fields::ignore_collisions) != 0;
  return goal;
}

MotionPlanner::MotionPlanner(const robot::RobotModel& robot, const Eigen::Isometry3d& world_from_base,
                             PlannerOptions options)
    : robot_(robot),
      world_from_base_(world_from_base),
      options_(options),
      spheres_(robot),
      checker_(spheres_, world_from_base, options.collision) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
}

OccupancyScene MotionPlanner::scene_from(const stream::Record& obs, const StartState& start, const Goal* goal) const {
  const auto cameras = obs.prefixes(fields::per_camera::points);
  if (cameras.empty())
    throw StreamError(obs.position, "'obs' record has no point cloud: plan-path needs <camera>.points "
                                    "(sim-step without --no-points)");
  std::vector<Sphere> robot_now;
  spheres_.place(start.joints, start.opening_m, world_from_base_, robot_now);
  std::vector<Sphere> free_regions;
  if (start.holding) free_regions.push_back({world_from_base_ * robot_.tcp_pose(start.joints).translation(), 0.06, -1});
  // A grasp with a straight final approach sees the object it goes for: its path may not pass
  // through it, and the approach itself is checked against the robot and the table only.
  if (goal && goal->pose_valid && !approaches(start, *goal))
    free_regions.push_back({goal->tcp_pose.translation(), options_.goal_free_radius_m, -1});
  OccupancyScene scene(options_.scene);
  for (const auto& camera : cameras) {
    const auto points = obs.array<float>(camera + fields::per_camera::points);
    const auto extrinsics = obs.array<double>(camera + fields::per_camera::extrinsics);
    if (extrinsics.size() != 16) obs.fail(camera + fields::per_camera::extrinsics, "float64 [4, 4]");
    for (std::size_t i = 0; i < 16; ++i)
      if (!std::isfinite(extrinsics[i]))
        obs.fail(camera + fields::per_camera::extrinsics, "finite float64 [4, 4] (the camera pose)");
    if (points.shape.size() != 3 || points.shape[2] != 3)
      obs.fail(camera + fields::per_camera::points, "float32 [H, W, 3]");
    const Eigen::Vector3d origin(extrinsics[3], extrinsics[7], extrinsics[11]);
    scene.insert_camera(points.data, static_cast<std::size_t>(points.size() / 3), origin, robot_now, free_regions);
  }
  scene.build_distance_field();
  return scene;
}

std::vector<robot::JointVector> MotionPlanner::shortcut(std::vector<robot::JointVector> path, double opening_m,
                                                        const OccupancyScene* scene) const {
  // Greedy string pulling: from each kept waypoint jump to the farthest one reachable in a
  // straight joint-space line. Deterministic, and usually leaves 2-4 waypoints.
  std::vector<robot::JointVector> out = {path.front()};
  std::size_t i = 0;
  while (i + 1 < path.size()) {
    std::size_t j = path.size() - 1;
    while (j > i + 1 && !checker_.motion_valid(path[i], path[j], opening_m, scene)) --j;
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

bool MotionPlanner::straight_line(const robot::JointVector& start, const Eigen::Isometry3d& goal_in_base,
                                  double opening_m, std::vector<robot::JointVector>& path) const {
  const Eigen::Isometry3d from = robot_.tcp_pose(start);
  const double distance = (goal_in_base.translation() - from.translation()).norm();
  const double angle = Eigen::AngleAxisd(goal_in_base.linear() * from.linear().transpose()).angle();
  const int steps = std::max(1, static_cast<int>(std::ceil(std::max(distance / options_.straight_step_m,
                                                                     angle / kStraightStep_rad))));
  const Eigen::Quaterniond q0(from.linear()), q1(goal_in_base.linear());
  path = {start};
  robot::IkOptions ik;
  ik.restarts = 0;  // follow the current branch: a jump would not be a straight line
  for (int i = 1; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = from.translation() + t * (goal_in_base.translation() - from.translation());
    pose.linear() = q0.slerp(t, q1).toRotationMatrix();
    const auto q = robot::solve_ik(robot_, pose, path.back(), ik);
    if (!q || (*q - path.back()).cwiseAbs().maxCoeff() > kBranchJump_rad) return false;
    if (!checker_.state_valid(*q, opening_m, nullptr)) return false;
    path.push_back(*q);
  }
  return true;
}

PlanResult MotionPlanner::finish(std::vector<robot::JointVector> path, const std::string& method,
                                 Clock::time_point t0) const {
  const robot::JointVector vmax = robot_.max_velocities() * options_.velocity_scale;
  const robot::JointVector amax = robot::JointVector::Constant(options_.max_acceleration_rad_s2);
  TimedPath timed = time_parametrize(path, vmax, amax, options_.sample_period_s);
  PlanResult result;
  result.time_s = std::move(timed.time_s);
  result.joint_positions = std::move(timed.joint_positions);
  result.method = method;
  result.planning_time_s = seconds_since(t0);
  return result;
}

bool MotionPlanner::approaches(const StartState& start, const Goal& goal) const {
  const bool grasp = !goal.gripper_open && !start.holding && start.opening_m > kOpenGripper_m;
  return options_.approach_m > 0 && grasp && !goal.ignore_collisions;
}

PlanResult MotionPlanner::plan(const StartState& start, const Goal& goal, const OccupancyScene& scene,
                               uint64_t plan_index) const {
  const auto t0 = Clock::now();
  if (!goal.pose_valid) return failed("invalid_pose", t0);
  const Eigen::Isometry3d goal_in_base = world_from_base_.inverse() * goal.tcp_pose;
  // Farther than the TCP can ever be from the shoulder (0.93 m): no IK restarts needed.
  if ((goal_in_base.translation() - Eigen::Vector3d(0, 0, 0.267)).norm() > 0.95) return failed("outside_workspace", t0);

  robot::IkOptions ik;
  ik.seed = derive_seed(options_.seed, plan_index);
  if (goal.ignore_collisions) return plan_ignoring_scene(start, goal_in_base, ik, t0);

  if (!checker_.state_valid(start.joints, start.opening_m, &scene)) return failed("start_in_collision", t0);
  const bool approach = approaches(start, goal);
  // With an approach, the planned move ends approach_m back along the TCP's z axis.
  const Eigen::Isometry3d end_in_base =
      approach ? goal_in_base * Eigen::Translation3d(0, 0, -options_.approach_m) : goal_in_base;
  std::string failure, method;
  std::vector<robot::JointVector> approach_path;
  std::function<bool(const robot::JointVector&)> straight_approach;  // only with an approach
  if (approach)
    straight_approach = [&](const robot::JointVector& q) {
      return straight_line(q, goal_in_base, start.opening_m, approach_path);
    };
  const auto end_q = goal_configuration(start, end_in_base, scene, ik, failure, straight_approach);
  if (!end_q) return failed(failure, t0);
  std::vector<robot::JointVector> path = path_to(start, *end_q, scene, plan_index, method, failure);
  if (path.empty()) return failed(failure, t0);
  if (!approach) return finish(std::move(path), method, t0);
  path.insert(path.end(), approach_path.begin() + 1, approach_path.end());
  return finish(std::move(path), method + "+approach", t0);
}

std::vector<robot::JointVector> MotionPlanner::path_to(const StartState& start, const robot::JointVector& goal_q,
                                                       const OccupancyScene& scene, uint64_t plan_index,
                                                       std::string& method, std::string& failure) const {
  if (checker_.motion_valid(start.joints, goal_q, start.opening_m, &scene)) {
    method = "direct";
    return {start.joints, goal_q};
  }
  method = "rrt_connect";
  return rrt_connect(start, goal_q, scene, plan_index, failure);
}

// Grasp approaches and retreats: a straight line of the TCP, else straight in joint space,
// checked against the robot and the table only.
PlanResult MotionPlanner::plan_ignoring_scene(const StartState& start, const Eigen::Isometry3d& goal_in_base,
                                              robot::IkOptions ik, Clock::time_point t0) const {
  std::vector<robot::JointVector> path;
  if (straight_line(start.joints, goal_in_base, start.opening_m, path)) return finish(path, "straight_line", t0);
  const auto q = robot::solve_ik(robot_, goal_in_base, start.joints, ik);
  if (!q) return failed("ik_failed", t0);
  if (!checker_.motion_valid(start.joints, *q, start.opening_m, nullptr)) return failed("no_path", t0);
  return finish({start.joints, *q}, "direct", t0);
}

// Several IK solutions: the first collision-free one is the goal. `failure` says why there is none.
std::optional<robot::JointVector> MotionPlanner::goal_configuration(const StartState& start,
                                                                    const Eigen::Isometry3d& goal_in_base,
                                                                    const OccupancyScene& scene, robot::IkOptions ik,
                                                                    std::string& failure,
                                                                    const std::function<bool(const robot::JointVector&)>& accept) const {
  bool any_solution = false, any_free = false;
  for (int attempt = 0; attempt < 4; ++attempt) {
    ik.seed = derive_seed(ik.seed, attempt);
    const auto q = robot::solve_ik(robot_, goal_in_base, start.joints, ik);
    if (!q) break;
    any_solution = true;
    if (!checker_.state_valid(*q, start.opening_m, &scene)) continue;
    any_free = true;
    if (!accept || accept(*q)) return q;
  }
  failure = any_free ? "approach_blocked" : any_solution ? "goal_in_collision" : "ik_failed";
  return std::nullopt;
}

// RRT-Connect in joint space. Joints with 720-degree ranges are kept within half a turn of
// the start: more is never needed and it keeps collision checks dense.
std::vector<robot::JointVector> MotionPlanner::rrt_connect(const StartState& start, const robot::JointVector& goal_q,
                                                           const OccupancyScene& scene, uint64_t plan_index,
                                                           std::string& failure) const {
  auto space = std::make_shared<ob::RealVectorStateSpace>(robot::kArmJoints);
  ob::RealVectorBounds bounds(robot::kArmJoints);
  const robot::JointVector lo = robot_.lower_limits(), hi = robot_.upper_limits();
  for (int k = 0; k < robot::kArmJoints; ++k) {
    bounds.setLow(k, std::max(lo[k], std::min(start.joints[k], goal_q[k]) - M_PI));
    bounds.setHigh(k, std::min(hi[k], std::max(start.joints[k], goal_q[k]) + M_PI));
  }
  space->setBounds(bounds);
  // The sampler's own stream, apart from the IK seeds drawn from the same --seed.
  const uint64_t sampler_seed = derive_seed(options_.seed ^ 0x5a5a5a5aull, plan_index);
  space->setStateSamplerAllocator([sampler_seed](const ob::StateSpace* s) {
    return std::make_shared<SeededSampler>(s, sampler_seed);
  });
  og::SimpleSetup setup(space);
  const double opening = start.opening_m;
  setup.setStateValidityChecker([&](const ob::State* s) { return checker_.state_valid(to_joints(s), opening, &scene); });
  setup.getSpaceInformation()->setStateValidityCheckingResolution(options_.collision.check_step_rad / space->getMaximumExtent());
  ob::ScopedState<> from(space), to(space);
  for (int k = 0; k < robot::kArmJoints; ++k) {
    from[k] = start.joints[k];
    to[k] = goal_q[k];
  }
  setup.setStartAndGoalStates(from, to);
  auto planner = std::make_shared<og::RRTConnect>(setup.getSpaceInformation());
  planner->setRange(kRrtRange_rad);
  setup.setPlanner(planner);
  setup.setup();
  const ob::PlannerStatus status = setup.solve(ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(options_.time_budget_s),
      ob::exactSolnPlannerTerminationCondition(setup.getProblemDefinition())));
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    const bool timeout = status == ob::PlannerStatus::TIMEOUT || status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
    failure = timeout ? "timeout" : "no_path";
    return {};
  }
  std::vector<robot::JointVector> path;
  for (const ob::State* s : setup.getSolutionPath().getStates()) path.push_back(to_joints(s));
  return shortcut(path, opening, &scene);
}

stream::Record action_record(const Goal& goal) {
  stream::Record action(record_type::action);
  action.set<double>(fields::pose, {robot::kPoseValues}, robot::pose_values(goal.tcp_pose));
  action.set_scalar<uint8_t>(fields::gripper_open, goal.gripper_open);
  action.set_scalar<uint8_t>(fields::ignore_collisions, goal.ignore_collisions);
  return action;
}

PlanPathFilter::PlanPathFilter(const robot::RobotModel& robot, const Eigen::Isometry3d& world_from_base,
                               PlannerOptions options)
    : planner_(robot, world_from_base, options) {}

void PlanPathFilter::handle(const stream::Record& record, const stream::Emit& emit) {
  emit(record);
  if (record.type() == record_type::obs) {
    obs_ = prepare_ ? prepare_(record) : record;
    scene_.reset();
    return;
  }
  if (record.type() != record_type::action) return;
  if (!obs_)
    throw StreamError(record.position, "action before any observation: plan-path needs the 'obs' record "
                                       "(joint state and point cloud) ahead of each action");
  const StartState start = start_state_from(*obs_);
  const Goal goal = goal_from(record);
  scene_ = std::make_unique<OccupancyScene>(planner_.scene_from(*obs_, start, &goal));
  emit(trajectory_record(planner_.plan(start, goal, *scene_, plans_++), goal));
}

stream::Record trajectory_record(const PlanResult& plan, const Goal& goal) {
  stream::Record t(record_type::trajectory);
  if (!plan.failure.empty()) {
    t.set_string(fields::failure, plan.failure);
  } else {
    const int64_t n = static_cast<int64_t>(plan.time_s.size());
    std::vector<double> joints;
    for (const auto& q : plan.joint_positions) joints.insert(joints.end(), q.data(), q.data() + robot::kArmJoints);
    t.set<double>(fields::time_s, {n}, plan.time_s);
    t.set<double>(fields::joint_positions, {n, robot::kArmJoints}, joints);
    t.set_scalar<uint8_t>(fields::gripper_open, goal.gripper_open);
    t.set_string(fields::method, plan.method);
  }
  t.set_scalar<uint8_t>(fields::ignore_collisions, goal.ignore_collisions);
  return t;
}

}  // namespace qte::planning
