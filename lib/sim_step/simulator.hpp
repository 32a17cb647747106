// The sim-step loop as a library: `reset` and `trajectory` records in, `obs` records out.
// A trajectory is executed at the physics rate; its gripper command is applied at the end.
// Anything wrong with an action (limits, collisions, a planner failure) ends the episode with
// reward 0 and the reason in the observation, as an invalid action does in RLBench.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "render/camera.hpp"
#include "robot/robot_model.hpp"
#include "world/world.hpp"
#include "stream/record.hpp"
#include "stream/stage.hpp"
#include "tasks/task.hpp"

namespace qte::sim_step {

struct CameraSpec {
  std::string name;              // "front", "wrist", "overhead"
  render::CameraIntrinsics intrinsics;
};

struct SimulatorOptions {
  std::vector<CameraSpec> cameras = {{"front", {}}};
  bool point_clouds = true;           // include <camera>.points in observations
  bool observe_every_step = false;    // also emit an obs at every control step of a trajectory
  double control_period_s = 0.05;     // 20 Hz control steps along trajectories
  // The longest trajectory one next-best pose may take: the arm crosses its workspace at full
  // speed in about 2 s; a longer one fails the action rather than run for minutes.
  double max_trajectory_s = 60.0;
  int render_threads = 2;
  bool compress_images = false;       // zstd on rgb/depth/points (for files on disk)
  // Also write the task's objects as the simulator knows them (objects.*: names, roles, poses,
  // bounding boxes, which one is held), for analyses of where an agent went and why it
  // failed; the agent never reads them.
  bool object_poses = false;
};

// The waypoints of a 'trajectory' record (time_s [N], joint_positions [N, 7] in radians), its
// shapes checked (StreamError naming the record otherwise): what sim-step and robot-step execute.
struct TrajectoryWaypoints {
  const double* time_s;
  const double* joints;
  int64_t n;
};
TrajectoryWaypoints trajectory_waypoints(const stream::Record& trajectory);

// The objects.* fields of an observation: every object of `world` in id order, its name
// (objects.names, joined by commas), role (ObjectSpec::Role's code), pose, bounding box in
// its own frame (lower then upper corner) and whether the gripper holds it (objects.held:
// what tells a grasp that closed on nothing, or a dropped object, from one that holds).
void set_object_fields(stream::Record& obs, const world::World& world);

// Options for the cameras named in `cameras` ("front", "wrist") at width x height pixels, as the
// tools' --cameras and --image-size give them (parse_camera_options).
SimulatorOptions options_for_cameras(const std::vector<std::string>& cameras, int width, int height);

// The camera poses of the scene layout (front: facing the robot across the table).
Eigen::Isometry3d camera_pose(const std::string& name, const world::World& world);
std::vector<std::string> camera_names();

// A stage that runs episodes one after another, what SimStep drives: the simulator, or the
// real robot behind robot-step (lib/robot_step).
class EpisodeStage : public stream::Stage {
 public:
  virtual bool episode_over() const = 0;
  virtual int steps() const = 0;  // next-best poses executed in the current episode
};

class Simulator : public EpisodeStage {
 public:
  Simulator(const robot::RobotModel& robot, SimulatorOptions options);
  ~Simulator() override;

  // Consumes one record; `emit` receives each observation produced. Records other than
  // reset and trajectory produce nothing. Protocol errors (a trajectory before any reset,
  // or after the episode ended) throw StreamError naming the record.
  void handle(const stream::Record& record, const stream::Emit& emit) override;

  bool episode_over() const override { return terminal_; }
  int steps() const override { return step_; }

  // For tests and tools that drive the world directly.
  world::World* world() { return world_.get(); }
  const tasks::Task* task() const { return task_.get(); }

 private:
  stream::Record observe(const std::string& failure = "");
  void reset(const stream::Record& record, const stream::Emit& emit);
  void execute(const stream::Record& record, const stream::Emit& emit);
  std::string check_trajectory(const stream::Record& record) const;

