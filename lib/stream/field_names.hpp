// The names of the record fields and record types (formats/record-stream.md, section 12), one
// constant each, so that every writer and reader spells a name once: record_types.cpp lists the registry's fields
// by these constants, tests/unit/stream/test_field_names.cpp holds the lists equal, and
// tests/tools/test_field_names.py finds no field named by a string literal in lib/ or tools/.
// Written `fields::gripper_open` anywhere in qte (the alias at the end).
#pragma once

#include <string>

namespace qte::stream::fields {

// X(constant, "name"): every field name that is the same in every record holding it.
#define QTE_FIELD_NAMES(X)                  \
  X(task, "task")                           \
  X(variation, "variation")                 \
  X(seed, "seed")                           \
  X(episode, "episode")                     \
  X(joint_positions, "joint_positions")     \
  X(joint_velocities, "joint_velocities")   \
  X(gripper_pose, "gripper_pose")           \
  X(gripper_open, "gripper_open")           \
  X(gripper_opening_m, "gripper_opening_m") \
  X(step, "step")                           \
  X(episode_length, "episode_length")       \
  X(frame, "frame")                         \
  X(time_s, "time_s")                       \
  X(reward, "reward")                       \
  X(terminal, "terminal")                   \
  X(success, "success")                     \
  X(ignore_collisions, "ignore_collisions") \
  X(description, "description")             \
  X(episode_seed, "episode_seed")           \
  X(failure, "failure")                     \
  X(objects_names, "objects.names")         \
  X(objects_role, "objects.role")           \
  X(objects_pose, "objects.pose")           \
  X(objects_box, "objects.box")             \
  X(objects_held, "objects.held")           \
  X(hierarchy_bounds, "hierarchy.bounds")   \
  X(hierarchy_offsets, "hierarchy.offsets") \
  X(hierarchy_depths, "hierarchy.depths")   \
  X(hierarchy_voxels, "hierarchy.voxels")   \
  X(pose, "pose")                           \
  X(rotation_bins, "rotation_bins")         \
  X(value, "value")                         \
  X(k, "k")                                 \
  X(branches, "branches")                   \
  X(explored, "explored")                   \
  X(checkpoint_step, "checkpoint_step")     \
  X(method, "method")                       \
  X(frames, "frames")                       \
  X(attempts, "attempts")                   \
  X(episode_key, "episode_key")             \
  X(next_frame, "next_frame")               \
  X(voxels, "voxels")                       \
  X(target_pose, "target_pose")             \
  X(demo, "demo")                           \
  X(architecture, "architecture")           \
  X(base_channels, "base_channels")         \
  X(head_input, "head_input")               \
  X(channels, "channels")                   \
  X(proprio, "proprio")                     \
  X(depths, "depths")                       \
  X(config, "config")                       \
  X(learner, "learner")                     \
  X(role, "role")                           \
  X(transitions_read, "transitions_read")   \
  X(agent_transitions, "agent_transitions") \
  X(threads, "threads")                     \
  X(priorities, "priorities")               \
  X(max_priority, "max_priority")

// Per camera, "<camera><suffix>": camera + per_camera::rgb is "front.rgb", and
// record.prefixes(per_camera::rgb) lists the cameras.
#define QTE_CAMERA_FIELD_SUFFIXES(X) \
  X(rgb, ".rgb")                     \
  X(depth, ".depth")                 \
  X(depth_mm, ".depth_mm")           \
  X(points, ".points")               \
  X(intrinsics, ".intrinsics")       \
  X(extrinsics, ".extrinsics")

// Per depth of the hierarchy, "depth<d><suffix>": depth_field(0, per_depth::index) is
// "depth0.index".
#define QTE_DEPTH_FIELD_SUFFIXES(X) \
  X(index, ".index")                \
  X(bounds, ".bounds")              \
  X(centre, ".centre")              \
  X(q_value, ".q_value")            \
  X(argmax_index, ".argmax_index")  \
  X(grid, ".grid")

// X(constant, "name"): every record type of the registry.
#define QTE_RECORD_TYPES(X)     \
  X(reset, "reset")             \
  X(obs, "obs")                 \
  X(voxels, "voxels")           \
  X(action, "action")           \
  X(trajectory, "trajectory")   \
  X(episode, "episode")         \
  X(frame, "frame")             \
  X(transition, "transition")   \
  X(checkpoint, "checkpoint")   \
  X(learner, "learner")

#define QTE_FIELD_CONSTANT(constant, name) inline constexpr char constant[] = name;
QTE_FIELD_NAMES(QTE_FIELD_CONSTANT)
namespace per_camera {
QTE_CAMERA_FIELD_SUFFIXES(QTE_FIELD_CONSTANT)
}
namespace per_depth {
QTE_DEPTH_FIELD_SUFFIXES(QTE_FIELD_CONSTANT)
}

inline std::string depth_field(int depth, const char* suffix) { return "depth" + std::to_string(depth) + suffix; }
// "depth<d>." : the prefix of a depth's fields, network parameters included
// ("depth0.conv1.weight"); the optimiser's state is under "adam." + depth_prefix(d).
inline std::string depth_prefix(int depth) { return depth_field(depth, "."); }
// Whether `name` is a depth's field or network parameter: "depth<digits>.…".
inline bool is_per_depth(const std::string& name) {
  const std::size_t after = name.find_first_not_of("0123456789", 5);
  return name.rfind("depth", 0) == 0 && after != std::string::npos && after > 5 && name[after] == '.';
}
inline constexpr char adam_prefix[] = "adam.";
// Adam's state per parameter: "<adam.depth<d>.<parameter>><suffix>".
namespace per_parameter {
inline constexpr char exp_avg[] = ".exp_avg";
inline constexpr char exp_avg_sq[] = ".exp_avg_sq";
inline constexpr char max_exp_avg_sq[] = ".max_exp_avg_sq";
inline constexpr char step[] = ".step";
}  // namespace per_parameter

}  // namespace qte::stream::fields

// The record types' names: record.type() == record_type::obs, stream::Record r(record_type::transition).
namespace qte::stream::record_type {
QTE_RECORD_TYPES(QTE_FIELD_CONSTANT)
}  // namespace qte::stream::record_type
#undef QTE_FIELD_CONSTANT

namespace qte {
namespace fields = stream::fields;
namespace record_type = stream::record_type;
}
