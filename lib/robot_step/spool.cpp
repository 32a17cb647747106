#include "robot_step/spool.hpp"

#include <cmath>
#include <filesystem>
#include <thread>

#include "common/atomic_file.hpp"
#include "common/bounded_file.hpp"
#include "common/error.hpp"
#include "common/number_list.hpp"

namespace qte::robot_step {

namespace fs = std::filesystem;

namespace {

std::string read_answer(const std::string& path) { return read_regular_file(path, kAnswerLimitBytes, "a driver's answer"); }

std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

// A fault's words as they go into an observation's string: valid UTF-8, one line, bounded.
std::string fault_text(const std::string& answer, const char* silent) {
  const std::string line = clean_text(first_line(answer), kFaultTextLimitBytes);
  return line.empty() ? silent : line;
}

// A frame is read only from regular files: a FIFO or a device named as one would never end.
void require_frame_file(const std::string& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error))
    throw Error(path + ": " + (fs::exists(path, error) ? "not a regular file" : "missing") +
                ", expected the recorder's PNG beside its .ready answer");
}

}  // namespace

MotionAnswer parse_done(const std::string& text, const std::string& what) {
  std::vector<double> values;
  std::string bad;
  const std::string line = first_line(text);
  if (!parse_number_list(line, values, bad) || values.size() != robot::kArmJoints + 1)
    throw Error(what + ": expected one line of 7 joint angles in degrees and the gripper position, comma-separated, got '" +
                line.substr(0, 120) + "'");
  MotionAnswer answer;
  answer.done = true;
  for (int k = 0; k < robot::kArmJoints; ++k) answer.degrees[k] = values[k];
  const double gripper = values[robot::kArmJoints];
  if (gripper < 0 || gripper > robot::kXarmGripperOpenUnits || gripper != std::floor(gripper))
    throw Error(what + ": the gripper position must be a whole number from 0 to 850, got " + std::to_string(gripper));
  answer.gripper = static_cast<int>(gripper);
  return answer;
}

Spool::Spool(std::string directory, long session, std::chrono::milliseconds motion_timeout,
             std::chrono::milliseconds capture_timeout, std::function<std::string()> should_stop)
    : directory_(std::move(directory)),
      session_(session),
      motion_timeout_(motion_timeout),
      capture_timeout_(capture_timeout),
      should_stop_(std::move(should_stop)) {
  std::error_code error;
  fs::create_directories(directory_, error);
  if (!fs::is_directory(directory_)) throw Error(directory_ + ": not a directory the spool can be made in");
}

bool Spool::stopped() const { return fs::exists(path("stop")); }

void Spool::stop(const std::string& why) {
  const std::string text = why + "\n";
  write_file_atomically(path("stop"), text.data(), text.size());
  withdraw();
}

void Spool::withdraw() {
  // A request left unanswered must not be carried out once a person has removed `stop`.
  if (last_request_.empty()) return;
  std::error_code ignored;
  for (const char* answer : {".done", ".fault", ".ready"})
    if (fs::exists(path(last_request_ + answer))) return;
  fs::remove(path(last_request_ + ".xarm.csv"), ignored);
  fs::remove(path(last_request_ + ".request"), ignored);
}

std::string Spool::claim(const std::string& kind) {
  // A process id is reused in time: skip numbers an earlier process of this id left answers to.
  for (;;) {
    char name[96];
    std::snprintf(name, sizeof name, "%s-%ld-%06ld", kind.c_str(), session_, counter_++);
    bool used = false;
    for (const char* suffix : {".xarm.csv", ".done", ".fault", ".request", ".ready", ".color.png", ".depth.png"})
      used = used || fs::exists(path(name + std::string(suffix)));
    if (!used) return last_request_ = name;
  }
}

std::size_t Spool::wait_for(const std::vector<std::string>& names, std::chrono::milliseconds timeout,
                            const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (fs::exists(path(names[i]))) return i;
    if (stopped()) {
      withdraw();
      throw Error(path("stop") + " exists: stopped while waiting for " + what);
    }
    const std::string reason = should_stop_ ? should_stop_() : "";
    if (!reason.empty()) {
      stop(reason);
      throw Error(reason + ": stopped while waiting for " + what + " (" + path("stop") + " written)");
    }
    if (std::chrono::steady_clock::now() > deadline) {
      stop("no answer to " + what);
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", timeout.count() / 1000.0);
      throw Error("no answer to " + what + " in " + seconds + " s: " + path("stop") + " written; is the driver running on " +
                  directory_ + "?");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

MotionAnswer Spool::move(const std::vector<robot::XarmRow>& rows, const std::string& comment) {
  if (stopped()) throw Error(path("stop") + " exists: the robot was stopped; remove it once the robot is safe");
  const std::string reason = should_stop_ ? should_stop_() : "";
  if (!reason.empty()) {
    stop(reason);
    throw Error(reason + ": no motion sent (" + path("stop") + " written)");
  }
  const std::string name = claim("motion");
  const std::string csv = robot::xarm_csv(rows, comment);
  // An interrupt from here on withdraws the request (the handler writes `stop`, then removes it).
  const RemovedOnSignal pending(path(name + ".xarm.csv"));
  return stopping_on_error([&] {
    write_file_atomically(path(name + ".xarm.csv"), csv.data(), csv.size());
    wait_for({name + ".done", name + ".fault"}, motion_timeout_, path(name + ".xarm.csv"));
    // A fault wins over any other answer to the same request: the driver knows better.
    if (!fs::exists(path(name + ".fault"))) return parse_done(read_answer(path(name + ".done")), path(name + ".done"));
    MotionAnswer fault;
    fault.fault = fault_text(read_answer(path(name + ".fault")), "the driver reported a fault without saying which");
    return fault;
  });
}

CaptureAnswer Spool::capture() {
  const std::string name = claim("capture");
  const RemovedOnSignal pending(path(name + ".request"));
  return stopping_on_error([&] {
    write_file_atomically(path(name + ".request"), "", 0);
    wait_for({name + ".ready", name + ".fault"}, capture_timeout_, path(name + ".request"));
    CaptureAnswer answer;
    if (fs::exists(path(name + ".fault"))) {
      answer.fault = fault_text(read_answer(path(name + ".fault")), "the recorder reported a fault without saying which");
      return answer;
    }
    answer.colour_png = path(name + ".color.png");
    answer.depth_png = path(name + ".depth.png");
    require_frame_file(answer.colour_png);
    require_frame_file(answer.depth_png);
    return answer;
  });
}

template <class F>
auto Spool::stopping_on_error(F&& exchange) -> decltype(exchange()) {
  try {
    return exchange();
  } catch (const std::exception& e) {
    // Whatever went wrong (a garbled answer, a file system error), the drivers stop with us.
    if (!stopped()) stop(std::string("robot-step stopped: ") + e.what());
    else withdraw();
    throw;
  }
}

}  // namespace qte::robot_step
