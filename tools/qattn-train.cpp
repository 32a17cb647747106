// qattn-train: the learner. Replayed transitions in, Q-attention network checkpoints out.
#include <chrono>
#include <deque>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <thread>

#include <sys/stat.h>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "common/random.hpp"
#include "learner/q_learner.hpp"
#include "learner/training_files.hpp"
#include "nets/qattention_net.hpp"
#include "replay/replay_buffer.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "qattn-train";
  u.summary = "train the coarse-to-fine Q-attention networks from replayed transitions";
  u.description = {
      "Reads 'frame' and 'transition' records (keyframe's output: demonstrations, and with "
      "--agent the agent's own episodes) into a prioritised replay buffer and trains one "
      "Q-attention network per coarse-to-fine depth (LibTorch on the CPU), as C2F-ARM does: a "
      "1-step bootstrap target per depth, r * 0.01 + 0.99 * Q'(s', a'), clamped at 0, where a' "
      "is the online network's greedy coarse-to-fine choice and Q' the target network's value "
      "of it (double DQN); with --tree-target K the target is Q-attention tree expansion over "
      "the target network instead (the K best voxels of each depth expanded, all of a batch's "
      "branches in one forward per depth). Huber loss on the Q of the transition's voxel at "
      "every depth, and at the last depth on its rotation bins' and gripper action's Q; "
      "importance weights of prioritised replay; lambda * mean|Q| regularisation; Adam; "
      "gradient clipping; a soft target update after every step. Priorities are the mean "
      "over depths of the absolute TD error.",
      "Checkpoints go to DIR/step-NNNNNNNN.rec every --checkpoint-every steps (the last --keep "
      "kept) and DIR/latest.rec always names the newest; each is written whole or not at "
      "all. The first record of a checkpoint holds the online networks (what qte-select "
      "loads), then the target networks, then the learner's state (replay priorities, "
      "transitions read). With --resume a run continues from DIR/latest.rec: the same inputs "
      "are read up to where the checkpoint was taken, and the same seed gives the same "
      "steps as an uninterrupted run; a kill loses only the steps since the last checkpoint. "
      "A checkpoint with other settings is refused with the difference. --steps 0 writes the "
      "initial networks (for an actor to start with) and exits.",
      "With --follow the inputs are followed as they grow (files appended by keyframe "
      "--append, FIFOs until closed) and training is paced by --replay-ratio gradient steps "
      "per agent transition (demonstrations are not counted), starting once the replay holds "
      "--start-after transitions. The run ends at --steps, or when --stop-file exists and the "
      "steps the transitions allow are done.",
      "Metrics go to --metrics as CSV (step, transitions, replay size, loss and per-depth "
      "loss, mean and max Q per depth, mean TD error, steps per second); a progress line "
      "goes to standard error. A non-finite loss stops the run with the step and the "
      "records of the batch; the last checkpoint stays the last good one. Transitions of "
      "another voxel size or depth count are refused with their position.",
      "Architectures: 'light' (default; plain 3x3x3 convolutions, 16 base channels, about 0.25 "
      "M parameters per depth, 0.09 GMAC per sample) and 'arm' (the published inception U-Net, "
      "64 base channels, 0.88 M / 1.19 M parameters, 1.8 GMAC per sample: 20 times the work "
      "per step on a CPU).",
  };
  u.arguments = {{"FILE", "frame and transition records; '-' is standard input", false, true}};
  u.options = {
      {"checkpoint-dir", "DIR", "where checkpoints go (required)", ""},
      {"steps", "N", "gradient steps to reach (0: write the initial networks and exit)", "1000"},
      {"resume", "", "continue from DIR/latest.rec when it exists", ""},
      {"follow", "", "keep reading the inputs as they grow; pace training by --replay-ratio", ""},
      {"stop-file", "FILE", "with --follow: finish once FILE exists and the allowed steps are done", ""},
      {"replay-ratio", "R", "with --follow: gradient steps per agent transition", "1"},
      {"pretrain", "N", "with --follow: steps allowed before any agent transition, on the demonstrations even below --start-after", "0"},
      {"start-after", "N", "train once the replay holds N transitions (demos included)", "200"},
      {"checkpoint-every", "N", "steps between checkpoints", "100"},
      {"keep", "N", "numbered checkpoints to keep", "3"},
      {"metrics", "FILE", "CSV of training figures", ""},
      {"log-every", "N", "steps between metrics rows and progress lines", "10"},
      {"architecture", "A", "network per depth: light or arm", "light"},
      {"base-channels", "C", "first-level kernels (default: light 16, arm 64)", ""},
      {"voxels", "V", "voxels per side at every depth", "16"},
      {"depths", "D", "coarse-to-fine depths", "2"},
      {"offset", "M", "half edge of the grids below depth 0, metres", "0.15"},
      {"bounds", "X,Y,Z,S", "scene bounds: minimum corner and edge length, metres", "-0.3,-0.5,0.6,1.0"},
      {"batch", "B", "transitions per step (published: 128)", "32"},
      {"gamma", "G", "discount", "0.99"},
      {"reward-scale", "F", "reward multiplier in the target", "0.01"},
      {"tau", "T", "soft target update rate per step", "0.0025"},
      {"lr", "R", "Adam learning rate", "0.0005"},
      {"weight-decay", "W", "Adam weight decay", "0.000001"},
      {"grad-clip", "N", "maximum gradient norm (0: none)", "5"},
      {"q-reg", "L", "lambda of the lambda * mean|Q| regularisation", "1"},
      {"huber-delta", "D", "Huber loss threshold", "1"},
      {"tree-target", "K", "bootstrap with tree expansion of K branches per depth (0: double DQN)", "0"},
      {"n-step", "N", "bootstrap after N transitions of a chain, summing their discounted rewards", "1"},
      {"uniform", "", "uniform replay sampling instead of prioritised", ""},
      {"alpha", "A", "priority exponent", "0.7"},
      {"beta", "B", "importance-weight exponent", "1"},
      {"capacity", "N", "replay capacity in transitions (demos always kept)", "100000"},
      {"threads", "N", "LibTorch threads", "2"},
  };
  u.uses_randomness = true;
  u.examples = {
      {"qattn-train --checkpoint-dir ckpt --steps 2000 --metrics train.csv demos.rec",
       "train on demonstrations alone"},
      {"qattn-train --follow --stop-file actor.done --replay-ratio 1 --checkpoint-dir ckpt replay.rec &",
       "the learner of the online loop: trains as the actor appends episodes to replay.rec"},
      {"qattn-train --resume --checkpoint-dir ckpt --steps 5000 demos.rec", "continue a run after a kill"},
  };
  u.see_also = {"keyframe(1)", "qte-select(1)", "qte-stream(5)"};
  return u;
}

