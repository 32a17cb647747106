// Episodes of observation streams and their summary: splitting 'obs' records (as sim-step
// writes them) into episodes at terminal observations, and the success rate with a Wilson
// score interval, mean steps and mean return; both as CSV rows.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "stream/record.hpp"

namespace qte::report {

// The normal quantile of a two-sided 95 % interval.
constexpr double kZ95 = 1.959963984540054;

// One finished episode, as read from its terminal observation.
struct Episode {
  int64_t seed = 0;  // 'episode_seed', 0 when absent
  std::string task;  // 'task', empty when absent
  bool success = false;
  int64_t steps = 0;    // 'step': next-best poses executed
  double return_ = 0;   // sum of 'reward' over the episode's observations
  std::string failure;  // 'failure', empty when absent
};

// Splits one stream into episodes, record by record: an episode is the 'obs' records up to and
// including one whose 'terminal' is 1; other record types are ignored. Observations before an
// 'obs' with 'frame' 0 (a new reset), and those left at finish(), form an unfinished episode:
// not kept, and `report` gets one line "<source>: unfinished episode ... not counted".
class EpisodeSplitter {
 public:
  // `source` names the stream in reports; "-" is named "<stdin>".
  EpisodeSplitter(std::string source, std::function<void(const std::string&)> report);

  void handle(const stream::Record& record);
  void finish();
  const std::vector<Episode>& episodes() const { return episodes_; }

 private:
  void report_unfinished(const std::string& where);

  std::string source_;
  std::function<void(const std::string&)> report_;
  std::vector<Episode> episodes_;
  int64_t observations_ = 0;  // of the episode in progress
  double return_so_far_ = 0;
};

// The finished episodes of the stream at `path` ("-" is standard input): an episode does not
// span files. Unfinished ones go to `report` as EpisodeSplitter says.
std::vector<Episode> read_episodes(const std::string& path, std::function<void(const std::string&)> report);

// Wilson score interval for `successes` out of `trials` at normal quantile z; unlike the normal
// approximation it stays within 0..1 and is exact at 0 and `trials` successes. 0..1 when there
// are no trials: nothing is known.
std::pair<double, double> wilson_interval(int64_t successes, int64_t trials, double z = kZ95);

struct EpisodeSummary {
  int64_t episodes = 0, successes = 0;
  double success_rate = 0, ci95_low = 0, ci95_high = 1, mean_steps = 0, mean_return = 0;
};

// Counts and means over `episodes` (0 with none) and the Wilson 95 % interval of the rate.
EpisodeSummary summarise_episodes(const std::vector<Episode>& episodes);

// CSV lines (with "\n"): the summary's header and row, and per-episode ones; `index` is the
// episode's place in the run.
std::string summary_csv_header();
std::string summary_csv_row(const EpisodeSummary& summary);
std::string episode_csv_header();
std::string episode_csv_row(std::size_t index, const Episode& episode);

}  // namespace qte::report
