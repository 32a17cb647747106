#include "report/episode_stats.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "report/csv.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"
#include "stream/stage.hpp"

namespace qte::report {
namespace {

std::string optional_string(const stream::Record& obs, const std::string& name) {
  return obs.has(name) ? obs.string(name) : std::string();
}

}  // namespace

EpisodeSplitter::EpisodeSplitter(std::string source, std::function<void(const std::string&)> report)
    : source_(source == "-" ? "<stdin>" : std::move(source)), report_(std::move(report)) {}

void EpisodeSplitter::report_unfinished(const std::string& where) {
  report_(source_ + ": unfinished episode " + where + " (" + std::to_string(observations_) + " observation" +
          (observations_ == 1 ? "" : "s") + ", no terminal one): not counted");
}

void EpisodeSplitter::handle(const stream::Record& obs) {
  if (obs.type() != record_type::obs) return;
  if (observations_ > 0 && obs.has(fields::frame) && obs.scalar<int32_t>(fields::frame) == 0) {
    report_unfinished("before record " + std::to_string(obs.position.record_index));
    observations_ = 0;
    return_so_far_ = 0;
  }
  ++observations_;
  const float reward = obs.scalar<float>(fields::reward);
  if (!std::isfinite(reward)) obs.fail(fields::reward, "a finite reward");
  return_so_far_ += reward;
  if (obs.scalar<uint8_t>(fields::terminal) == 0) return;
  Episode e;
  e.seed = obs.has(fields::episode_seed) ? obs.scalar<int64_t>(fields::episode_seed) : 0;
  e.task = optional_string(obs, fields::task);
  e.success = obs.scalar<uint8_t>(fields::success) != 0;
  e.steps = obs.scalar<int32_t>(fields::step);
  e.return_ = return_so_far_;
  e.failure = optional_string(obs, fields::failure);
  episodes_.push_back(std::move(e));
  observations_ = 0;
  return_so_far_ = 0;
}

void EpisodeSplitter::finish() {
  if (observations_ > 0) report_unfinished("at the end");
  observations_ = 0;
  return_so_far_ = 0;
}

std::vector<Episode> read_episodes(const std::string& path, std::function<void(const std::string&)> report) {
  stream::RecordReader reader(path);
  EpisodeSplitter splitter(path, std::move(report));
  std::map<std::string, int64_t> counts;
  while (auto record = reader.next()) {
    ++counts[record->type()];
    splitter.handle(*record);
  }
  stream::require_record_types(reader, counts, {record_type::obs});  // a replay is not episodes
  splitter.finish();
  return splitter.episodes();
}

std::pair<double, double> wilson_interval(int64_t successes, int64_t trials, double z) {
  if (trials <= 0) return {0.0, 1.0};
  const double n = static_cast<double>(trials), p = static_cast<double>(successes) / n;
  const double z2 = z * z, denominator = 1 + z2 / n;
  const double centre = (p + z2 / (2 * n)) / denominator;
  const double half = z * std::sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denominator;
  // Exact ends at 0 and n successes, where centre - half (or + half) cancels to rounding noise.
  return {successes == 0 ? 0.0 : std::max(0.0, centre - half),
          successes == trials ? 1.0 : std::min(1.0, centre + half)};
}

EpisodeSummary summarise_episodes(const std::vector<Episode>& episodes) {
  EpisodeSummary s;
  s.episodes = static_cast<int64_t>(episodes.size());
  int64_t steps = 0;
  double returns = 0;
  for (const Episode& e : episodes) {
    s.successes += e.success;
    steps += e.steps;
    returns += e.return_;
  }
  const int64_t n = s.episodes;
  auto mean = [n](double total) { return n ? total / static_cast<double>(n) : 0.0; };
  s.success_rate = mean(static_cast<double>(s.successes));
  std::tie(s.ci95_low, s.ci95_high) = wilson_interval(s.successes, n, kZ95);
  s.mean_steps = mean(static_cast<double>(steps));
  s.mean_return = mean(returns);
  return s;
}

std::string summary_csv_header() {
  return "episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return\n";
}

std::string summary_csv_row(const EpisodeSummary& s) {
  return std::to_string(s.episodes) + "," + std::to_string(s.successes) + "," + csv_number(s.success_rate) + "," +
         csv_number(s.ci95_low) + "," + csv_number(s.ci95_high) + "," + csv_number(s.mean_steps) + "," +
         csv_number(s.mean_return) + "\n";
}

std::string episode_csv_header() { return "episode,episode_seed,task,success,steps,return,failure\n"; }

std::string episode_csv_row(std::size_t index, const Episode& e) {
  return std::to_string(index) + "," + std::to_string(e.seed) + "," + csv_cell(e.task) + "," +
         (e.success ? "1" : "0") + "," + std::to_string(e.steps) + "," + csv_number(e.return_) + "," +
         csv_cell(e.failure) + "\n";
}

}  // namespace qte::report
