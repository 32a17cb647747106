#include "learner/training_loop.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <random>
#include <sstream>
#include <thread>

#include "common/atomic_file.hpp"
#include "common/error.hpp"
#include "common/random.hpp"
#include "stream/field_names.hpp"
#include "stream/record_types.hpp"

namespace qte::learner {
namespace {

bool exists(const std::string& path) {
  struct stat info {};
  return !path.empty() && ::stat(path.c_str(), &info) == 0;
}

bool is_agent_transition(const stream::Record& r) {
  return r.type() == record_type::transition && !(r.has(fields::demo) && r.scalar<uint8_t>(fields::demo) != 0);
}

// With an adaptive tree target, the mean branches it expanded at depths 1.. come last.
std::string csv_header(int depths, bool adaptive_tree) {
  std::string h = "step,transitions,agent_transitions,replay,demos,loss";
  for (int d = 0; d < depths; ++d) h += ",loss_d" + std::to_string(d);
  for (int d = 0; d < depths; ++d) h += ",q_mean_d" + std::to_string(d) + ",q_max_d" + std::to_string(d);
  h += ",td_mean,priority_mean,steps_per_s,elapsed_s";
  if (adaptive_tree)
    for (int d = 1; d < depths; ++d) h += ",branches_d" + std::to_string(d);
  // The head against the batches' own actions (StepStats), means over the rows' steps.
  h += ",agree_rotation_x,agree_rotation_y,agree_rotation_z,agree_gripper,loss_rotation";
  return h;
}

// Keeps the rows of an earlier run up to `step` (a resumed run rewrites what follows); a fresh
// run (step < 0) starts the file anew without reading what was there, and only a regular file
// is read (not a device or a pipe someone named).
void trim_metrics(const std::string& path, int64_t step, const std::string& header) {
  std::string text = header + "\n";
  std::ifstream in;
  std::error_code ignored;
  if (step >= 0 && std::filesystem::is_regular_file(path, ignored)) in.open(path);
  std::string line;
  if (in) std::getline(in, line);
  for (int64_t row = 2; in && std::getline(in, line); ++row) {
    if (line.empty()) continue;
    const std::string first = line.substr(0, line.find(','));
    char* end = nullptr;
    errno = 0;
    const long long row_step = std::strtoll(first.c_str(), &end, 10);
    if (first.empty() || *end != '\0' || errno != 0)
      throw Error(path + ": line " + std::to_string(row) + ": expected a step number in the first column " +
                  "(a metrics CSV written by qattn-train), found '" + first.substr(0, 24) + "'");
    if (row_step <= step) text += line + "\n";
  }
  AtomicOutputFile file(path);
  file.write(text.data(), text.size());
  file.commit();
}

}  // namespace

int64_t allowed_steps(const LoopOptions& o, int64_t agent_transitions) {
  return o.pretrain + static_cast<int64_t>(o.replay_ratio * static_cast<double>(agent_transitions));
}

int64_t transitions_needed(const LoopOptions& o, int64_t step) {
  if (step < o.pretrain) return 0;
  if (!(o.replay_ratio > 0)) return INT64_MAX;
  int64_t n = static_cast<int64_t>(std::ceil(static_cast<double>(step - o.pretrain + 1) / o.replay_ratio));
  while (allowed_steps(o, n) <= step) ++n;  // floating-point rounding either way
  while (n > 0 && allowed_steps(o, n - 1) > step) --n;
  return n;
}

TrainingLoop::TrainingLoop(QLearner& learner, replay::ReplayBuffer& replay, InputFollower& inputs,
                           CheckpointDirectory& checkpoints, LoopOptions options, std::ostream& progress)
    : learner_(learner), replay_(replay), inputs_(inputs), checkpoints_(checkpoints), options_(std::move(options)),
      progress_(progress) {
  if (options_.steps < 0 || options_.start_after < 0 || !(options_.replay_ratio >= 0) || options_.pretrain < 0)
    throw UsageError("--steps, --start-after, --pretrain and --replay-ratio must be >= 0");
  options_.checkpoint_every = std::max<int64_t>(1, options_.checkpoint_every);
  options_.log_every = std::max<int64_t>(1, options_.log_every);
}

void TrainingLoop::ingest(int64_t agent_limit, bool fill_to_start_after, int64_t total_limit) {
  for (auto& r : inputs_.poll()) pending_.push_back(std::move(r));
  while (!pending_.empty()) {
    const stream::Record& r = pending_.front();
    if (r.type() == record_type::transition) {
      if (transitions_read_ >= total_limit) break;
      const bool agent = is_agent_transition(r);
      const bool wanted = agent_transitions_ < agent_limit ||
                          (fill_to_start_after && static_cast<int64_t>(replay_.size()) < options_.start_after);
      if (agent && !wanted) break;
      check_transition(r, learner_.config());
      ++transitions_read_;
      agent_transitions_ += agent;
    }
    ++records_read_[r.type()];
    replay_.add(r);
    pending_.pop_front();
  }
}

void TrainingLoop::save() {
  stream::Record state(record_type::learner);
  state.set_scalar<int64_t>(fields::step, learner_.step());
  state.set_scalar<int64_t>(fields::transitions_read, transitions_read_);
  state.set_scalar<int64_t>(fields::agent_transitions, agent_transitions_);
  state.set_scalar<int64_t>(fields::seed, static_cast<int64_t>(options_.seed));
  state.set_scalar<int64_t>(fields::threads, options_.threads);
  const std::vector<double> priorities = replay_.priorities();
  state.set<double>(fields::priorities, {static_cast<int64_t>(priorities.size())}, priorities, /*compress=*/true);
  state.set_scalar<double>(fields::max_priority, replay_.max_priority());
  learner_.save(checkpoints_.path_for(learner_.step()), state);
  checkpoints_.publish(learner_.step());
  last_saved_ = learner_.step();
}

bool TrainingLoop::start(bool resume) {
  const std::string header =
      csv_header(learner_.config().hierarchy.depths, learner_.config().tree_branching.adaptive());
  bool resumed = false;
  if (resume && exists(checkpoints_.latest())) {
    const stream::Record state = learner_.load(checkpoints_.latest());
    // Another seed or thread count would continue as another run (other batches, other sums).
    for (const auto& [name, value] :
         {std::pair<const char*, int64_t>{fields::seed, static_cast<int64_t>(options_.seed)},
          std::pair<const char*, int64_t>{fields::threads, options_.threads}})
      if (state.has(name) && state.scalar<int64_t>(name) != value)
        throw UsageError(checkpoints_.latest() + ": the run was started with --" + name + " " +
                         std::to_string(state.scalar<int64_t>(name)) + "; resume it with the same, not " +
                         std::to_string(value));
    const int64_t want = state.scalar<int64_t>(fields::transitions_read);
    while (true) {  // the inputs up to where the checkpoint was taken
      ingest(INT64_MAX, false, want);
      if (transitions_read_ >= want) break;
      if (!options_.follow || inputs_.finished())
        throw Error(checkpoints_.latest() + ": the checkpoint was taken after " + std::to_string(want) +
                    " transitions, the inputs hold " + std::to_string(transitions_read_));
      // Files are read to their end at every poll, and what the checkpoint read was in them
      // before it: fewer now means records were lost (a file system that dropped recent
      // appends), and waiting for them would never end.
      if (inputs_.only_files())
        throw Error(checkpoints_.latest() + ": the checkpoint was taken after " + std::to_string(want) +
                    " transitions, its input files now hold " + std::to_string(transitions_read_) +
                    ": they lost records since; rebuild the replay, or start over with --overwrite");
      std::this_thread::sleep_for(options_.poll);
    }
    const auto priorities = state.array<double>(fields::priorities);
    replay_.restore_priorities(std::vector<double>(priorities.begin(), priorities.end()),
                               state.has(fields::max_priority) ? state.scalar<double>(fields::max_priority) : 1.0);
    last_saved_ = learner_.step();
    progress_ << "qattn-train: resumed at step " << learner_.step() << " with " << transitions_read_
              << " transitions\n";
    resumed = true;
  } else {
    fresh_ = true;
  }
  // The metrics file before the first checkpoint: a --metrics that cannot be written leaves no
  // checkpoint behind.
  if (!options_.metrics_path.empty()) {
    trim_metrics(options_.metrics_path, resumed ? learner_.step() : -1, header);
    metrics_.open(options_.metrics_path, std::ios::app);
  }
  if (!resumed) {
    try {
      save();
    } catch (...) {
      discard_metrics();
      throw;
    }
  }
  return resumed;
}

// A fresh run's metrics file goes with its initial checkpoint (never a device like /dev/null).
void TrainingLoop::discard_metrics() {
  metrics_.close();
  std::error_code ignored;
  if (!options_.metrics_path.empty() && std::filesystem::is_regular_file(options_.metrics_path, ignored))
    std::filesystem::remove(options_.metrics_path, ignored);
}

void TrainingLoop::run() {
  try {
    train();
  } catch (...) {
    if (only_initial_weights_saved()) {
      checkpoints_.discard(0);
      discard_metrics();
    }
    throw;
  }
}

void TrainingLoop::train() {
  started_ = window_start_ = std::chrono::steady_clock::now();
  bool stopping = false;
  while (learner_.step() < options_.steps) {
    const int64_t step = learner_.step();
    const bool pretraining = options_.follow && step < options_.pretrain;
    const int64_t needed = options_.follow ? transitions_needed(options_, step) : INT64_MAX;
    ingest(needed, options_.follow && !pretraining);
    const bool ready = replay_.size() > 0 &&
                       (static_cast<int64_t>(replay_.size()) >= options_.start_after || pretraining) &&
                       (!options_.follow || agent_transitions_ >= needed);
    if (!ready) {
      if (!options_.follow && replay_.size() == 0 && !records_read_.empty())
        throw Error("the inputs hold no transitions, only " + stream::describe_counts(records_read_) +
                    " records: the learner reads keyframe's replay ('frame' and 'transition' records), so run "
                    "keyframe on demonstrations or episodes first");
      if (!options_.follow)
        throw Error("the inputs hold " + std::to_string(replay_.size()) + " transitions, fewer than --start-after " +
                    std::to_string(options_.start_after));
      if (exists(options_.stop_file) || inputs_.finished()) {
        if (stopping) break;
        stopping = true;  // read once more: what was written before the stop file is complete
        continue;
      }
      std::this_thread::sleep_for(options_.poll);
      continue;
    }
    std::mt19937_64 rng(derive_seed(options_.seed, static_cast<uint64_t>(step)));
    const replay::Sample sample = replay_.sample(static_cast<std::size_t>(learner_.config().batch), options_.beta, rng,
                                                 learner_.config().demo_share);
    const Minibatch batch = assemble_minibatch(replay_, sample, learner_.config());
    StepStats stats;
    try {
      stats = learner_.train_step(batch);
    } catch (const Error& e) {
      std::string records;
      for (std::size_t i = 0; i < sample.indices.size() && i < 8; ++i)
        records += (i ? "; " : "") + replay_.transition(sample.indices[i]).position.describe();
      throw Error("step " + std::to_string(step) + ": " + e.what() + " in the batch of " + records +
                  (sample.indices.size() > 8 ? "; ..." : "") +
                  (only_initial_weights_saved() ? " (no trained checkpoint was saved: none is kept)"
                                              : " (the last good checkpoint is " + checkpoints_.path_for(last_saved_) + ")"));
    }
    for (std::size_t index : sample.indices) priority_sum_ += replay_.priority(index);
    replay_.update_priorities(sample.indices, stats.td_errors);
    for (double td : stats.td_errors) td_sum_ += td;
    td_count_ += static_cast<int64_t>(stats.td_errors.size());
    for (std::size_t i = 0; i < stats.head_agreement.size() && i < head_agreement_sum_.size(); ++i)
      head_agreement_sum_[i] += stats.head_agreement[i];
    rotation_loss_sum_ += stats.rotation_loss;
    ++window_steps_;
    if (learner_.step() % options_.log_every == 0 || learner_.step() == options_.steps) log_row(stats);
    if (learner_.step() % options_.checkpoint_every == 0) save();
  }
  if (learner_.step() != last_saved_) save();
}

void TrainingLoop::log_row(const StepStats& stats) {
  const auto now = std::chrono::steady_clock::now();
  const double rate = window_steps_ / std::max(1e-9, std::chrono::duration<double>(now - window_start_).count());
  const double elapsed = std::chrono::duration<double>(now - started_).count();
  std::ostringstream row;
  row << std::setprecision(6) << learner_.step() << ',' << transitions_read_ << ',' << agent_transitions_ << ','
      << replay_.size() << ',' << replay_.demo_count() << ',' << stats.loss;
  for (double l : stats.depth_loss) row << ',' << l;
  for (std::size_t d = 0; d < stats.q_mean.size(); ++d) row << ',' << stats.q_mean[d] << ',' << stats.q_max[d];
  row << ',' << td_sum_ / std::max<int64_t>(1, td_count_) << ',' << priority_sum_ / std::max<int64_t>(1, td_count_)
      << ',' << rate << ',' << elapsed;
  if (learner_.config().tree_branching.adaptive())
    for (double b : stats.mean_branches) row << ',' << b;
  const double window = static_cast<double>(std::max<int64_t>(1, window_steps_));
  for (double a : head_agreement_sum_) row << ',' << a / window;
  row << ',' << rotation_loss_sum_ / window;
  if (metrics_.is_open()) metrics_ << row.str() << '\n' << std::flush;
  progress_ << "qattn-train: step " << learner_.step() << "/" << options_.steps << "  loss " << std::setprecision(4)
            << stats.loss << "  q_max";
  for (double q : stats.q_max) progress_ << ' ' << std::setprecision(3) << q;
  progress_ << "  replay " << replay_.size() << " (" << replay_.demo_count() << " demos)  " << std::setprecision(3)
            << rate << " steps/s  " << options_.networks_in << "\n";
  window_start_ = now;
  window_steps_ = 0;
  td_sum_ = priority_sum_ = 0;
  td_count_ = 0;
  head_agreement_sum_.assign(head_agreement_sum_.size(), 0.0);
  rotation_loss_sum_ = 0;
}

}  // namespace qte::learner
