#include "qattention/action_record.hpp"

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "robot/pose_values.hpp"
#include "robot/rotation_bins.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::qattention {

stream::Record action_record(const Choice& choice, bool ignore_collisions, int k, bool explored,
                             int64_t checkpoint_step, int32_t step) {
  const Choice& c = choice;
  stream::Record a("action");
  const Eigen::Vector3d p = c.position();
  Eigen::Quaterniond q(robot::rotation_from_bins(c.rotation_bins));
  q.normalize();
  a.set<double>("pose", {robot::kPoseValues}, robot::pose_values(p, q));
  a.set_scalar<uint8_t>("gripper_open", c.gripper_open ? 1 : 0);
  a.set_scalar<uint8_t>("ignore_collisions", ignore_collisions ? 1 : 0);
  for (std::size_t d = 0; d < c.indices.size(); ++d) {
    const std::string prefix = "depth" + std::to_string(d);
    a.set<int32_t>(prefix + ".index", {3}, c.indices[d].data());
    a.set<double>(prefix + ".bounds", {4}, voxels::bounds_values(c.bounds[d]));
    const Eigen::Vector3d centre = c.bounds[d].centre_of(c.indices[d]);
    a.set<double>(prefix + ".centre", {3}, centre.data());
    a.set_scalar<float>(prefix + ".q_value", c.q_values[d]);
    if (d < c.argmax_indices.size()) a.set<int32_t>(prefix + ".argmax_index", {3}, c.argmax_indices[d].data());
  }
  a.set<int32_t>("rotation_bins", {3}, c.rotation_bins.data());
  a.set_scalar<float>("value", c.value);
  a.set_scalar<int32_t>("k", k);
  if (!c.branches.empty()) a.set<int32_t>("branches", {static_cast<int64_t>(c.branches.size())}, c.branches);
  a.set_scalar<uint8_t>("explored", explored ? 1 : 0);
  a.set_scalar<int64_t>("checkpoint_step", checkpoint_step);
  a.set_scalar<int32_t>("step", step);
  return a;
}

}  // namespace qte::qattention
