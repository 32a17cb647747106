#include <gtest/gtest.h>

#include <string>

#include "cli/command.hpp"
#include "common/error.hpp"
#include "learner/learner_options.hpp"
#include "learner/settings.hpp"
#include "voxels/hierarchy_options.hpp"

using namespace qte;

// The learner's settings have one range each, declared with their options: the command line is
// held to it, and so is a configuration that comes from elsewhere (a checkpoint's), by validate().
TEST(LearnerSettings, OneRangePerSettingForTheCommandLineAndForCheckpoints) {
  EXPECT_NO_THROW(learner::LearnerConfig{}.validate());
  const auto refused = [](learner::LearnerConfig config, const std::string& setting) {
    try {
      config.validate();
      ADD_FAILURE() << setting << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(setting + " must be "), std::string::npos) << e.what();
    }
  };
  const std::pair<std::string, void (*)(learner::LearnerConfig&)> out_of_range[] = {
      {"gamma", [](learner::LearnerConfig& c) { c.gamma = 1.5; }},
      {"batch", [](learner::LearnerConfig& c) { c.batch = 0; }},
      {"n-step", [](learner::LearnerConfig& c) { c.n_step = 11; }},
      {"lr", [](learner::LearnerConfig& c) { c.learning_rate = 0; }},
      {"depths", [](learner::LearnerConfig& c) { c.hierarchy.depths = 9; }},
  };
  for (const auto& [setting, spoil] : out_of_range) {
    learner::LearnerConfig c;
    spoil(c);
    refused(c, setting);
  }

  cli::Usage u;
  u.name = "t";
  u.add_options(learner::learner_config_options());
  u.add_options(voxels::hierarchy_options());
  for (const auto& [option, value] : {std::pair<std::string, std::string>{"gamma", "1.5"}, {"batch", "0"},
                                      {"n-step", "11"}, {"lr", "0"}, {"depths", "9"}})
    EXPECT_THROW(learner::learner_config_from(cli::parse(u, {"--" + option, value})), UsageError) << option;
  EXPECT_DOUBLE_EQ(learner::learner_config_from(cli::parse(u, {"--gamma", "0.5"})).gamma, 0.5);
}
