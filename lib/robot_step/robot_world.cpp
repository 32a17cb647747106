#include "robot_step/robot_world.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>

#include "camera_recordings/png_frames.hpp"
#include "cli/command.hpp"
#include "common/error.hpp"
#include "observation/observation.hpp"
#include "planning/collision_checker.hpp"
#include "robot/joint_path.hpp"
#include "stream/field_names.hpp"
#include "tasks/task.hpp"
#include "world/scene_layout.hpp"

namespace qte::robot_step {

namespace {

constexpr double kStartTolerance_rad = 1e-3;  // a motion must start where the arm is (sim-step's)
constexpr double kJointLimitSlack_deg = 1.0;  // a reported joint past its limit by more is a lie
constexpr double kHomeCheckStep_rad = 0.02;   // the move to the start pose, checked this finely

std::string point_text(const Eigen::Vector3d& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
  return text;
}

std::string degrees_text(const robot::JointVector& degrees) {
  std::string out;
  char number[32];
  for (int k = 0; k < robot::kArmJoints; ++k) {
    std::snprintf(number, sizeof number, "%s%.1f", k ? "," : "", degrees[k]);
    out += number;
  }
  return out;
}

}  // namespace

double time_stretch(const double* time_s, const double* joints, int64_t n, const robot::RobotModel& robot,
                    double fraction) {
  const robot::JointVector limit = robot.max_velocities() * fraction;
  double stretch = 1.0;
  for (int64_t i = 1; i < n; ++i) {
    const double dt = time_s[i] - time_s[i - 1];
    for (int k = 0; k < robot::kArmJoints; ++k) {
      const double distance = std::abs(joints[i * 7 + k] - joints[(i - 1) * 7 + k]);
      if (dt > 0) stretch = std::max(stretch, distance / (dt * limit[k]));
    }
  }
  return stretch;
}

RobotWorld::RobotWorld(const robot::RobotModel& robot, RobotOptions options, Spool& spool, Judge& judge)
    : robot_(robot),
      spheres_(robot),
      options_(std::move(options)),
      spool_(spool),
      judge_(judge),
      world_from_base_(world::SceneLayout().robot_base_pose()) {
  const std::string home = robot::joint_path_failure(std::vector<double>{0.0}.data(), options_.home.data(), 1, robot_);
  if (!home.empty()) throw UsageError("--home: " + home);
  gripper_m_ = robot_.max_finger_opening_m();
  const std::string outside = arm_outside(options_.home, gripper_m_);
  if (!outside.empty())
    throw UsageError("--home, --workspace: at the start pose the arm's " + outside +
                     " is outside the workspace or in the table");
}

std::string RobotWorld::arm_outside(const robot::JointVector& q, double opening_m) const {
  const Eigen::Vector3d tool = (world_from_base_ * robot_.tcp_pose(q)).translation();
  if (!options_.workspace.contains(tool)) return "gripper at " + point_text(tool);
  thread_local std::vector<planning::Sphere> placed;
  spheres_.place(q, opening_m, world_from_base_, placed);
  const double table_z = world::SceneLayout::kTableHeight_m;
  for (const planning::Sphere& s : placed) {
    if (s.link == 0) continue;  // the base stands on the table, where the arm is mounted
    // Inside: the sphere, shrunk by what spheres over-cover, in the box and above the table.
    const double r = std::max(0.0, s.radius_m - planning::kSphereOvercover_m);
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(r);
    const bool inside = options_.workspace.contains(s.centre - reach) && options_.workspace.contains(s.centre + reach) &&
                        s.centre.z() - r >= table_z;
    if (!inside) return robot_.links()[s.link].name + " at " + point_text(s.centre);
  }
  return "";
}

void RobotWorld::handle(const stream::Record& record, const stream::Emit& emit) {
  if (record.type() == record_type::reset) reset(record, emit);
  else if (record.type() == record_type::trajectory) execute(record, emit);
}

std::string RobotWorld::send(const std::vector<robot::XarmRow>& rows, const std::string& what) {
  const robot::XarmRow& last = rows.back();
  if (options_.log)
    *options_.log << "robot-step: " << (options_.dry_run ? "dry run, not sent: " : "") << what << ", " << rows.size()
                  << " rows, " << last.time_s << " s, to " << degrees_text(last.degrees) << " deg, gripper "
                  << last.gripper << std::endl;
  robot::JointVector reached = last.degrees;
  int gripper = last.gripper;
  last_motion_.clear();
  if (!options_.dry_run) {
    const std::string comment = "# robot-step: " + what + "\n";
    const MotionAnswer answer = spool_.move(rows, comment);
    last_motion_ = spool_.last_request();
    if (!answer.done) {
      joints_known_ = false;  // the arm stopped somewhere the driver did not say
      return answer.fault;
    }
    reached = answer.degrees, gripper = answer.gripper;
    // An answer no arm could give stops the robot: the driver cannot be trusted further.
    const robot::JointVector lower = robot_.lower_limits() * (180.0 / M_PI), upper = robot_.upper_limits() * (180.0 / M_PI);
    for (int k = 0; k < robot::kArmJoints; ++k)
      if (!(reached[k] >= lower[k] - kJointLimitSlack_deg && reached[k] <= upper[k] + kJointLimitSlack_deg)) {
        const std::string why = spool_.directory() + "/" + last_motion_ + ".done: joint " + std::to_string(k + 1) +
                                " reported at " + std::to_string(reached[k]) + " deg, outside its limits " +
                                std::to_string(lower[k]) + " to " + std::to_string(upper[k]) +
                                " deg: the driver's answer cannot be right";
        spool_.stop("robot-step stopped: " + why);
        throw Error(why + " (stop written)");
      }
  }
  // The arm is where the driver says, whether or not that is where it was sent.
  joints_ = reached * (M_PI / 180.0);
  joints_known_ = true;
  gripper_m_ = gripper / robot::kXarmGripperOpenUnits * robot_.max_finger_opening_m();
  if ((reached - last.degrees).cwiseAbs().maxCoeff() > options_.reach_tolerance_deg)
    return "reached " + degrees_text(reached) + " deg, not the commanded " + degrees_text(last.degrees) +
           " deg (more than " + cli::default_text(options_.reach_tolerance_deg) + " deg away)";
  return "";
}

stream::Record RobotWorld::observe() {
  const CaptureAnswer frame = spool_.capture();
  if (!frame.fault.empty()) throw Error("the camera recorder on " + spool_.directory() + ": " + frame.fault);
  stream::Record obs(record_type::obs);
  camera_recordings::add_camera_images(obs, options_.camera, camera_recordings::read_colour_png(frame.colour_png),
                                       camera_recordings::read_depth_png(frame.depth_png),
                                       frame.colour_png + " and " + frame.depth_png);
  if (options_.compress)
    for (const char* name :
         {fields::per_camera::rgb, fields::per_camera::depth_mm, fields::per_camera::depth, fields::per_camera::points})
      if (const stream::Field* f = obs.find(options_.camera.name + name)) {
        stream::Field compressed = *f;
        compressed.compress = true;
        obs.remove(options_.camera.name + name);
        obs.add(std::move(compressed));
      }
  camera_recordings::RobotState state;  // at rest: a motion has ended before each frame
  state.joints = joints_;
  state.gripper_opening_m = gripper_m_;
  observation::set_arm_state(obs, camera_recordings::arm_state(state, robot_, world_from_base_));
  last_frame_ = frame.colour_png;
  return obs;
}

void RobotWorld::set_episode_fields(stream::Record& obs, const std::string& failure) {
  observation::EpisodeState episode;
  episode.step = step_;
  episode.episode_length = options_.episode_length;
  episode.frame = frame_++;
  episode.time_s = time_s_;
  episode.reward = success_ ? tasks::kSuccessReward : 0.0f;
  episode.terminal = terminal_;
  episode.success = success_;
  episode.task = episode_.task;
  episode.variation = episode_.variation;
  episode.episode_seed = episode_.seed;
  episode.description = description_;
  episode.ignore_collisions = ignore_collisions_;
  episode.failure = failure;
  observation::set_episode_state(obs, episode);
}

void RobotWorld::reset(const stream::Record& record, const stream::Emit& emit) {
  episode_.task = record.has(fields::task) ? record.string(fields::task) : "real";
  episode_.variation = record.has(fields::variation) ? record.scalar<int32_t>(fields::variation) : 0;
  episode_.seed = record.has(fields::seed) ? record.scalar<int64_t>(fields::seed) : 0;
  episode_.episode = episodes_++;
  description_.clear();  // a simulated task's words, when the real scene is named after one
  const std::vector<std::string> known = tasks::task_names();
  if (std::find(known.begin(), known.end(), episode_.task) != known.end())
    description_ = tasks::make_task(episode_.task)->description(episode_.variation);
  judge_.reset(episode_);
  // The start pose, reached slowly by the driver (a motion of one row), the gripper open.
  robot::XarmRow home;
  home.degrees = options_.home * (180.0 / M_PI);
  home.gripper = static_cast<int>(robot::kXarmGripperOpenUnits);
  // The driver reaches a one-row motion in joint space along the straight line from where the
  // arm is: checked like any motion once a driver has said where that is.
  if (joints_known_) {
    const int steps =
        std::max(1, static_cast<int>(std::ceil((options_.home - joints_).cwiseAbs().maxCoeff() / kHomeCheckStep_rad)));
    for (int i = 0; i <= steps; ++i) {
      const std::string outside =
          arm_outside(joints_ + (options_.home - joints_) * (static_cast<double>(i) / steps), gripper_m_);
      if (!outside.empty())
        throw Error("the move to the start pose (--home) would take the arm's " + outside +
                    " outside the workspace or into the table: not sent; move the arm by hand, then run again");
    }
  }
  const std::string fault = send({home}, episode_.task + " episode " + std::to_string(episode_.episode) + ": start pose");
  if (!fault.empty()) throw Error("the arm driver could not reach the start pose: " + fault);
  step_ = frame_ = 0;
  time_s_ = 0;
  terminal_ = success_ = ignore_collisions_ = false;
  started_ = true;
  stream::Record obs = observe();
  set_episode_fields(obs, "");
  emit(obs);
}

std::string RobotWorld::check_motion(const stream::Record& record, std::vector<robot::XarmRow>& rows) const {
  if (record.has(fields::failure)) return record.string(fields::failure);  // the planner found no path
  const sim_step::TrajectoryWaypoints path = sim_step::trajectory_waypoints(record);
  robot::JointPathLimits limits;
  limits.start = &joints_;
  limits.start_tolerance_rad = kStartTolerance_rad;
  std::string failure = robot::joint_path_failure(path.time_s, path.joints, path.n, robot_, limits);
  if (!failure.empty()) return failure;
  std::vector<double> stretched(path.time_s, path.time_s + path.n);
  const double stretch = time_stretch(path.time_s, path.joints, path.n, robot_, options_.speed_fraction);
  for (double& t : stretched) t *= stretch;
  const double after_m = !record.has(fields::gripper_open)              ? gripper_m_
                         : record.scalar<uint8_t>(fields::gripper_open) ? robot_.max_finger_opening_m()
                                                                        : 0.0;
  try {
    rows = robot::xarm_rows(stretched.data(), path.joints, path.n, gripper_m_, after_m, robot_, options_.timing.rate_hz,
                            options_.timing.settle_s);
  } catch (const Error& e) {
    return std::string("invalid_trajectory:") + e.what();
  }
  if (rows.back().time_s > robot::JointPathLimits().max_duration_s) {  // the drivers' limit too
    char longer[96];
    std::snprintf(longer, sizeof longer, "invalid_trajectory:longer than %g s at --speed, with its gripper row",
                  robot::JointPathLimits().max_duration_s);
    return longer;
  }
  for (const robot::XarmRow& row : rows) {
    const double opening_m = row.gripper / robot::kXarmGripperOpenUnits * robot_.max_finger_opening_m();
    const std::string outside = arm_outside(row.degrees * (M_PI / 180.0), opening_m);
    if (!outside.empty()) {
      char at[48];
      std::snprintf(at, sizeof at, " at %.2f s", row.time_s);
      return "workspace:" + outside + at;
    }
  }
  return "";
}

void RobotWorld::execute(const stream::Record& record, const stream::Emit& emit) {
  if (!started_) throw StreamError(record.position, "trajectory before any reset: expected a reset record first");
  if (terminal_) throw StreamError(record.position, "trajectory after the episode ended: expected a reset record");
  step_ += 1;
  ignore_collisions_ = record.has(fields::ignore_collisions) && record.scalar<uint8_t>(fields::ignore_collisions) != 0;
  std::vector<robot::XarmRow> rows;
  std::string failure = check_motion(record, rows);
  if (failure.empty()) {
    const std::string fault =
        send(rows, episode_.task + " episode " + std::to_string(episode_.episode) + " step " + std::to_string(step_));
    if (!fault.empty()) failure = "driver_fault:" + fault;
    time_s_ += rows.back().time_s;
  }
  stream::Record obs = observe();
  if (failure.empty()) {
    const Verdict verdict =
        judge_.judge({episode_, step_, options_.episode_length, last_motion_, last_frame_});
    success_ = verdict.outcome == Outcome::success;
    if (verdict.outcome == Outcome::failure) failure = verdict.reason;
  }
  terminal_ = success_ || !failure.empty() || step_ >= options_.episode_length;
  set_episode_fields(obs, failure);
  emit(obs);
}

}  // namespace qte::robot_step
