#include "robot_step/judge.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "common/atomic_file.hpp"
#include "common/bounded_file.hpp"
#include "common/error.hpp"
#include "robot_step/spool.hpp"

namespace qte::robot_step {

Verdict parse_verdict(const std::string& line, const std::string& what) {
  std::string text = line;
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const std::size_t space = text.find(' ');
  const std::string word = text.substr(0, space);
  const std::string rest = space == std::string::npos ? "" : text.substr(text.find_first_not_of(' ', space));
  Verdict verdict;
  if (word == "success") verdict.outcome = Outcome::success;
  else if (word == "failure") verdict.outcome = Outcome::failure, verdict.reason = rest.empty() ? "judged_failure" : clean_text(rest, kFaultTextLimitBytes);
  else if (word == "continue") verdict.outcome = Outcome::go_on;
  else throw Error(what + ": expected success, failure [reason] or continue, got '" + text.substr(0, 80) + "'");
  return verdict;
}

namespace {

// The terminal a person judges at while it is in raw mode, for a fatal signal to put back.
volatile int g_raw_terminal = -1;
termios g_saved_terminal{};
void restore_terminal() {
  if (g_raw_terminal >= 0) ::tcsetattr(g_raw_terminal, TCSANOW, &g_saved_terminal);
}

class PersonJudge : public Judge {
 public:
  explicit PersonJudge(const std::string& terminal) : terminal_(terminal) {
    fd_ = ::open(terminal.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (fd_ < 0)
      throw Error("no terminal to ask a person at (" + terminal + "): give --judge COMMAND or --outcomes FILE");
  }
  ~PersonJudge() override { ::close(fd_); }

  void reset(const EpisodeInfo& e) override {
    say("\nrobot-step: episode " + std::to_string(e.episode) + " of " + e.task + " (variation " +
        std::to_string(e.variation) + ", scene seed " + std::to_string(e.seed) +
        "): set the scene up, clear the robot's path, then press Enter (q stops) ");
    for (;;) {
      const char key = read_key();
      if (key == '\n' || key == '\r') return;
      if (key == 'q') throw Error("stopped by the person at " + terminal_);
    }
  }

  Verdict judge(const StepInfo& s) override {
    say("\nrobot-step: step " + std::to_string(s.step) + " of " + std::to_string(s.episode_length) +
        ": s = success, f = failure, Enter = go on (q stops) ");
    for (;;) {
      const char key = read_key();
      if (key == 's') return {Outcome::success, ""};
      if (key == 'f') return {Outcome::failure, "judged_failure"};
      if (key == '\n' || key == '\r') return {Outcome::go_on, ""};
      if (key == 'q') throw Error("stopped by the person at " + terminal_);
    }
  }

 private:
  void say(const std::string& text) {
    if (::write(fd_, text.data(), text.size()) < 0) throw Error(terminal_ + ": cannot be written to");
  }
  // One key pressed after the prompt, without waiting for Enter or echoing it: keys typed
  // before are discarded (an early Enter must not start the arm's move home). The terminal's
  // mode is restored after, and by a fatal signal meanwhile.
  char read_key() {
    termios saved{};
    const bool is_terminal = ::tcgetattr(fd_, &saved) == 0;
    if (is_terminal) {
      termios raw = saved;
      raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);
      raw.c_cc[VMIN] = 1, raw.c_cc[VTIME] = 0;
      g_saved_terminal = saved;
      g_raw_terminal = fd_;
      call_on_fatal_signal(restore_terminal);
      ::tcsetattr(fd_, TCSAFLUSH, &raw);  // TCSAFLUSH: the keys typed ahead are dropped
    }
    char key = 0;
    const ssize_t n = ::read(fd_, &key, 1);
    if (is_terminal) {
      ::tcsetattr(fd_, TCSANOW, &saved);
      g_raw_terminal = -1;
    }
    if (n != 1) throw Error(terminal_ + ": closed while waiting for the person's key");
    return key;
  }
  std::string terminal_;
  int fd_ = -1;
};

class FileJudge : public Judge {
 public:
  // A file or a FIFO (a script's outcomes as they come), read a bounded line at a time.
  explicit FileJudge(const std::string& path)
      : lines_(path, kJudgeLineLimitBytes, kOutcomesFileLimitBytes, "outcomes (--outcomes)") {}
  void reset(const EpisodeInfo&) override {}
  Verdict judge(const StepInfo& s) override {
    std::string line;
    while (lines_.next(line)) {
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      return parse_verdict(line.substr(first), lines_.path() + ": line " + std::to_string(lines_.line_number()));
    }
    throw Error(lines_.path() + ": no outcome left for step " + std::to_string(s.step) + " of episode " +
                std::to_string(s.episode.episode) + " (after line " + std::to_string(lines_.line_number()) + ")");
  }

