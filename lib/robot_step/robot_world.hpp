// The real robot as an episode stage, what robot-step runs: 'reset' and 'trajectory' records in,
// 'obs' records out, as the simulator does, with the arm and camera behind a spool and a judge
// for the reward. Every motion is checked before it is handed over: joint limits, joint speeds,
// a start where the arm is, and the whole arm (every link and both fingers) inside the
// workspace and above the table along the whole path, the move to the start pose included; a
// motion that fails a check is never sent, and ends the episode as an invalid action does in
// sim-step. Every answer of the driver is checked before it enters an observation.
#pragma once

#include <Eigen/Geometry>
#include <iosfwd>
#include <string>

#include "camera_recordings/camera_recordings.hpp"
#include "planning/robot_spheres.hpp"
#include "robot/robot_model.hpp"
#include "robot_step/judge.hpp"
#include "robot_step/spool.hpp"
#include "sim_step/simulator.hpp"
#include "world/scene_layout.hpp"

namespace qte::robot_step {

struct RobotOptions {
  camera_recordings::CameraSetup camera;
  robot::JointVector home = world::SceneLayout::ready_joints();  // rad: the simulation's start pose
  // Where the arm may go (world frame): every link's collision spheres but the base's, and the
  // gripper's tool point, stay in this box, which holds the arm at its start pose; its floor
  // is the table top.
  Eigen::AlignedBox3d workspace{Eigen::Vector3d(-0.65, -0.5, 0.752), Eigen::Vector3d(0.7, 0.5, 1.6)};
  // A driver's reached joints further than this from the motion's last row are a fault.
  double reach_tolerance_deg = 2.0;
  double speed_fraction = 1.0;  // of each joint's speed limit; slower motions are stretched in time
  robot::XarmTiming timing;  // the rows the driver streams (xarm-export's)
  int episode_length = 10;
  bool dry_run = false;     // write no motion: print it, and take it as done
  bool compress = false;    // zstd on the camera arrays
  std::ostream* log = nullptr;  // one line per motion handed over (or printed, dry)
};

class RobotWorld : public sim_step::EpisodeStage {
 public:
  RobotWorld(const robot::RobotModel& robot, RobotOptions options, Spool& spool, Judge& judge);

  // Protocol errors (a trajectory before any reset, or after the episode ended) throw
  // StreamError naming the record; a stop, a timeout or a camera fault throws Error.
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  bool episode_over() const override { return terminal_; }
  int steps() const override { return step_; }

 private:
  void reset(const stream::Record& record, const stream::Emit& emit);
  void execute(const stream::Record& record, const stream::Emit& emit);
  // The motion's rows, or why it must not be sent (an observation's failure reason).
  std::string check_motion(const stream::Record& record, std::vector<robot::XarmRow>& rows) const;
  std::string send(const std::vector<robot::XarmRow>& rows, const std::string& what);  // "" or the fault
  // Where the arm at q (the fingers `opening_m` apart) leaves the workspace or touches the
  // table: "<link> at (x, y, z)", or "" when it is inside.
  std::string arm_outside(const robot::JointVector& q, double opening_m) const;
  stream::Record observe();  // a frame from the camera and the arm's state
  void set_episode_fields(stream::Record& obs, const std::string& failure);

  const robot::RobotModel& robot_;
  planning::RobotSpheres spheres_;
  RobotOptions options_;
  Spool& spool_;
  Judge& judge_;
  Eigen::Isometry3d world_from_base_;
  EpisodeInfo episode_;
  int episodes_ = 0;
  robot::JointVector joints_ = robot::JointVector::Zero();
  bool joints_known_ = false;  // a driver has reported where the arm is
  double gripper_m_ = 0;
  bool started_ = false;
  int step_ = 0;
  double time_s_ = 0;
  bool terminal_ = true, success_ = false, ignore_collisions_ = false;
  int frame_ = 0;
  std::string last_frame_, last_motion_;  // for the judge
  std::string description_;
};

// The factor (at least 1) a path's times must be stretched by so that no joint goes faster
// than `fraction` of its speed limit.
double time_stretch(const double* time_s, const double* joints, int64_t n, const robot::RobotModel& robot,
                    double fraction);

}  // namespace qte::robot_step
