#include "qattention/action_record.hpp"

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "robot/pose_values.hpp"
#include "robot/rotation_bins.hpp"
#include "stream/field_names.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::qattention {

stream::Record action_record(const Choice& choice, bool ignore_collisions, int k, bool explored,
                             int64_t checkpoint_step, int32_t step) {
  const Choice& c = choice;
  stream::Record a(record_type::action);
  const Eigen::Vector3d p = c.position();
  Eigen::Quaterniond q(robot::rotation_from_bins(c.rotation_bins));
  q.normalize();
  a.set<double>(fields::pose, {robot::kPoseValues}, robot::pose_values(p, q));
  a.set_scalar<uint8_t>(fields::gripper_open, c.gripper_open ? 1 : 0);
  a.set_scalar<uint8_t>(fields::ignore_collisions, ignore_collisions ? 1 : 0);
  for (std::size_t d = 0; d < c.indices.size(); ++d) {
    a.set<int32_t>(fields::depth_field(d, fields::per_depth::index), {3}, c.indices[d].data());
    a.set<double>(fields::depth_field(d, fields::per_depth::bounds), {4}, voxels::bounds_values(c.bounds[d]));
    const Eigen::Vector3d centre = c.bounds[d].centre_of(c.indices[d]);
    a.set<double>(fields::depth_field(d, fields::per_depth::centre), {3}, centre.data());
    a.set_scalar<float>(fields::depth_field(d, fields::per_depth::q_value), c.q_values[d]);
    if (d < c.argmax_indices.size())
      a.set<int32_t>(fields::depth_field(d, fields::per_depth::argmax_index), {3}, c.argmax_indices[d].data());
  }
  a.set<int32_t>(fields::rotation_bins, {3}, c.rotation_bins.data());
  a.set_scalar<float>(fields::value, c.value);
  a.set_scalar<int32_t>(fields::k, k);
  if (!c.branches.empty()) a.set<int32_t>(fields::branches, {static_cast<int64_t>(c.branches.size())}, c.branches);
  a.set_scalar<uint8_t>(fields::explored, explored ? 1 : 0);
  a.set_scalar<int64_t>(fields::checkpoint_step, checkpoint_step);
  a.set_scalar<int32_t>(fields::step, step);
  return a;
}

}  // namespace qte::qattention
