#include <gtest/gtest.h>

#include <set>
#include <string>

#include "observation/observation.hpp"
#include "stream/dtype.hpp"
#include "stream/record_types.hpp"

using namespace qte;

namespace {

// The schema's field for a written name: "front.rgb" is "<camera>.rgb".
const stream::FieldSchema* schema_of(const std::string& name) {
  const stream::RecordType* obs = stream::find_record_type("obs");
  const std::size_t dot = name.find('.');
  const std::string generic = dot == std::string::npos ? name : "<camera>" + name.substr(dot);
  for (const auto& f : obs->fields)
    if (f.name == name || f.name == generic) return &f;
  return nullptr;
}

}  // namespace

// The one obs builder writes what the record stream's schema (lib/stream/record_types, held
// equal to formats/record-stream.md by a test) says: every field it writes is there with the
// schema's dtype and shape, every required non-camera, non-object field is written, and the
// optional ones (failure; the arm's joints without a joint log) only when there is a value.
TEST(Observation, FieldsAreTheSchemasObsFields) {
  stream::Record obs("obs");
  observation::set_camera_pose(obs, "front", Eigen::Matrix3d::Identity(), Eigen::Isometry3d::Identity());
  observation::ArmState arm;
  arm.joints = robot::JointVector::Constant(0.1);
  arm.tool_in_world.translation() = Eigen::Vector3d(0.2, 0.1, 0.9);
  arm.gripper_opening_m = 0.04;
  observation::set_arm_state(obs, arm);
  observation::EpisodeState episode;
  episode.step = 3;
  episode.task = "reach_target";
  episode.failure = "joint_limits:joint2";
  observation::set_episode_state(obs, episode);

  std::set<std::string> written;
  for (const auto& f : obs.fields()) {
    written.insert(f.name());
    const stream::FieldSchema* schema = schema_of(f.name());
    ASSERT_NE(schema, nullptr) << f.name() << " is not an obs field";
    EXPECT_EQ(std::string(stream::dtype_name(f.dtype())), schema->dtype) << f.name();
    if (f.dtype() != stream::DType::str) EXPECT_EQ(stream::shape_to_string(f.shape()), schema->shape) << f.name();
  }
  for (const auto& f : stream::find_record_type("obs")->fields) {
    const std::string name = f.name;
    if (f.optional || name.rfind("<camera>", 0) == 0 || name.rfind("objects.", 0) == 0) continue;
    EXPECT_TRUE(written.count(name)) << name << " (required) not written";
  }
  EXPECT_EQ(obs.scalar<int32_t>("step"), 3);
  EXPECT_EQ(obs.string("failure"), "joint_limits:joint2");
  EXPECT_DOUBLE_EQ(obs.array<double>("gripper_pose")[0], 0.2);

  // No failure, no joints: neither written.
  stream::Record bare("obs");
  observation::set_arm_state(bare, observation::ArmState{});
  observation::set_episode_state(bare, observation::EpisodeState{});
  EXPECT_FALSE(bare.has("failure"));
  EXPECT_FALSE(bare.has("joint_positions"));
  EXPECT_FALSE(bare.has("gripper_pose"));
  EXPECT_TRUE(bare.has("gripper_open"));
}
