// Who says how a real episode went, and puts the scene back: a person at the terminal (one key
// a step), a file of outcomes (scripted runs, tests), or a command (a success detector, or the
// stand-in world of the tests). The reward stays sparse: only "success" earns it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace qte::robot_step {

// What is read of a judge at most: a line of an outcomes file or of a command's output, an
// outcomes file, a command's output (formats/robot-spool.md).
constexpr std::size_t kJudgeLineLimitBytes = 4096;
constexpr uint64_t kOutcomesFileLimitBytes = 16u << 20;
constexpr std::size_t kJudgeOutputLimitBytes = 64 * 1024;

struct EpisodeInfo {
  std::string task;
  int variation = 0;
  int64_t seed = 0;   // the reset record's scene seed (a stand-in world rebuilds the scene from it)
  int episode = 0;    // this robot-step's count of episodes, from 0
};

struct StepInfo {
  EpisodeInfo episode;
  int step = 0;            // next-best poses executed in the episode, from 1
  int episode_length = 0;
  std::string motion;      // the spool request the step's motion went as (motion-<session>-<n>)
  std::string colour_png;  // the frame taken after it
};

enum class Outcome { go_on, success, failure };

struct Verdict {
  Outcome outcome = Outcome::go_on;
  std::string reason;  // a failure's, as the judge gave it
};

class Judge {
 public:
  virtual ~Judge() = default;
  // Returns once the scene of `episode` is set up and the robot's path to its start is clear.
  virtual void reset(const EpisodeInfo& episode) = 0;
  virtual Verdict judge(const StepInfo& step) = 0;
};

// A person at `terminal` (/dev/tty): Enter to start an episode once the scene is back; after
// each step one key, s (success), f (failure) or Enter (go on); q stops the run (Error).
std::unique_ptr<Judge> person_judge(const std::string& terminal);
// Outcomes read from `path` in order, one a line: success, failure [reason], continue (blank
// lines and # comments skipped). Resets ask nothing. Running out is an Error naming the file.
std::unique_ptr<Judge> file_judge(const std::string& path);
// `command reset` before each episode (exit 0 when the scene is ready) and `command outcome`
// after each step, printing success, failure [reason] or continue; run by /bin/sh with QTE_TASK,
// QTE_VARIATION, QTE_SEED, QTE_EPISODE, and after a step QTE_STEP, QTE_EPISODE_LENGTH,
// QTE_MOTION, QTE_FRAME (the colour PNG) in the environment.
std::unique_ptr<Judge> command_judge(const std::string& command);

// A judge's word: success, failure [reason] or continue; throws Error naming `what` otherwise.
Verdict parse_verdict(const std::string& line, const std::string& what);

}  // namespace qte::robot_step
