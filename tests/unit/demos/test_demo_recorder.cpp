// Expert demonstrations: real reach_target episodes at 32x32, each episode's observations in
// order and then its 'episode' record; an expert that cannot act fails and is retried on new seeds.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "demos/demo_recorder.hpp"
#include "test_support.hpp"

using namespace qte;

namespace {

demos::DemoOptions small_demos(int episodes) {
  demos::DemoOptions options;
  options.episodes.task = "reach_target";
  options.episodes.episodes = episodes;
  options.episodes.seed = 1;
  options.episodes.scenes = sim_step::SceneSet::demo;
  options.simulator.cameras[0].intrinsics.width = options.simulator.cameras[0].intrinsics.height = 32;
  options.simulator.render_threads = 1;
  return options;
}

struct Recording {
  std::vector<stream::Record> records;
  std::vector<std::string> progress;
  demos::DemoSummary summary;
};

Recording record(const demos::DemoOptions& options) {
  Recording out;
  out.summary = demos::record_demos(
      test_support::xarm(), options, [&](const stream::Record& r) { out.records.push_back(r); },
      [&](const std::string& line) { out.progress.push_back(line); });
  return out;
}

// The records between episode boundaries: each episode's observations, then its 'episode' record.
struct Episode {
  std::vector<const stream::Record*> observations;
  const stream::Record* summary = nullptr;
};

std::vector<Episode> split_episodes(const std::vector<stream::Record>& records) {
  std::vector<Episode> episodes(1);
  for (const auto& r : records) {
    if (r.type() == "episode") {
      episodes.back().summary = &r;
      episodes.emplace_back();
    } else {
      episodes.back().observations.push_back(&r);
    }
  }
  EXPECT_TRUE(episodes.back().observations.empty()) << "observations after the last episode record";
  episodes.pop_back();
  return episodes;
}

}  // namespace

TEST(DemoRecorder, EachEpisodesObservationsInOrderThenItsEpisodeRecord) {
  const demos::DemoOptions options = small_demos(2);
  const Recording run = record(options);
  const std::vector<Episode> episodes = split_episodes(run.records);
  ASSERT_EQ(episodes.size(), 2u);
  for (int e = 0; e < 2; ++e) {
    SCOPED_TRACE("episode " + std::to_string(e));
    const Episode& episode = episodes[e];
    const stream::Record& summary = *episode.summary;
    ASSERT_GE(episode.observations.size(), 2u);  // the reset's observation and at least one move
    // Every control step is observed (observe_every_step is forced on), frames counted from 0,
    // and only the last observation ends the episode: the expert solved it.
    for (std::size_t i = 0; i < episode.observations.size(); ++i) {
      const stream::Record& obs = *episode.observations[i];
      EXPECT_EQ(obs.type(), "obs");
      EXPECT_EQ(obs.scalar<int32_t>("frame"), static_cast<int32_t>(i));
      EXPECT_EQ(obs.scalar<int64_t>("episode_seed"), summary.scalar<int64_t>("seed"));
      EXPECT_EQ(obs.scalar<uint8_t>("terminal"), i + 1 == episode.observations.size());
      EXPECT_EQ(obs.array<uint8_t>("front.rgb").shape, (stream::Shape{32, 32, 3}));
    }
    EXPECT_EQ(episode.observations.front()->scalar<int32_t>("step"), 0);
    EXPECT_GT(episode.observations.back()->scalar<int32_t>("step"), 0);
    EXPECT_EQ(episode.observations.back()->scalar<uint8_t>("success"), 1);
    EXPECT_FALSE(episode.observations.back()->has("failure"));
    // The episode record says what its observations show, and where its scene came from.
    EXPECT_EQ(summary.string("task"), "reach_target");
    EXPECT_EQ(summary.scalar<int32_t>("episode"), e);
    EXPECT_EQ(summary.scalar<int32_t>("variation"), 0);
    EXPECT_EQ(summary.scalar<int64_t>("seed"), sim_step::plan_reset(options.episodes, e).scalar<int64_t>("seed"));
    EXPECT_EQ(summary.scalar<uint8_t>("success"), 1);
    EXPECT_EQ(summary.scalar<int32_t>("frames"), static_cast<int32_t>(episode.observations.size()));
    EXPECT_EQ(summary.scalar<int32_t>("attempts"), 1);
    EXPECT_FALSE(summary.has("failure"));
  }
  EXPECT_NE(episodes[0].summary->scalar<int64_t>("seed"), episodes[1].summary->scalar<int64_t>("seed"));
  EXPECT_EQ(run.summary.episodes, 2);
  EXPECT_EQ(run.summary.successes, 2);
  EXPECT_EQ(run.summary.retried, 0);
  ASSERT_EQ(run.progress.size(), 2u);
  EXPECT_EQ(run.progress[0].rfind("episode 1/2 reach_target: success, ", 0), 0u) << run.progress[0];
}

TEST(DemoRecorder, AnExpertThatFailsIsRetriedOnNewSeedsAndItsFailureRecorded) {
  // No trajectory may last more than 10 ms: the expert's first move fails the action.
  demos::DemoOptions options = small_demos(1);
  options.simulator.max_trajectory_s = 0.01;
  options.retries = 1;
  const Recording run = record(options);
  const std::vector<Episode> episodes = split_episodes(run.records);
  ASSERT_EQ(episodes.size(), 1u);
  const Episode& episode = episodes[0];
  // Only the last attempt is written: the reset's observation and the failed move's.
  ASSERT_EQ(episode.observations.size(), 2u);
  const stream::Record& last = *episode.observations.back();
  EXPECT_EQ(last.scalar<uint8_t>("terminal"), 1);
  EXPECT_EQ(last.scalar<uint8_t>("success"), 0);
  ASSERT_TRUE(last.has("failure"));
  const stream::Record& summary = *episode.summary;
  EXPECT_EQ(summary.scalar<uint8_t>("success"), 0);
  EXPECT_EQ(summary.string("failure"), last.string("failure"));
  EXPECT_EQ(summary.scalar<int32_t>("attempts"), 2);
  EXPECT_EQ(summary.scalar<int32_t>("frames"), 2);
  // The retry's scene is one no first attempt uses: index episodes + e * retries + attempt - 1.
  const int64_t retry_seed = sim_step::plan_reset(options.episodes, 1).scalar<int64_t>("seed");
  EXPECT_EQ(summary.scalar<int64_t>("seed"), retry_seed);
  EXPECT_EQ(last.scalar<int64_t>("episode_seed"), retry_seed);
  EXPECT_NE(retry_seed, sim_step::plan_reset(options.episodes, 0).scalar<int64_t>("seed"));
  EXPECT_EQ(run.summary.episodes, 1);
  EXPECT_EQ(run.summary.successes, 0);
  EXPECT_EQ(run.summary.retried, 1);
  ASSERT_EQ(run.progress.size(), 1u);
  EXPECT_NE(run.progress[0].find("failed (" + last.string("failure") + ")"), std::string::npos) << run.progress[0];
  EXPECT_NE(run.progress[0].find("after 2 attempts"), std::string::npos) << run.progress[0];
}
