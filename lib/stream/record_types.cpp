#include "stream/record_types.hpp"

#include <algorithm>

namespace qte::stream {

namespace {

// The fields of each type, one table per type, transcribed from the tables of section 12 of
// formats/record-stream.md (test_record_schema holds them equal): a row that names several
// fields there is one entry per field here; the `frame` fields "as in `obs`" carry obs's dtype
// and shape. Constant data (no constructor runs), so a static of another file may read it.

constexpr FieldSchema reset_fields[] = {
    {"task", "str", "[n]", false,
     "task name: `reach_target`, `pick_and_lift`, `lift_numbered_block`, `reach_prism`"},
    {"variation", "int32", "[]", true,
     "optional (default 0): task variation index"},
    {"seed", "int64", "[]", true,
     "optional (default 0): random seed of the episode's scene"},
    {"episode", "int32", "[]", true,
     "optional: episode index, written by `sim-step --task`"},
};

constexpr FieldSchema obs_fields[] = {
    {"<camera>.rgb", "uint8", "[H, W, 3]", false,
     "colour image, rows top to bottom, RGB"},
    {"<camera>.depth", "float32", "[H, W]", false,
     "metres along the optical axis; 0 where no surface was hit"},
    {"<camera>.points", "float32", "[H, W, 3]", false,
     "world-frame point per pixel, metres; NaN where depth is 0 (absent with `--no-points`)"},
    {"<camera>.intrinsics", "float64", "[3, 3]", false,
     "pinhole matrix K: fx = fy = (H/2)/tan(fov_y/2), cx = W/2 − 0.5, cy = H/2 − 0.5"},
    {"<camera>.extrinsics", "float64", "[4, 4]", false,
     "camera-to-world transform; camera frame x right, y down, z forward (OpenCV)"},
    {"joint_positions", "float64", "[7]", false,
     "xArm 7 joint angles, radians"},
    {"joint_velocities", "float64", "[7]", false,
     "rad/s over the last control step (0 at rest and after a trajectory)"},
    {"gripper_pose", "float64", "[7]", false,
     "tool centre point: x, y, z, qx, qy, qz, qw (world frame)"},
    {"gripper_open", "uint8", "[]", false,
     "1 = open (the last gripper command)"},
    {"gripper_opening_m", "float64", "[]", false,
     "distance between the fingers, 0 to 0.085"},
    {"step", "int32", "[]", false,
     "next-best poses executed in this episode, from 0"},
    {"episode_length", "int32", "[]", false,
     "the task's next-best poses per episode (10, as published, unless its expert needs more); the networks' time input scales by it (10 when absent)"},
    {"frame", "int32", "[]", false,
     "observations written in this episode, from 0 (counts every control step with `--every-step`)"},
    {"time_s", "float64", "[]", false,
     "simulated seconds since the reset"},
    {"reward", "float32", "[]", false,
     "100 when the task is solved, else 0"},
    {"terminal", "uint8", "[]", false,
     "1 when the episode has ended (success, failure, or `episode_length` steps)"},
    {"success", "uint8", "[]", false,
     "1 when the task is solved"},
    {"ignore_collisions", "uint8", "[]", false,
     "the flag of the trajectory that led here (0 after a reset)"},
    {"task", "str", "[n]", false,
     "task name"},
    {"description", "str", "[n]", false,
     "the variation in words (\"lift the block numbered 2\")"},
    {"variation", "int32", "[]", false,
     "task variation"},
    {"episode_seed", "int64", "[]", false,
     "the reset's seed"},
    {"failure", "str", "[n]", true,
     "optional: why the last action failed: `invalid_trajectory:...`, `joint_limits:jointK`, `velocity_limit:jointK`, `collision:<link>-table`, `collision:<link>-<link>`, or a planner's reason passed on"},
    {"objects.names", "str", "[n]", false,
     "the N names, joined by commas (`block1,block2,block3`)"},
    {"objects.role", "uint8", "[N]", false,
     "what the task makes of each: 1 = target (an object the variation asks for), 2 = distractor (a lookalike or rival of a target), 0 = other (zones, bins, boards, racks)"},
    {"objects.pose", "float64", "[N, 7]", false,
     "each object's pose: x, y, z, qx, qy, qz, qw (world frame; the origin is the object's own, not always its centre)"},
    {"objects.box", "float64", "[N, 6]", false,
     "each object's bounding box in its own frame: lower corner x, y, z, then upper corner x, y, z, m"},
    {"objects.held", "uint8", "[N]", false,
     "1 for the object the gripper holds (grasped: it moves with the gripper until the gripper opens), else 0; all 0 after a grasp that closed on nothing. Absent in streams written before it (`qte_stream.scene_objects` gives `held` None)"},
};

constexpr FieldSchema voxels_fields[] = {
    {"depth0.grid", "float32", "[V, V, V, C]", false,
     "the scene bounds"},
    {"depth0.bounds", "float64", "[4]", false,
     "minimum corner x, y, z and edge length, m"},
    {"depth1.grid", "float32", "[K, V, V, V, C]", true,
     "optional: K crops of centre ± offset (`voxelize --centre`)"},
    {"depth1.bounds", "float64", "[K, 4]", true,
     "optional (with `depth1.grid`): their minimum corners and edge lengths"},
};

constexpr FieldSchema action_fields[] = {
    {"pose", "float64", "[7]", false,
     "next-best TCP pose in the world frame: x, y, z, qx, qy, qz, qw (unit quaternion, ±1e-3); from `qte-select` the last depth's `centre` turned by `rotation_bins`"},
    {"gripper_open", "uint8", "[]", true,
     "optional (default 1): gripper command after the move, 1 = open"},
    {"ignore_collisions", "uint8", "[]", true,
     "optional (default 0): 1 = move in a straight line of the TCP, ignoring the scene"},
    {"depth<d>.index", "int32", "[3]", false,
     "the chosen voxel at depth d (x, y, z), 0 ≤ index < V"},
    {"depth<d>.bounds", "float64", "[4]", false,
     "that depth's grid: minimum corner x, y, z and edge length, m (as in `transition`); depth 0 the scene bounds, depth d > 0 centre ± offset around depth d−1's `centre`"},
    {"depth<d>.centre", "float64", "[3]", false,
     "the chosen voxel's centre: `min + (index + 0.5) * edge / V`"},
    {"depth<d>.q_value", "float32", "[]", false,
     "the network's Q-value of that voxel"},
    {"depth<d>.argmax_index", "int32", "[3]", false,
     "at non-leaf depths (d < depths − 1): the best voxel of the same grid by that depth's own Q (at depth 0, depth 0's argmax): where K = 1 would have gone from it; differs from `index` where a finer depth overruled the coarse choice"},
    {"rotation_bins", "int32", "[3]", false,
     "Euler 'xyz' angles in 72 bins of 5°: angle = bin · 5° − 180°"},
    {"value", "float32", "[]", false,
     "the tree's value of the path taken: the last depth's Q, then (Q at depth d + the value below) / 2 up to depth 0"},
    {"k", "int32", "[]", false,
     "voxels expanded per non-leaf grid (1 = C2F-ARM's greedy choice); with `--k auto`, the most per grid (`--k-max`)"},
    {"branches", "int32", "[depths − 1]", false,
     "grids the tree expanded at depth 1, 2, …: K, K², … with a fixed K; fewer where `--k auto` found a node sure"},
    {"explored", "uint8", "[]", false,
     "1 when exploration (random voxel, index or rotation noise, gripper flip) changed the greedy choice"},
    {"checkpoint_step", "int64", "[]", false,
     "training step of the checkpoint whose networks chose the action"},
    {"step", "int32", "[]", false,
     "the observation's `step`"},
};

constexpr FieldSchema trajectory_fields[] = {
    {"time_s", "float64", "[T]", false,
     "time stamp of each waypoint, seconds; starts at 0 and increases"},
    {"joint_positions", "float64", "[T, 7]", false,
     "joint waypoints, radians; the first is the current joint state (within 1e-3 rad)"},
    {"gripper_open", "uint8", "[]", true,
     "optional: gripper command applied after the motion"},
    {"ignore_collisions", "uint8", "[]", true,
     "optional: the action's flag, copied into the next observations"},
    {"method", "str", "[n]", true,
     "optional: how the path was found: `direct`, `rrt_connect`, `straight_line`"},
    {"failure", "str", "[n]", true,
     "optional: present (and `time_s`, `joint_positions` absent) when no trajectory was found: `invalid_pose`, `outside_workspace`, `ik_failed`, `start_in_collision`, `goal_in_collision`, `no_path`, `timeout`, `approach_blocked` (plan-path `--approach`: no straight approach to a grasp)"},
};

constexpr FieldSchema episode_fields[] = {
    {"task", "str", "[n]", false,
     "task name"},
    {"episode", "int32", "[]", false,
     "episode index in the recording"},
    {"variation", "int32", "[]", false,
     "the episode's reset"},
    {"seed", "int64", "[]", false,
     "the episode's reset"},
    {"success", "uint8", "[]", false,
     "1 when the expert solved the task"},
    {"frames", "int32", "[]", false,
     "observations of the episode (they precede this record)"},
    {"attempts", "int32", "[]", false,
     "1, or more when `--retries` needed new seeds"},
    {"failure", "str", "[n]", true,
     "optional: why the expert failed"},
};

constexpr FieldSchema frame_fields[] = {
    {"episode_key", "int64", "[]", false,
     "the key transitions refer to it by"},
    {"frame", "int32", "[]", false,
     "the key transitions refer to it by"},
    {"<camera>.rgb", "uint8", "[H, W, 3]", false,
     "zstd-compressed"},
    {"<camera>.depth_mm", "uint16", "[H, W]", false,
     "depth in millimetres (0 = none), zstd-compressed"},
    {"<camera>.intrinsics", "float64", "[3, 3]", false,
     "as in `obs`; points are rebuilt from them"},
    {"<camera>.extrinsics", "float64", "[4, 4]", false,
     "as in `obs`; points are rebuilt from them"},
    {"joint_positions", "float64", "[7]", false,
     "as in `obs`"},
    {"gripper_pose", "float64", "[7]", false,
     "as in `obs`"},
    {"gripper_open", "uint8", "[]", false,
     "as in `obs`"},
    {"gripper_opening_m", "float64", "[]", false,
     "as in `obs`"},
    {"episode_length", "int32", "[]", false,
     "as in `obs`"},
    {"task", "str", "[n]", false,
     "as in `obs`"},
    {"variation", "int32", "[]", false,
     "as in `obs`"},
};

constexpr FieldSchema transition_fields[] = {
    {"episode_key", "int64", "[]", false,
     "the episode (a hash of task, seed and final pose)"},
    {"frame", "int32", "[]", false,
     "the observation acted on"},
    {"next_frame", "int32", "[]", false,
     "the keyframe reached"},
    {"step", "int32", "[]", false,
     "position of `frame` in its chain (0 for a chain's start); for the agent, the observation's `step`"},
    {"voxels", "int32", "[]", false,
     "voxels per side of the grids the indices refer to (`qattn-train` refuses others; optional in older files)"},
    {"depth<d>.index", "int32", "[3]", false,
     "the action's voxel at depth d (x, y, z)"},
    {"depth<d>.bounds", "float64", "[4]", false,
     "that depth's grid: minimum corner, edge (crop-augmented for d > 0)"},
    {"rotation_bins", "int32", "[3]", false,
     "Euler 'xyz' angles in 72 bins of 5°: bin = round((deg + 180) / 5) mod 72"},
    {"gripper_open", "uint8", "[]", false,
     "the action's gripper state"},
    {"ignore_collisions", "uint8", "[]", false,
     "the action's flag"},
    {"target_pose", "float64", "[7]", false,
     "the next keyframe's TCP pose (x, y, z, qx, qy, qz, qw)"},
    {"reward", "float32", "[]", false,
     "100 on the final transition of a successful episode, else 0"},
    {"terminal", "uint8", "[]", false,
     "1 on a chain's final transition"},
    {"demo", "uint8", "[]", false,
     "1 for demonstrations"},
};

constexpr FieldSchema checkpoint_fields[] = {
    {"architecture", "str", "[n]", false,
     "`arm` (the published inception 3D U-Net) or `light` (the CPU default)"},
    {"base_channels", "int64", "[]", false,
     "the networks' configuration"},
    {"voxels", "int64", "[]", false,
     "the networks' configuration"},
    {"channels", "int64", "[]", false,
     "the networks' configuration"},
    {"proprio", "int64", "[]", false,
     "the networks' configuration"},
    {"depths", "int64", "[]", false,
     "the networks' configuration"},
    {"step", "int64", "[]", false,
     "training step"},
    {"config", "str", "[n]", false,
     "the same configuration as JSON, for people (loading reads the fields above)"},
    {"depth<d>.<parameter>", "float32", "its shape", false,
     "one field per parameter and buffer, named as LibTorch's `named_parameters()`; for `arm` the names of the PyTorch reference's modules (`inp.a.0.weight`, …), so Python loads them by name"},
    {"adam.depth<d>.<parameter>.exp_avg", "float32", "its shape", true,
     "optional: Adam's moments"},
    {"adam.depth<d>.<parameter>.exp_avg_sq", "float32", "its shape", true,
     "optional: Adam's moments"},
    {"adam.depth<d>.<parameter>.step", "int64", "[]", true,
     "optional: Adam's step count for it"},
    {"hierarchy.bounds", "float64", "[4]", false,
     "scene bounds: minimum corner x, y, z and edge length, metres"},
    {"hierarchy.offsets", "float64", "[D - 1]", false,
     "half edge of each depth below 0, metres"},
    {"hierarchy.depths", "int32", "[]", false,
     "D"},
    {"hierarchy.voxels", "int32", "[]", false,
     "voxels per side"},
};

constexpr FieldSchema learner_fields[] = {
    {"step", "int64", "[]", false,
     "gradient steps taken"},
    {"transitions_read", "int64", "[]", false,
     "transition records read from the inputs, in order (a resumed run reads exactly these again)"},
    {"agent_transitions", "int64", "[]", false,
     "of those, the agent's own (what `--replay-ratio` counts)"},
    {"seed", "int64", "[]", false,
     "the run's `--seed` (a resume with another is refused)"},
    {"threads", "int64", "[]", false,
     "the run's `--threads` (floating-point sums depend on it; a resume with another is refused)"},
    {"priorities", "float64", "[N]", false,
     "the replay's priorities, by transition index"},
    {"max_priority", "float64", "[]", false,
     "the largest priority ever set, which new transitions start with"},
};

constexpr FieldSchema metrics_fields[] = {
    {"step", "int64", "[]", false,
     "training step or episode index the figures belong to"},
    {"<name>", "float64", "[]", false,
     "one scalar per figure, e.g. `loss`, `success_rate`, `episode_return`, `wall_time_s`"},
};

template <std::size_t N>
std::vector<FieldSchema> table(const FieldSchema (&fields)[N]) {
  return {fields, fields + N};
}

}  // namespace

const std::vector<RecordType>& record_types() {
  static const std::vector<RecordType> types = {
      {"reset", "episode starts", "the actor loop (sim-step --task writes its own)", table(reset_fields)},
      {"obs", "observations", "sim-step, robot-step, obs-pack or demo-record", table(obs_fields)},
      {"voxels", "voxel grids", "voxelize", table(voxels_fields)},
      {"action", "next-best poses", "qte-select", table(action_fields)},
      {"trajectory", "planned motions", "plan-path", table(trajectory_fields)},
      {"episode", "ends of recorded demonstrations", "demo-record or obs-pack", table(episode_fields)},
      {"frame", "replay frames", "keyframe", table(frame_fields)},
      {"transition", "replay transitions", "keyframe", table(transition_fields)},
      {"checkpoint", "network weights", "qattn-train", table(checkpoint_fields)},
      {"learner", "a training run's state", "qattn-train", table(learner_fields)},
      {"metrics", "figures of a run", "qattn-train", table(metrics_fields)},
  };
  return types;
}

const RecordType* find_record_type(const std::string& name) {
  for (const RecordType& t : record_types())
    if (name == t.name) return &t;
  return nullptr;
}

std::string record_type_names() {
  std::string names;
  for (const RecordType& t : record_types()) names += (names.empty() ? "" : ", ") + std::string(t.name);
  return names;
}

std::string schema_text(const RecordType& type) {
  std::string text = std::string(type.name) + "\t" + type.what + "\twritten by " + type.written_by + "\n";
  for (const FieldSchema& f : type.fields)
    text += std::string("\t") + f.name + "\t" + f.dtype + "\t" + f.shape + "\t" +
            (f.optional ? "optional" : "required") + "\t" + f.meaning + "\n";
  return text;
}

std::string describe_counts(const std::map<std::string, int64_t>& counts) {
  std::vector<std::pair<std::string, int64_t>> sorted(counts.begin(), counts.end());
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string text;
  for (const auto& [name, n] : sorted) text += (text.empty() ? "" : ", ") + std::to_string(n) + " '" + name + "'";
  return text;
}

}  // namespace qte::stream