  const robot::RobotModel& robot_;
  SimulatorOptions options_;
  std::unique_ptr<world::World> world_;
  std::unique_ptr<tasks::Task> task_;
  std::string task_name_;
  int variation_ = 0;
  int64_t episode_seed_ = 0;
  int step_ = 0;    // next-best poses executed in this episode
  int frame_ = 0;   // observations emitted in this episode
  double time_s_ = 0;
  bool terminal_ = true;
  bool success_ = false;
  bool ignore_collisions_ = false;  // of the trajectory that led to the current state
  robot::JointVector velocity_ = robot::JointVector::Zero();
};

// The scenes an episode may be drawn from. Demonstrations, exploration and evaluation use
// disjoint sets by construction, whatever the run seeds: a scene seed's residue mod 4 names
// its set. So no run can explore or be evaluated on a demonstrated scene. `any`: seeds
// derived from the run seed alone, in no set (what a single sim-step run needs).
enum class SceneSet { any = 0, demo = 1, explore = 2, eval = 3 };
SceneSet scene_set_from_name(const std::string& name);  // any, demo, explore, eval; throws UsageError
const char* scene_set_name(SceneSet set);
// The scene seed of episode `episode` of a run seeded `run_seed`, in `set`.
uint64_t scene_seed(uint64_t run_seed, SceneSet set, uint64_t episode);
inline SceneSet scene_set_of(uint64_t scene_seed) { return static_cast<SceneSet>(scene_seed % 4); }

// A run's exploration in chunks, for an actor that stays up for the whole run: chunk c holds
// `episodes` episodes drawn as the plan with seed `plan.seed + c` draws them, so a chunk's
// scenes do not depend on which process runs it; an actor runs chunks first, first + stride, ...
struct ChunkPlan {
  int episodes = 10;
  int first = 0;
  int stride = 1;
  int chunk_of(int episode) const { return first + episode / episodes * stride; }
};

// Decides when each chunk starts and hears when it has ended: the learning loop paces an
// actor by its learner through it.
class ChunkGate {
 public:
  virtual ~ChunkGate() = default;
  virtual bool open(int chunk) = 0;  // blocks until `chunk` may start; false: no more chunks
  virtual void finished(int chunk, int steps) = 0;
};

// The gate as files, for shell scripts: chunk c starts once DIR/cccc.go exists (c printed
// with at least four digits), no chunk starts once DIR/stop exists, and when a chunk's last
// episode has ended DIR/cccc.steps holds its environment steps (written atomically).
class DirectoryGate : public ChunkGate {
 public:
  explicit DirectoryGate(std::string directory) : directory_(std::move(directory)) {}
  bool open(int chunk) override;
  void finished(int chunk, int steps) override;
  std::string path(int chunk, const std::string& suffix) const;

 private:
  std::string directory_;
};

// What sim-step runs by itself: episodes of one task, each reset from its own seed.
struct EpisodePlan {
  std::string task;
  int variation = 0;  // -1: drawn per episode from its seed
  int episodes = 1;
  uint64_t seed = 0;
  SceneSet scenes = SceneSet::any;
};

// The reset record of episode `index` of a plan (its scene seed from plan.seed, plan.scenes
// and index).
stream::Record plan_reset(const EpisodePlan& plan, int index);

// The sim-step stage: the simulator (or another EpisodeStage) driven by the records it reads
// and, with a plan, by itself: its first episode starts before any input (in the actor loop the input is made from
// that first observation), the next one after each terminal observation, and the stage is
// done after plan.episodes.
class SimStep : public stream::Stage {
 public:
  SimStep(EpisodeStage& simulator, std::optional<EpisodePlan> plan) : simulator_(simulator), plan_(std::move(plan)) {}
  // In chunks: `gate` opens each chunk and hears of its end (it must outlive the stage).
  SimStep(EpisodeStage& simulator, EpisodePlan plan, ChunkPlan chunks, ChunkGate& gate)
      : simulator_(simulator), plan_(std::move(plan)), chunks_(chunks), gate_(&gate) {}
  void start(const stream::Emit& emit) override;
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  bool done() const override {
    return plan_ && simulator_.episode_over() && (started_ >= plan_->episodes || stopped_);
  }

 private:
  void start_episodes_due(const stream::Emit& emit);
  void count_ended_episode();
  EpisodeStage& simulator_;
  std::optional<EpisodePlan> plan_;
  std::optional<ChunkPlan> chunks_;
  ChunkGate* gate_ = nullptr;
  int started_ = 0;
  int ended_ = 0;        // episodes of the plan that have ended
  int chunk_steps_ = 0;  // environment steps of the current chunk so far
  bool stopped_ = false;  // the gate said no more chunks
};

}  // namespace qte::sim_step
