#include "stream/record_types.hpp"

#include <algorithm>

#include "stream/field_names.hpp"

namespace qte::stream {

namespace {

// The fields of each type, one table per type, transcribed from the tables of section 12 of
// formats/record-stream.md (test_record_schema holds them equal): a row that names several
// fields there is one entry per field here; the `frame` fields "as in `obs`" carry obs's dtype
// and shape. Constant data (no constructor runs), so a static of another file may read it.

constexpr FieldSchema reset_fields[] = {
    {fields::task, "str", "[n]", false,
     "task name: `reach_target`, `pick_and_lift`, `lift_numbered_block`, `reach_prism`"},
    {fields::variation, "int32", "[]", true,
     "optional (default 0): task variation index"},
    {fields::seed, "int64", "[]", true,
     "optional (default 0): random seed of the episode's scene"},
    {fields::episode, "int32", "[]", true,
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
    {fields::joint_positions, "float64", "[7]", false,
     "xArm 7 joint angles, radians"},
    {fields::joint_velocities, "float64", "[7]", false,
     "rad/s over the last control step (0 at rest and after a trajectory)"},
    {fields::gripper_pose, "float64", "[7]", false,
     "tool centre point: x, y, z, qx, qy, qz, qw (world frame)"},
    {fields::gripper_open, "uint8", "[]", false,
     "1 = open (the last gripper command)"},
    {fields::gripper_opening_m, "float64", "[]", false,
     "distance between the fingers, 0 to 0.085"},
    {fields::step, "int32", "[]", false,
     "next-best poses executed in this episode, from 0"},
    {fields::episode_length, "int32", "[]", false,
     "the task's next-best poses per episode (10, as published, unless its expert needs more); the networks' time input scales by it (10 when absent)"},
    {fields::frame, "int32", "[]", false,
     "observations written in this episode, from 0 (counts every control step with `--every-step`)"},
    {fields::time_s, "float64", "[]", false,
     "simulated seconds since the reset"},
    {fields::reward, "float32", "[]", false,
     "100 when the task is solved, else 0"},
    {fields::terminal, "uint8", "[]", false,
     "1 when the episode has ended (success, failure, or `episode_length` steps)"},
    {fields::success, "uint8", "[]", false,
     "1 when the task is solved"},
    {fields::ignore_collisions, "uint8", "[]", false,
     "the flag of the trajectory that led here (0 after a reset)"},
    {fields::task, "str", "[n]", false,
     "task name"},
    {fields::description, "str", "[n]", false,
     "the variation in words (\"lift the block numbered 2\")"},
    {fields::variation, "int32", "[]", false,
     "task variation"},
    {fields::episode_seed, "int64", "[]", false,
     "the reset's seed"},
    {fields::failure, "str", "[n]", true,
     "optional: why the last action failed: `invalid_trajectory:...`, `joint_limits:jointK`, `velocity_limit:jointK`, `collision:<link>-table`, `collision:<link>-<link>`, or a planner's reason passed on"},
    {fields::objects_names, "str", "[n]", true,
     "optional (with `--objects`): the N names, joined by commas (`block1,block2,block3`)"},
    {fields::objects_role, "uint8", "[N]", true,
     "optional (with `--objects`): what the task makes of each: 1 = target (an object the variation asks for), 2 = distractor (a lookalike or rival of a target), 0 = other (zones, bins, boards, racks)"},
    {fields::objects_pose, "float64", "[N, 7]", true,
     "optional (with `--objects`): each object's pose: x, y, z, qx, qy, qz, qw (world frame; the origin is the object's own, not always its centre)"},
    {fields::objects_box, "float64", "[N, 6]", true,
     "optional (with `--objects`): each object's bounding box in its own frame: lower corner x, y, z, then upper corner x, y, z, m"},
    {fields::objects_held, "uint8", "[N]", true,
     "optional (with `--objects`): 1 for the object the gripper holds (grasped: it moves with the gripper until the gripper opens), else 0; all 0 after a grasp that closed on nothing. Absent in streams written before it (`qte_stream.scene_objects` gives `held` None)"},
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
    {fields::pose, "float64", "[7]", false,
     "next-best TCP pose in the world frame: x, y, z, qx, qy, qz, qw (unit quaternion, ±1e-3); from `qte-select` the last depth's `centre` turned by `rotation_bins`"},
    {fields::gripper_open, "uint8", "[]", true,
     "optional (default 1): gripper command after the move, 1 = open"},
    {fields::ignore_collisions, "uint8", "[]", true,
     "optional (default 0): 1 = move in a straight line of the TCP, ignoring the scene"},
    {"depth<d>.index", "int32", "[3]", false,
     "the chosen voxel at depth d (x, y, z), 0 ≤ index < V"},
    {"depth<d>.bounds", "float64", "[4]", false,
     "that depth's grid: minimum corner x, y, z and edge length, m (as in `transition`); depth 0 the scene bounds, depth d > 0 centre ± offset around depth d−1's `centre`"},
    {"depth<d>.centre", "float64", "[3]", false,
     "the chosen voxel's centre: `min + (index + 0.5) * edge / V`"},
    {"depth<d>.q_value", "float32", "[]", false,
     "the network's Q-value of that voxel"},
    {"depth<d>.argmax_index", "int32", "[3]", true,
     "optional: at non-leaf depths (d < depths − 1): the best voxel of the same grid by that depth's own Q (at depth 0, depth 0's argmax): where K = 1 would have gone from it; differs from `index` where a finer depth overruled the coarse choice"},
    {fields::rotation_bins, "int32", "[3]", false,
     "Euler 'xyz' angles in 72 bins of 5°: angle = bin · 5° − 180°"},
    {fields::value, "float32", "[]", false,
     "the tree's value of the path taken: the last depth's Q, then (Q at depth d + the value below) / 2 up to depth 0"},
    {fields::k, "int32", "[]", false,
     "voxels expanded per non-leaf grid (1 = C2F-ARM's greedy choice); with `--k auto`, the most per grid (`--k-max`)"},
    {fields::branches, "int32", "[depths − 1]", false,
     "grids the tree expanded at depth 1, 2, …: K, K², … with a fixed K; fewer where `--k auto` found a node sure"},
    {fields::explored, "uint8", "[]", false,
     "1 when exploration (random voxel, index or rotation noise, gripper flip) changed the greedy choice"},
    {fields::checkpoint_step, "int64", "[]", false,
     "training step of the checkpoint whose networks chose the action"},
    {fields::step, "int32", "[]", false,
     "the observation's `step`"},
};

constexpr FieldSchema trajectory_fields[] = {
    {fields::time_s, "float64", "[T]", false,
     "time stamp of each waypoint, seconds; starts at 0 and increases"},
    {fields::joint_positions, "float64", "[T, 7]", false,
     "joint waypoints, radians; the first is the current joint state (within 1e-3 rad)"},
    {fields::gripper_open, "uint8", "[]", true,
     "optional: gripper command applied after the motion"},
    {fields::ignore_collisions, "uint8", "[]", true,
     "optional: the action's flag, copied into the next observations"},
    {fields::method, "str", "[n]", true,
     "optional: how the path was found: `direct`, `rrt_connect`, `straight_line`"},
    {fields::failure, "str", "[n]", true,
     "optional: present (and `time_s`, `joint_positions` absent) when no trajectory was found: `invalid_pose`, `outside_workspace`, `ik_failed`, `start_in_collision`, `goal_in_collision`, `no_path`, `timeout`, `approach_blocked` (plan-path `--approach`: no straight approach to a grasp)"},
};

constexpr FieldSchema episode_fields[] = {
    {fields::task, "str", "[n]", false,
     "task name"},
    {fields::episode, "int32", "[]", false,
     "episode index in the recording"},
    {fields::variation, "int32", "[]", false,
     "the episode's reset"},
    {fields::seed, "int64", "[]", false,
     "the episode's reset"},
    {fields::success, "uint8", "[]", false,
     "1 when the expert solved the task"},
    {fields::frames, "int32", "[]", false,
     "observations of the episode (they precede this record)"},
    {fields::attempts, "int32", "[]", false,
     "1, or more when `--retries` needed new seeds"},
    {fields::failure, "str", "[n]", true,
     "optional: why the expert failed"},
};

constexpr FieldSchema frame_fields[] = {
    {fields::episode_key, "int64", "[]", false,
     "the key transitions refer to it by"},
    {fields::frame, "int32", "[]", false,
     "the key transitions refer to it by"},
    {"<camera>.rgb", "uint8", "[H, W, 3]", false,
     "zstd-compressed"},
    {"<camera>.depth_mm", "uint16", "[H, W]", false,
     "depth in millimetres (0 = none), zstd-compressed"},
    {"<camera>.intrinsics", "float64", "[3, 3]", false,
     "as in `obs`; points are rebuilt from them"},
    {"<camera>.extrinsics", "float64", "[4, 4]", false,
     "as in `obs`; points are rebuilt from them"},
    {fields::joint_positions, "float64", "[7]", false,
     "as in `obs`"},
    {fields::gripper_pose, "float64", "[7]", false,
     "as in `obs`"},
    {fields::gripper_open, "uint8", "[]", false,
     "as in `obs`"},
    {fields::gripper_opening_m, "float64", "[]", false,
     "as in `obs`"},
    {fields::episode_length, "int32", "[]", false,
     "as in `obs`"},
    {fields::task, "str", "[n]", false,
     "as in `obs`"},
    {fields::variation, "int32", "[]", false,
     "as in `obs`"},
};

constexpr FieldSchema transition_fields[] = {
    {fields::episode_key, "int64", "[]", false,
     "the episode (a hash of task, seed and final pose)"},
    {fields::frame, "int32", "[]", false,
     "the observation acted on"},
    {fields::next_frame, "int32", "[]", false,
     "the keyframe reached"},
    {fields::step, "int32", "[]", false,
     "the step of `frame`: its position in its chain (0 for a chain's start), or with `keyframe --chain-steps episode` the keyframes at or before it; for the agent, the observation's `step`"},
    {fields::voxels, "int32", "[]", false,
     "voxels per side of the grids the indices refer to (`qattn-train` refuses others; optional in older files)"},
    {"depth<d>.index", "int32", "[3]", false,
     "the action's voxel at depth d (x, y, z)"},
    {"depth<d>.bounds", "float64", "[4]", false,
     "that depth's grid: minimum corner, edge (crop-augmented for d > 0)"},
    {fields::rotation_bins, "int32", "[3]", false,
     "Euler 'xyz' angles in 72 bins of 5°: bin = round((deg + 180) / 5) mod 72"},
    {fields::gripper_open, "uint8", "[]", false,
     "the action's gripper state"},
    {fields::ignore_collisions, "uint8", "[]", false,
     "the action's flag"},
    {fields::target_pose, "float64", "[7]", false,
     "the next keyframe's TCP pose (x, y, z, qx, qy, qz, qw)"},
    {fields::reward, "float32", "[]", false,
     "100 on the final transition of a successful episode, else 0"},
    {fields::terminal, "uint8", "[]", false,
     "1 on a chain's final transition"},
    {fields::demo, "uint8", "[]", false,
     "1 for demonstrations"},
};

constexpr FieldSchema checkpoint_fields[] = {
    {fields::architecture, "str", "[n]", false,
     "`arm` (the published inception 3D U-Net) or `light` (the CPU default)"},
    {fields::base_channels, "int64", "[]", false,
     "the networks' configuration"},
    {fields::voxels, "int64", "[]", false,
     "the networks' configuration"},
    {fields::channels, "int64", "[]", false,
     "the networks' configuration"},
    {fields::proprio, "int64", "[]", false,
     "the networks' configuration"},
    {fields::depths, "int64", "[]", false,
     "the networks' configuration"},
    {fields::head_input, "str", "[n]", true,
     "optional (default `pooled`): what the last depth's dense head reads: `pooled` (as published) or `voxel` (also the finest level's features at the chosen voxel)"},
    {fields::step, "int64", "[]", false,
     "training step"},
    {fields::config, "str", "[n]", false,
     "the same configuration as JSON, for people (loading reads the fields above)"},
    {"depth<d>.<parameter>", "float32", "its shape", false,
     "one field per parameter and buffer, named as LibTorch's `named_parameters()`; for `arm` the names of the PyTorch reference's modules (`inp.a.0.weight`, …), so Python loads them by name"},
    {fields::learner, "str", "[n]", true,
     "optional: the training settings as JSON, on the online networks' record of `qattn-train`'s checkpoint files (a resumed run must match them)"},
    {fields::role, "str", "[n]", true,
     "optional: `target` on the target networks' record of `qattn-train`'s checkpoint files; absent on the online networks'"},
    {"adam.depth<d>.<parameter>.exp_avg", "float32", "its shape", true,
     "optional: Adam's moments"},
    {"adam.depth<d>.<parameter>.exp_avg_sq", "float32", "its shape", true,
     "optional: Adam's moments"},
    {"adam.depth<d>.<parameter>.max_exp_avg_sq", "float32", "its shape", true,
     "optional: AMSGrad's running maximum, written only when the optimiser keeps one (the learner's Adam does not)"},
    {"adam.depth<d>.<parameter>.step", "int64", "[]", true,
     "optional: Adam's step count for it"},
    {fields::hierarchy_bounds, "float64", "[4]", true,
     "optional: scene bounds: minimum corner x, y, z and edge length, metres"},
    {fields::hierarchy_offsets, "float64", "[D - 1]", true,
     "optional: half edge of each depth below 0, metres"},
    {fields::hierarchy_depths, "int32", "[]", true,
     "optional: D"},
    {fields::hierarchy_voxels, "int32", "[]", true,
     "optional: voxels per side"},
};

constexpr FieldSchema learner_fields[] = {
    {fields::step, "int64", "[]", false,
     "gradient steps taken"},
    {fields::transitions_read, "int64", "[]", false,
     "transition records read from the inputs, in order (a resumed run reads exactly these again)"},
    {fields::agent_transitions, "int64", "[]", false,
     "of those, the agent's own (what `--replay-ratio` counts)"},
    {fields::seed, "int64", "[]", false,
     "the run's `--seed` (a resume with another is refused)"},
    {fields::threads, "int64", "[]", false,
     "the run's `--threads` (floating-point sums depend on it; a resume with another is refused)"},
    {fields::priorities, "float64", "[N]", false,
     "the replay's priorities, by transition index"},
    {fields::max_priority, "float64", "[]", false,
     "the largest priority ever set, which new transitions start with"},
};

template <std::size_t N>
std::vector<FieldSchema> table(const FieldSchema (&fields)[N]) {
  return {fields, fields + N};
}

}  // namespace

const std::vector<RecordType>& record_types() {
  static const std::vector<RecordType> types = {
      {record_type::reset, "episode starts", "the actor loop (sim-step --task writes its own)", table(reset_fields)},
      {record_type::obs, "observations", "sim-step, robot-step, obs-pack or demo-record", table(obs_fields)},
      {record_type::voxels, "voxel grids", "voxelize", table(voxels_fields)},
      {record_type::action, "next-best poses", "qte-select", table(action_fields)},
      {record_type::trajectory, "planned motions", "plan-path", table(trajectory_fields)},
      {record_type::episode, "ends of recorded demonstrations", "demo-record or obs-pack", table(episode_fields)},
      {record_type::frame, "replay frames", "keyframe", table(frame_fields)},
      {record_type::transition, "replay transitions", "keyframe", table(transition_fields)},
      {record_type::checkpoint, "network weights", "qattn-train", table(checkpoint_fields)},
      {record_type::learner, "a training run's state", "qattn-train", table(learner_fields)},
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