namespace {

std::string csv_header(int depths) {
  std::string h = "step,transitions,agent_transitions,replay,demos,loss";
  for (int d = 0; d < depths; ++d) h += ",loss_d" + std::to_string(d);
  for (int d = 0; d < depths; ++d) h += ",q_mean_d" + std::to_string(d) + ",q_max_d" + std::to_string(d);
  return h + ",td_mean,priority_mean,steps_per_s,elapsed_s";
}

// Keeps the rows of an earlier run up to `step` (a resumed run rewrites what follows).
void trim_metrics(const std::string& path, int64_t step, const std::string& header) {
  std::ifstream in(path);
  std::string text = header + "\n";
  if (in) {
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line))
      if (!line.empty() && std::stoll(line.substr(0, line.find(','))) <= step) text += line + "\n";
  }
  AtomicOutputFile file(path);
  file.write(text.data(), text.size());
  file.commit();
}

bool exists(const std::string& path) {
  struct stat info {};
  return !path.empty() && ::stat(path.c_str(), &info) == 0;
}

}  // namespace

static void run(const cli::Arguments& args) {
  learner::LearnerConfig config;
  config.net.architecture = nets::architecture_from_name(args.text("architecture"));
  config.net.base_channels = args.has("base-channels") ? static_cast<int>(args.integer("base-channels"))
                                                       : nets::default_base_channels(config.net.architecture);
  config.hierarchy.scene = voxels::GridBounds::parse(args.text("bounds"), static_cast<int>(args.integer("voxels")));
  config.hierarchy.depths = static_cast<int>(args.integer("depths"));
  config.hierarchy.offset_m = args.real("offset");
  config.batch = static_cast<int>(args.integer("batch"));
  config.gamma = args.real("gamma");
  config.reward_scale = args.real("reward-scale");
  config.tau = args.real("tau");
  config.learning_rate = args.real("lr");
  config.weight_decay = args.real("weight-decay");
  config.grad_clip = args.real("grad-clip");
  config.q_regularisation = args.real("q-reg");
  config.huber_delta = args.real("huber-delta");
  config.tree_target_k = static_cast<int>(args.integer("tree-target"));
  config.n_step = static_cast<int>(args.integer("n-step"));
  config.validate();
  if (!args.has("checkpoint-dir")) throw UsageError("--checkpoint-dir is required");
  const int64_t total_steps = args.integer("steps"), start_after = args.integer("start-after");
  const int64_t checkpoint_every = std::max<int64_t>(1, args.integer("checkpoint-every"));
  const int64_t log_every = std::max<int64_t>(1, args.integer("log-every"));
  const double replay_ratio = args.real("replay-ratio"), beta = args.real("beta");
  const int64_t pretrain = args.integer("pretrain");
  const bool follow = args.flag("follow");
  const std::string stop_file = args.text("stop-file");
  if (total_steps < 0 || start_after < 0 || !(replay_ratio >= 0) || pretrain < 0)
    throw UsageError("--steps, --start-after, --pretrain and --replay-ratio must be >= 0");
  replay::ReplayOptions replay_options;
  replay_options.capacity = static_cast<std::size_t>(std::max<int64_t>(1, args.integer("capacity")));
  replay_options.prioritised = !args.flag("uniform");
  replay_options.alpha = args.real("alpha");
  const uint64_t seed = args.seed();

  nets::set_torch_threads(static_cast<int>(args.integer("threads")));
  nets::seed_torch(seed);
  learner::QLearner learner(config);
  replay::ReplayBuffer replay(replay_options);
  learner::CheckpointDirectory checkpoints(args.text("checkpoint-dir"), static_cast<int>(args.integer("keep")));
  learner::InputFollower inputs(args.positional(), follow);

  // Records are taken in input order; `limit` holds reading back to where a checkpoint was taken.
  std::deque<stream::Record> pending;
  int64_t transitions_read = 0, agent_transitions = 0;
  const auto ingest = [&](int64_t limit) {
    for (auto& r : inputs.poll()) pending.push_back(std::move(r));
    while (!pending.empty() && transitions_read < limit) {
      const stream::Record& r = pending.front();
      if (r.type() == "transition") {
        learner::check_transition(r, config);
        ++transitions_read;
        if (!(r.has("demo") && r.scalar<uint8_t>("demo") != 0)) ++agent_transitions;
      }
      replay.add(r);
      pending.pop_front();
    }
  };

  const std::string metrics_path = args.text("metrics");
  const std::string header = csv_header(config.hierarchy.depths);
  const auto save = [&] {
    stream::Record state("learner");
    state.set_scalar<int64_t>("step", learner.step());
    state.set_scalar<int64_t>("transitions_read", transitions_read);
    state.set_scalar<int64_t>("agent_transitions", agent_transitions);
    state.set_scalar<int64_t>("seed", static_cast<int64_t>(seed));
    const std::vector<double> priorities = replay.priorities();
    state.set<double>("priorities", {static_cast<int64_t>(priorities.size())}, priorities, /*compress=*/true);
    learner.save(checkpoints.path_for(learner.step()), state);
    checkpoints.publish(learner.step());
  };

  if (args.flag("resume") && exists(checkpoints.latest())) {
    const stream::Record state = learner.load(checkpoints.latest());
    const int64_t want = state.scalar<int64_t>("transitions_read");
    for (int waited = 0; transitions_read < want; ++waited) {  // the inputs up to the checkpoint
      ingest(want);
      if (transitions_read < want && (!follow || inputs.finished()))
        throw Error(checkpoints.latest() + ": the checkpoint was taken after " + std::to_string(want) +
                    " transitions, the inputs hold " + std::to_string(transitions_read));
      if (transitions_read < want) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    const auto priorities = state.array<double>("priorities");
    replay.restore_priorities(std::vector<double>(priorities.begin(), priorities.end()));
    std::cerr << "qattn-train: resumed at step " << learner.step() << " with " << transitions_read << " transitions\n";
    if (!metrics_path.empty()) trim_metrics(metrics_path, learner.step(), header);
  } else {
    save();  // the initial networks: an actor can start at once
    if (!metrics_path.empty()) trim_metrics(metrics_path, -1, header);
  }
  if (total_steps == 0 || learner.step() >= total_steps) return;

  std::ofstream metrics;
  if (!metrics_path.empty()) metrics.open(metrics_path, std::ios::app);
  const auto started = std::chrono::steady_clock::now();
  auto window_start = started;
  int64_t window_steps = 0, last_saved = learner.step();
  double td_sum = 0, priority_sum = 0;
  int64_t td_count = 0;
  while (learner.step() < total_steps) {
    ingest(INT64_MAX);
    const int64_t allowed = follow ? pretrain + static_cast<int64_t>(replay_ratio * agent_transitions) : INT64_MAX;
    // --pretrain steps may be taken on whatever the replay holds (the demonstrations).
    const bool enough = replay.size() > 0 && (static_cast<int64_t>(replay.size()) >= start_after ||
                                              (follow && learner.step() < pretrain));
    if (!enough || learner.step() >= allowed) {
      if (!follow)
        throw Error("the inputs hold " + std::to_string(replay.size()) + " transitions, fewer than --start-after " +
                    std::to_string(start_after));
      if (exists(stop_file) || inputs.finished()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      continue;
    }
    std::mt19937_64 rng(derive_seed(seed, static_cast<uint64_t>(learner.step())));
    const replay::Sample sample = replay.sample(static_cast<std::size_t>(config.batch), beta, rng);
    const learner::Minibatch batch = learner::assemble_minibatch(replay, sample, config);
    learner::StepStats stats;
    try {
      stats = learner.train_step(batch);
    } catch (const Error& e) {
      std::string records;
      for (std::size_t i = 0; i < sample.indices.size() && i < 8; ++i)
        records += (i ? "; " : "") + replay.transition(sample.indices[i]).position.describe();
      throw Error("step " + std::to_string(learner.step()) + ": " + e.what() + " in the batch of " + records +
                  (sample.indices.size() > 8 ? "; ..." : "") + " (the last good checkpoint is " +
                  checkpoints.path_for(last_saved) + ")");
    }
    for (std::size_t i = 0; i < sample.indices.size(); ++i) priority_sum += replay.priority(sample.indices[i]);
    replay.update_priorities(sample.indices, stats.td_errors);
    for (double td : stats.td_errors) td_sum += td;
    td_count += static_cast<int64_t>(stats.td_errors.size());
    ++window_steps;

    if (learner.step() % log_every == 0 || learner.step() == total_steps) {
      const auto now = std::chrono::steady_clock::now();
      const double rate = window_steps / std::max(1e-9, std::chrono::duration<double>(now - window_start).count());
      const double elapsed = std::chrono::duration<double>(now - started).count();
      std::ostringstream row;
      row << std::setprecision(6) << learner.step() << ',' << transitions_read << ',' << agent_transitions << ','
          << replay.size() << ',' << replay.demo_count() << ',' << stats.loss;
      for (double l : stats.depth_loss) row << ',' << l;
      for (std::size_t d = 0; d < stats.q_mean.size(); ++d) row << ',' << stats.q_mean[d] << ',' << stats.q_max[d];
      row << ',' << td_sum / std::max<int64_t>(1, td_count) << ',' << priority_sum / std::max<int64_t>(1, td_count)
          << ',' << rate << ',' << elapsed;
      if (metrics.is_open()) metrics << row.str() << '\n' << std::flush;
      std::cerr << "qattn-train: step " << learner.step() << "/" << total_steps << "  loss " << std::setprecision(4)
                << stats.loss << "  q_max";
      for (double q : stats.q_max) std::cerr << ' ' << std::setprecision(3) << q;
      std::cerr << "  replay " << replay.size() << " (" << replay.demo_count() << " demos)  "
                << std::setprecision(3) << rate << " steps/s\n";
      window_start = now;
      window_steps = 0;
      td_sum = priority_sum = 0;
      td_count = 0;
    }
    if (learner.step() % checkpoint_every == 0) {
      save();
      last_saved = learner.step();
    }
  }
  if (learner.step() != last_saved) save();
}

int main(int argc, char** argv) {
  nets::use_passive_openmp_waits(argv);
  return cli::run_tool(argc, argv, usage(), run);
}
