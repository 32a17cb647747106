// Every task builds its scene from any seed: its layouts are drawn by rejection sampling, and a
// layout that leaves no room for an object must be drawn again, never stop a run (a
// pick_and_lift_small layout in about 800 once stopped a learning run's actor). A thousand
// scene seeds of each task, from each scene set, as sim-step derives them.
#include <gtest/gtest.h>

#include "sim_step/simulator.hpp"
#include "task_scene.hpp"

using namespace qte;

TEST(EverySceneBuilds, AThousandSeedsOfEveryTask) {
  for (const std::string& name : tasks::task_names()) {
    const int variations = tasks::make_task(name)->variation_count();
    int built = 0;
    for (uint64_t episode = 0; episode < 250; ++episode)
      for (auto set : {sim_step::SceneSet::demo, sim_step::SceneSet::explore, sim_step::SceneSet::eval, sim_step::SceneSet::any}) {
        const uint64_t seed = sim_step::scene_seed(0, set, episode);
        try {
          test_support::TaskScene scene(name, seed, static_cast<int>(seed % variations));
          ++built;
        } catch (const Error& e) {
          ADD_FAILURE() << name << " scene seed " << seed << ": " << e.what();
        }
      }
    EXPECT_EQ(built, 1000) << name;
  }
}
