#include "sim_step/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <thread>

#include "common/atomic_file.hpp"
#include "common/error.hpp"
#include "common/random.hpp"
#include "observation/observation.hpp"
#include "robot/joint_path.hpp"
#include "robot/pose_values.hpp"
#include "stream/field_names.hpp"

namespace qte::sim_step {
namespace {

constexpr double kStartTolerance_rad = 1e-3;  // a trajectory must start where the arm is
constexpr double kSettleAfterRelease_s = 0.5;  // physics after opening on a held object

}  // namespace

SimulatorOptions options_for_cameras(const std::vector<std::string>& cameras, int width, int height) {
  render::CameraIntrinsics intrinsics;
  intrinsics.width = width;
  intrinsics.height = height;
  SimulatorOptions options;
  options.cameras.clear();
  for (const std::string& name : cameras) options.cameras.push_back({name, intrinsics});
  return options;
}

std::vector<std::string> camera_names() { return {"front", "wrist", "overhead"}; }

Eigen::Isometry3d camera_pose(const std::string& name, const world::World& world) {
  const double table = world.layout().table_height_m;
  if (name == "front")  // across the table, facing the robot, as RLBench's front camera
    return render::look_at({1.05, 0.0, table + 0.85}, {0.0, 0.0, table + 0.05});
  if (name == "overhead")  // over the robot's shoulder
    return render::look_at({-0.5, 0.8, table + 1.0}, {0.15, 0.0, table});
  if (name == "wrist") {  // on the gripper, looking along the fingers
    Eigen::Isometry3d tcp = world.tcp_pose();
    Eigen::Isometry3d camera = tcp;
    camera.translation() = tcp * Eigen::Vector3d(0.06, 0, -0.12);
    camera.linear() = tcp.linear() * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
    return camera;
  }
  std::string known;
  for (const auto& n : camera_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown camera '" + name + "' (known cameras: " + known + ")");
}

Simulator::Simulator(const robot::RobotModel& robot, SimulatorOptions options)
    : robot_(robot), options_(std::move(options)) {
  const auto names = camera_names();
  for (const auto& c : options_.cameras)
    if (std::find(names.begin(), names.end(), c.name) == names.end())
      throw Error("unknown camera '" + c.name + "' (known cameras: front, wrist, overhead)");
}

Simulator::~Simulator() = default;

stream::Record Simulator::observe(const std::string& failure) {
  stream::Record obs(record_type::obs);
  for (const auto& camera : options_.cameras) {
    const render::CameraFrame frame =
        render::render(world_->collision_world(), camera.intrinsics, camera_pose(camera.name, *world_),
                       camera.name, options_.render_threads);
    const int64_t h = frame.rgb.rows, w = frame.rgb.cols;
    const std::string& n = camera.name;
    const bool z = options_.compress_images;
    obs.set<uint8_t>(n + fields::per_camera::rgb, {h, w, 3}, frame.rgb.ptr<uint8_t>(), z);
    obs.set<float>(n + fields::per_camera::depth, {h, w}, frame.depth.ptr<float>(), z);
    if (options_.point_clouds) obs.set<float>(n + fields::per_camera::points, {h, w, 3}, frame.points.ptr<float>(), z);
    observation::set_camera_pose(obs, n, frame.intrinsics, frame.world_from_camera);
  }
  observation::ArmState arm;
  arm.joints = world_->joint_positions();
  arm.velocities_rad_s = velocity_;
  arm.tool_in_world = world_->tcp_pose();
  arm.gripper_open = world_->gripper_open();
  arm.gripper_opening_m = world_->finger_opening_m();
  observation::set_arm_state(obs, arm);
  observation::EpisodeState episode;
  episode.step = step_;
  episode.episode_length = task_->episode_length();
  episode.frame = frame_++;
  episode.time_s = time_s_;
  episode.reward = success_ ? tasks::kSuccessReward : 0.0f;
  episode.terminal = terminal_;
  episode.success = success_;
  episode.task = task_name_;
  episode.variation = variation_;
  episode.episode_seed = episode_seed_;
  episode.description = task_->description(variation_);
  episode.ignore_collisions = ignore_collisions_;
  episode.failure = failure;
  observation::set_episode_state(obs, episode);
  if (options_.object_poses) set_object_fields(obs, *world_);
  return obs;
}

void set_object_fields(stream::Record& obs, const world::World& world) {
  const int n = world.object_count();
  std::string names;
  std::vector<uint8_t> roles, held;
  std::vector<double> poses, boxes;
  for (int id = 0; id < n; ++id) {
    const world::ObjectSpec& spec = world.object_spec(id);
    names += (id ? "," : "") + spec.name;
    roles.push_back(static_cast<uint8_t>(spec.role));
    held.push_back(world.held_object() == id);
    const auto pose = robot::pose_values(world.object_pose(id));
    poses.insert(poses.end(), pose.begin(), pose.end());
    const Eigen::AlignedBox3d box = world.object_box(id);
    for (const Eigen::Vector3d& corner : {box.min(), box.max()}) boxes.insert(boxes.end(), corner.data(), corner.data() + 3);
  }
  obs.set_string(fields::objects_names, names);
  obs.set<uint8_t>(fields::objects_role, {n}, roles);
  obs.set<double>(fields::objects_pose, {n, robot::kPoseValues}, poses);
  obs.set<double>(fields::objects_box, {n, 6}, boxes);
  obs.set<uint8_t>(fields::objects_held, {n}, held);
}

void Simulator::handle(const stream::Record& record, const stream::Emit& emit) {
  if (record.type() == record_type::reset) reset(record, emit);
  else if (record.type() == record_type::trajectory) execute(record, emit);
}

void Simulator::reset(const stream::Record& record, const stream::Emit& emit) {
  task_name_ = record.string(fields::task);
  try {
    task_ = tasks::make_task(task_name_);
  } catch (const StreamError&) {
    throw;
  } catch (const Error& e) {
    record.fail(fields::task, std::string("a known task: ") + e.what());
  }
  variation_ = record.has(fields::variation) ? record.scalar<int32_t>(fields::variation) : 0;
  if (variation_ < 0 || variation_ >= task_->variation_count())
    record.fail(fields::variation, "0 to " + std::to_string(task_->variation_count() - 1) + " for " + task_name_ +
                                       ", got " + std::to_string(variation_));
  episode_seed_ = record.has(fields::seed) ? record.scalar<int64_t>(fields::seed) : 0;
  world_ = std::make_unique<world::World>(robot_);
  std::mt19937_64 rng(static_cast<uint64_t>(episode_seed_));
  try {
    task_->build(*world_, variation_, rng);
  } catch (const Error& e) {  // name the scene, so that it can be built again by itself
    throw Error(task_name_ + " variation " + std::to_string(variation_) + " scene seed " +
                std::to_string(episode_seed_) + ": " + e.what());
  }
  world_->settle(0.25);  // objects come to rest before the first image
  step_ = frame_ = 0;
  time_s_ = 0;
  terminal_ = success_ = ignore_collisions_ = false;
  velocity_.setZero();
  emit(observe());
}

TrajectoryWaypoints trajectory_waypoints(const stream::Record& trajectory) {
  const auto times = trajectory.array<double>(fields::time_s);
  const auto joints = trajectory.array<double>(fields::joint_positions);
  const int64_t n = times.size();
  if (n < 1 || joints.shape != stream::Shape{n, robot::kArmJoints})
    trajectory.fail(fields::joint_positions, "float64 [N, 7] with N = " + std::to_string(n) +
                                                 " (the length of time_s), got " +
                                                 stream::shape_to_string(joints.shape));
  return {times.data, joints.data, n};
}

std::string Simulator::check_trajectory(const stream::Record& record) const {
  if (record.has(fields::failure)) return record.string(fields::failure);
  const TrajectoryWaypoints path = trajectory_waypoints(record);
  robot::JointPathLimits limits;
  limits.max_duration_s = options_.max_trajectory_s;
  const robot::JointVector now = world_->joint_positions();
  limits.start = &now;
  limits.start_tolerance_rad = kStartTolerance_rad;
  return robot::joint_path_failure(path.time_s, path.joints, path.n, robot_, limits);
}

void Simulator::execute(const stream::Record& record, const stream::Emit& emit) {
  if (!world_) throw StreamError(record.position, "trajectory before any reset: expected a reset record first");
  if (terminal_)
    throw StreamError(record.position, "trajectory after the episode ended: expected a reset record");
  step_ += 1;
  ignore_collisions_ = record.has(fields::ignore_collisions) && record.scalar<uint8_t>(fields::ignore_collisions) != 0;
  std::string failure = check_trajectory(record);
  if (failure.empty()) {
    const auto times = record.array<double>(fields::time_s);
    const auto joints = record.array<double>(fields::joint_positions);
    const int64_t n = times.size();
    // Sample the piecewise-linear trajectory at the control period; physics runs in between.
    const double duration = times[n - 1];
    const int control_steps = std::max(1, static_cast<int>(std::ceil(duration / options_.control_period_s - 1e-9)));
    int64_t segment = 0;
    double previous_t = 0;
    for (int s = 1; s <= control_steps && failure.empty(); ++s) {
      const double t = std::min(duration, s * options_.control_period_s);
      while (segment + 1 < n - 1 && times[segment + 1] < t) ++segment;
      robot::JointVector q;
      if (n == 1) {
        q = Eigen::Map<const robot::JointVector>(&joints[0]);
      } else {
        const double a = (t - times[segment]) / (times[segment + 1] - times[segment]);
        for (int k = 0; k < robot::kArmJoints; ++k)
          q[k] = joints[segment * 7 + k] + std::clamp(a, 0.0, 1.0) * (joints[(segment + 1) * 7 + k] - joints[segment * 7 + k]);
      }
      const double dt = t - previous_t;
      previous_t = t;
      const robot::JointVector before = world_->joint_positions();
      world_->step_towards(q, world_->finger_opening_m(), dt);
      velocity_ = (q - before) / std::max(dt, 1e-9);
      time_s_ += dt;
      failure = world_->robot_collision();
      if (options_.observe_every_step && failure.empty() && s < control_steps) emit(observe());
    }
    velocity_.setZero();
    if (failure.empty() && record.has(fields::gripper_open)) {
      const bool open = record.scalar<uint8_t>(fields::gripper_open) != 0;
      const bool is_open = world_->gripper_open();
      if (open && !is_open) {
        // Placing: a released object comes to rest before success is judged (stacks, checkers).
        const bool releasing = world_->held_object() >= 0;
        world_->open_gripper();
        if (releasing) {
          world_->settle(kSettleAfterRelease_s);
          time_s_ += kSettleAfterRelease_s;
        }
      }
      if (!open && is_open) world_->close_gripper();
      if (open != is_open) time_s_ += 0.25;
    }
  }
  success_ = failure.empty() && task_->success(*world_);
  terminal_ = success_ || !failure.empty() || step_ >= task_->episode_length();
  emit(observe(failure));
}

SceneSet scene_set_from_name(const std::string& name) {
  for (SceneSet set : {SceneSet::any, SceneSet::demo, SceneSet::explore, SceneSet::eval})
    if (name == scene_set_name(set)) return set;
  throw UsageError("scenes '" + name + "': expected any, demo, explore or eval");
}

const char* scene_set_name(SceneSet set) {
  switch (set) {
    case SceneSet::demo: return "demo";
    case SceneSet::explore: return "explore";
    case SceneSet::eval: return "eval";
    default: return "any";
  }
}

uint64_t scene_seed(uint64_t run_seed, SceneSet set, uint64_t episode) {
  if (set == SceneSet::any) return derive_seed(run_seed, episode);
  const uint64_t stream = derive_seed(run_seed, 0x5ce5e700ull + static_cast<uint64_t>(set));
  return (derive_seed(stream, episode) & ~uint64_t{3}) | static_cast<uint64_t>(set);  // < 2^63: derive_seed's range
}

stream::Record plan_reset(const EpisodePlan& plan, int index) {
  const uint64_t seed = scene_seed(plan.seed, plan.scenes, static_cast<uint64_t>(index));
  int variation = plan.variation;
  if (variation < 0)  // not from the low bits: they name the scene set
    variation = static_cast<int>(derive_seed(seed, 0x7a) % tasks::make_task(plan.task)->variation_count());
  stream::Record reset(record_type::reset);
  reset.set_string(fields::task, plan.task);
  reset.set_scalar<int32_t>(fields::variation, variation);
  reset.set_scalar<int64_t>(fields::seed, static_cast<int64_t>(seed));
  reset.set_scalar<int32_t>(fields::episode, index);
  return reset;
}

void SimStep::start(const stream::Emit& emit) { start_episodes_due(emit); }

void SimStep::handle(const stream::Record& record, const stream::Emit& emit) {
  simulator_.handle(record, emit);
  start_episodes_due(emit);
}

void SimStep::start_episodes_due(const stream::Emit& emit) {
  if (!plan_ || !simulator_.episode_over()) return;
  if (!chunks_) {
    while (simulator_.episode_over() && started_ < plan_->episodes)
      simulator_.handle(plan_reset(*plan_, started_++), emit);
    return;
  }
  count_ended_episode();
  while (simulator_.episode_over() && !stopped_ && started_ < plan_->episodes) {
    const int index = started_ % chunks_->episodes;
    const int chunk = chunks_->chunk_of(started_);
    if (index == 0 && !gate_->open(chunk)) {
      stopped_ = true;
      return;
    }
    EpisodePlan chunk_plan = *plan_;
    chunk_plan.seed = plan_->seed + static_cast<uint64_t>(chunk);
    started_ += 1;
    simulator_.handle(plan_reset(chunk_plan, index), emit);
    count_ended_episode();  // an episode can end at its reset (a scene already solved)
  }
}

void SimStep::count_ended_episode() {
  if (ended_ == started_ || !simulator_.episode_over()) return;  // none has ended since the last count
  chunk_steps_ += simulator_.steps();
  ended_ += 1;
  if (ended_ % chunks_->episodes == 0 || ended_ == plan_->episodes) {
    gate_->finished(chunks_->chunk_of(ended_ - 1), chunk_steps_);
    chunk_steps_ = 0;
  }
}

std::string DirectoryGate::path(int chunk, const std::string& suffix) const {
  char name[32];
  std::snprintf(name, sizeof name, "%04d.%s", chunk, suffix.c_str());
  return (std::filesystem::path(directory_) / name).string();
}

bool DirectoryGate::open(int chunk) {
  const std::filesystem::path stop = std::filesystem::path(directory_) / "stop";
  const std::string go = path(chunk, "go");
  for (;;) {  // a file test every 20 ms costs nothing beside an episode
    if (std::filesystem::exists(stop)) return false;
    if (std::filesystem::exists(go)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void DirectoryGate::finished(int chunk, int steps) {
  const std::string text = std::to_string(steps) + "\n";
  write_file_atomically(path(chunk, "steps"), text.data(), text.size());
}

}  // namespace qte::sim_step