 private:
  BoundedLines lines_;
};

class CommandJudge : public Judge {
 public:
  explicit CommandJudge(std::string command) : command_(std::move(command)) {}
  void reset(const EpisodeInfo& e) override {
    set_episode(e);
    run("reset");
  }
  Verdict judge(const StepInfo& s) override {
    set_episode(s.episode);
    ::setenv("QTE_STEP", std::to_string(s.step).c_str(), 1);
    ::setenv("QTE_EPISODE_LENGTH", std::to_string(s.episode_length).c_str(), 1);
    ::setenv("QTE_MOTION", s.motion.c_str(), 1);
    ::setenv("QTE_FRAME", s.colour_png.c_str(), 1);
    const std::string said = run("outcome");
    return parse_verdict(said.substr(0, said.find('\n')), "the judge command '" + command_ + " outcome'");
  }

 private:
  static void set_episode(const EpisodeInfo& e) {
    for (const char* name : {"QTE_STEP", "QTE_EPISODE_LENGTH", "QTE_MOTION", "QTE_FRAME"}) ::unsetenv(name);
    ::setenv("QTE_TASK", e.task.c_str(), 1);
    ::setenv("QTE_VARIATION", std::to_string(e.variation).c_str(), 1);
    ::setenv("QTE_SEED", std::to_string(e.seed).c_str(), 1);
    ::setenv("QTE_EPISODE", std::to_string(e.episode).c_str(), 1);
  }
  // Runs `command word` by /bin/sh; its standard output, or Error when it fails.
  std::string run(const std::string& word) {
    // Its input is not ours (the trajectories' stream): a judge that reads must not take them.
    const std::string line = command_ + " " + word + " < /dev/null";
    std::fflush(nullptr);
    FILE* pipe = ::popen(line.c_str(), "r");
    if (!pipe) throw Error("the judge command '" + line + "' could not be started");
    std::string out;
    char buffer[4096];
    std::size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0 && out.size() <= kJudgeOutputLimitBytes)
      out.append(buffer, n);
    // Closing our end first: a judge still printing gets EPIPE and ends.
    const int status = ::pclose(pipe);
    if (out.size() > kJudgeOutputLimitBytes)
      throw Error("the judge command '" + line + "' printed more than " + std::to_string(kJudgeOutputLimitBytes / 1024) +
                  " KiB, expected one line: success, failure [reason] or continue");
    if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
      throw Error("the judge command '" + line + "' failed (" +
                  (WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                       : "exit status " + std::to_string(WEXITSTATUS(status))) +
                  ")");
    return out;
  }
  std::string command_;
};

}  // namespace

std::unique_ptr<Judge> person_judge(const std::string& terminal) { return std::make_unique<PersonJudge>(terminal); }
std::unique_ptr<Judge> file_judge(const std::string& path) { return std::make_unique<FileJudge>(path); }
std::unique_ptr<Judge> command_judge(const std::string& command) { return std::make_unique<CommandJudge>(command); }

}  // namespace qte::robot_step
