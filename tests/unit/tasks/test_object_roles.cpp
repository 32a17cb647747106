// Every task says which of its objects the variation asks for (targets), which look like them
// or compete with them (distractors) and which are neither: what the observations' objects.role
// carries for analyses of where an agent went.
#include <gtest/gtest.h>

#include <map>

#include "task_scene.hpp"

using namespace qte;
using Role = world::ObjectSpec::Role;

namespace {

// Role -> the names of the scene's objects with it, in id order.
std::map<Role, std::vector<std::string>> roles(const std::string& task, uint64_t seed, int variation) {
  test_support::TaskScene scene(task, seed, variation);
  std::map<Role, std::vector<std::string>> out;
  for (int id = 0; id < scene.world.object_count(); ++id)
    out[scene.world.object_spec(id).role].push_back(scene.world.object_spec(id).name);
  return out;
}

using Names = std::vector<std::string>;

}  // namespace

TEST(ObjectRoles, EveryTaskHasATargetInEveryVariation) {
  for (const std::string& name : tasks::task_names()) {
    const int variations = tasks::make_task(name)->variation_count();
    for (int variation = 0; variation < variations; variation += std::max(1, variations / 4))
      EXPECT_FALSE(roles(name, 5, variation)[Role::target].empty()) << name << " variation " << variation;
  }
}

TEST(ObjectRoles, TheVariationNamesTheTargetAmongItsLookalikes) {
  auto r = roles("lift_numbered_block", 3, 1);
  EXPECT_EQ(r[Role::target], Names{"block2"});
  EXPECT_EQ(r[Role::distractor], (Names{"block1", "block3"}));
  EXPECT_TRUE(r[Role::other].empty());

  r = roles("pick_and_lift_small", 3, 3);
  EXPECT_EQ(r[Role::target], Names{"star"});
  EXPECT_EQ(r[Role::distractor], (Names{"cube", "cylinder", "triangular_prism", "moon"}));
  EXPECT_EQ(r[Role::other], Names{"success_zone"});

  r = roles("reach_prism", 3, 0);
  EXPECT_EQ(r[Role::target], Names{"prism"});
  EXPECT_EQ(r[Role::distractor], (Names{"triangular_prism", "cube"}));

  r = roles("reach_target", 3, 4);
  EXPECT_EQ(r[Role::target], Names{"target"});
  EXPECT_EQ(r[Role::distractor], (Names{"distractor1", "distractor2"}));

  r = roles("stack_blocks", 3, 7);
  EXPECT_EQ(r[Role::target].size(), 4u);
  EXPECT_EQ(r[Role::distractor].size(), 4u);
  EXPECT_EQ(r[Role::other], Names{"target_plane"});

  r = roles("put_rubbish_in_bin", 3, 0);
  EXPECT_EQ(r[Role::target], Names{"rubbish"});
  EXPECT_EQ(r[Role::distractor], (Names{"tomato1", "tomato2"}));
  EXPECT_EQ(r[Role::other], Names{"bin"});
}

TEST(ObjectRoles, TheCheckersToMoveAreTargetsTheOthersLookalikes) {
  for (int variation = 0; variation < 3; ++variation) {
    auto r = roles("setup_checkers", 11, variation);
    EXPECT_EQ(r[Role::target].size(), static_cast<std::size_t>(variation + 1));
    EXPECT_EQ(r[Role::distractor].size(), 24u - (variation + 1));
    EXPECT_EQ(r[Role::other], Names{"board"});
  }
}
