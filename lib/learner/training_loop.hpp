// The learner's run: transitions read as they arrive, gradient steps paced by the replay
// ratio, checkpoints that a killed run resumes from step for step, metrics and progress.
// qattn-train is its options and one call.
//
// Which transitions a step learns from is a function of the inputs alone, never of timing:
// with `follow`, step s takes only the agent transitions the pacing needs for it (the first
// n with pretrain + floor(ratio * n) > s), and reads no agent transition beyond those before
// it is taken. Records before a needed transition (demonstrations, frames) are read freely.
// So a resumed run, or one started after the actor finished, takes the same steps as one that
// followed the actor live.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <fstream>
#include <iosfwd>
#include <map>
#include <string>

#include "learner/q_learner.hpp"
#include "learner/training_files.hpp"
#include "replay/replay_buffer.hpp"

namespace qte::learner {

struct LoopOptions {
  int64_t steps = 1000;          // gradient steps to reach
  int64_t start_after = 200;     // transitions the replay must hold (demos included)
  int64_t pretrain = 0;          // with follow: steps allowed before any agent transition
  double replay_ratio = 1;       // with follow: gradient steps per agent transition
  double beta = 0.5;             // importance-weight exponent: 1/sqrt(p) as published
  bool follow = false;
  std::string stop_file;         // with follow: finish once it exists and the allowed steps are done
  int64_t checkpoint_every = 100;
  int64_t log_every = 10;
  std::string metrics_path;      // CSV; empty: none
  uint64_t seed = 0;
  int threads = 2;  // LibTorch's: floating-point sums differ with it, so a resume must keep it
  std::string networks_in = "fp32";  // what the networks' convolutions run in, for the progress lines
  std::chrono::milliseconds poll{200};
};

// Gradient steps allowed after `agent_transitions` of the agent's own (the pacing of follow).
int64_t allowed_steps(const LoopOptions& options, int64_t agent_transitions);
// The fewest agent transitions that allow step `step` (0-based): 0 during pretraining.
int64_t transitions_needed(const LoopOptions& options, int64_t step);

class TrainingLoop {
 public:
  TrainingLoop(QLearner& learner, replay::ReplayBuffer& replay, InputFollower& inputs,
               CheckpointDirectory& checkpoints, LoopOptions options, std::ostream& progress);

  // With `resume` and a checkpoint in the directory: loads it and reads the inputs up to where
  // it was taken (waiting for them with follow); otherwise writes the initial networks (an
  // actor can start at once). Returns whether it resumed.
  bool start(bool resume);
  // Trains until options.steps, or with follow until the stop file exists (or every input is
  // closed) and no more steps are allowed. Ends with a checkpoint of the last step. A fresh run
  // that fails (bad input, a non-finite loss) before it saved a trained checkpoint removes what
  // it wrote (the initial checkpoint, an empty metrics file) and rethrows: nothing is left behind.
  void run();

  int64_t transitions_read() const { return transitions_read_; }
  int64_t agent_transitions() const { return agent_transitions_; }

 private:
  // Moves records from the inputs into the replay, stopping before the agent transition that
  // would exceed `agent_limit` (unless the replay is below --start-after and may fill up to
  // it), or before transition `total_limit`.
  void ingest(int64_t agent_limit, bool fill_to_start_after, int64_t total_limit = INT64_MAX);
  void train();
  void save();
  void discard_metrics();
  void log_row(const StepStats& stats);

  QLearner& learner_;
  replay::ReplayBuffer& replay_;
  InputFollower& inputs_;
  CheckpointDirectory& checkpoints_;
  LoopOptions options_;
  std::ostream& progress_;
  std::deque<stream::Record> pending_;
  std::map<std::string, int64_t> records_read_;  // by type, for a message on inputs that hold no transitions
  int64_t transitions_read_ = 0, agent_transitions_ = 0, last_saved_ = -1;
  bool fresh_ = false;  // started without a checkpoint to resume
  // A fresh run that saved only its initial weights: nothing worth keeping if it fails.
  bool only_initial_weights_saved() const { return fresh_ && last_saved_ == 0; }
  std::ofstream metrics_;
  std::chrono::steady_clock::time_point started_, window_start_;
  int64_t window_steps_ = 0, td_count_ = 0;
  double td_sum_ = 0, priority_sum_ = 0;
  std::vector<double> head_agreement_sum_ = std::vector<double>(4, 0.0);  // StepStats::head_agreement (x, y, z, gripper) summed over the window
  double rotation_loss_sum_ = 0;
};

}  // namespace qte::learner
