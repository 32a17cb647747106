// Episode statistics: the Wilson interval against published values, episodes split at terminal
// observations and resets, and the summary and per-episode CSV rows.
#include <gtest/gtest.h>

#include "report/episode_stats.hpp"

using namespace qte;
using namespace qte::report;

namespace {

stream::Record obs(int32_t frame, int32_t step, bool terminal, bool success, float reward) {
  stream::Record r("obs");
  r.set_scalar<int32_t>("frame", frame);
  r.set_scalar<int32_t>("step", step);
  r.set_scalar<uint8_t>("terminal", terminal);
  r.set_scalar<uint8_t>("success", success);
  r.set_scalar<float>("reward", reward);
  return r;
}

}  // namespace

// Values as statistics packages print them (e.g. statsmodels proportion_confint, method
// "wilson"), to 4 decimals.
TEST(WilsonInterval, MatchesKnownValues) {
  struct Case {
    int64_t successes, trials;
    double low, high;
  };
  for (const Case& c : {Case{0, 10, 0.0, 0.2775}, Case{5, 10, 0.2366, 0.7634}, Case{10, 10, 0.7225, 1.0},
                        Case{45, 50, 0.7864, 0.9565}, Case{1, 1, 0.2065, 1.0}}) {
    const auto [low, high] = wilson_interval(c.successes, c.trials);
    EXPECT_NEAR(low, c.low, 5e-5) << c.successes << "/" << c.trials;
    EXPECT_NEAR(high, c.high, 5e-5) << c.successes << "/" << c.trials;
  }
}

TEST(WilsonInterval, ExactAtTheEndsAndUnknownWithoutTrials) {
  EXPECT_EQ(wilson_interval(0, 10).first, 0.0);
  EXPECT_EQ(wilson_interval(10, 10).second, 1.0);
  EXPECT_EQ(wilson_interval(0, 0), std::make_pair(0.0, 1.0));
  // Symmetric about 1/2: k of n and n-k of n mirror each other.
  const auto [low, high] = wilson_interval(3, 17);
  const auto [mirror_low, mirror_high] = wilson_interval(14, 17);
  EXPECT_NEAR(low, 1 - mirror_high, 1e-12);
  EXPECT_NEAR(high, 1 - mirror_low, 1e-12);
}

TEST(ReportEpisodes, SplitsAtTerminalObservationsAndReportsUnfinishedOnes) {
  std::vector<std::string> reports;
  EpisodeSplitter splitter("-", [&](const std::string& line) { reports.push_back(line); });
  splitter.handle(obs(0, 0, false, false, 1));
  splitter.handle(stream::Record("action"));  // other records are ignored
  splitter.handle(obs(1, 1, false, false, 2));
  stream::Record last = obs(2, 2, true, true, 100);
  last.set_scalar<int64_t>("episode_seed", 42);
  last.set_string("task", "reach_target");
  splitter.handle(last);
  // Cut short by a reset: not counted.
  splitter.handle(obs(0, 0, false, false, 5));
  stream::Record reset = obs(0, 0, false, false, 0);
  reset.position.record_index = 7;
  splitter.handle(reset);
  stream::Record failed = obs(1, 1, true, false, 0);
  failed.set_string("failure", "invalid_trajectory: start, far");
  splitter.handle(failed);
  splitter.handle(obs(0, 0, false, false, 0));  // unfinished at the end
  splitter.handle(obs(1, 0, false, false, 0));
  splitter.finish();

  ASSERT_EQ(splitter.episodes().size(), 2u);
  const Episode& first = splitter.episodes()[0];
  EXPECT_EQ(first.seed, 42);
  EXPECT_EQ(first.task, "reach_target");
  EXPECT_TRUE(first.success);
  EXPECT_EQ(first.steps, 2);
  EXPECT_DOUBLE_EQ(first.return_, 103);
  const Episode& second = splitter.episodes()[1];
  EXPECT_EQ(second.seed, 0);
  EXPECT_FALSE(second.success);
  EXPECT_EQ(second.failure, "invalid_trajectory: start, far");
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0], "<stdin>: unfinished episode before record 7 (1 observation, no terminal one): not counted");
  EXPECT_EQ(reports[1], "<stdin>: unfinished episode at the end (2 observations, no terminal one): not counted");

  EXPECT_EQ(episode_csv_row(1, second), "1,0,,0,1,0,\"invalid_trajectory: start, far\"\n");
}

TEST(ReportEpisodes, SummaryRowHasRateIntervalAndMeans) {
  std::vector<Episode> episodes(7);
  for (int i = 0; i < 7; ++i) {
    episodes[i].success = i < 5;
    episodes[i].steps = i < 5 ? 2 : 3;
    episodes[i].return_ = i < 5 ? 100 : 0;
  }
  const EpisodeSummary s = summarise_episodes(episodes);
  EXPECT_EQ(s.episodes, 7);
  EXPECT_EQ(s.successes, 5);
  EXPECT_EQ(summary_csv_header(), "episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return\n");
  EXPECT_EQ(summary_csv_row(s), "7,5,0.714286,0.358934,0.917781,2.28571,71.4286\n");
  // No episodes: rate 0, interval 0..1, means 0 (no NaN).
  EXPECT_EQ(summary_csv_row(summarise_episodes({})), "0,0,0,0,1,0,0\n");
}
