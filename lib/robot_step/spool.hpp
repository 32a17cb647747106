// The robot spool (formats/robot-spool.md): requests to the arm driver and the camera recorder
// written as files in a directory, their answers read back as files. Nothing else crosses to
// the robot's side, so drivers can be written in any language and a test can stand in for them.
#pragma once

#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "robot/xarm_export.hpp"

namespace qte::robot_step {

// What is read of a driver's or recorder's answer file at most (formats/robot-spool.md): a
// .done is one line of eight numbers; a fault's words go into an observation cut to the second.
constexpr std::size_t kAnswerLimitBytes = 64 * 1024;
constexpr std::size_t kFaultTextLimitBytes = 200;

// What the arm driver reported at the end of a motion.
struct MotionAnswer {
  bool done = false;
  robot::JointVector degrees = robot::JointVector::Zero();  // reached (done)
  int gripper = 0;                                          // reached, xArm units (done)
  std::string fault;                                        // the driver's words (not done)
};

// A captured frame: the recorder's colour and depth PNGs, or its fault.
struct CaptureAnswer {
  std::string colour_png, depth_png;
  std::string fault;  // non-empty: no frame
};

class Spool {
 public:
  // `directory` is made if missing. `session` names this writer's requests (the process id in
  // robot-step). `should_stop` is asked while waiting: true makes the wait write `stop` and
  // throw (a person's stop file, an interrupt).
  Spool(std::string directory, long session, std::chrono::milliseconds motion_timeout,
        std::chrono::milliseconds capture_timeout, std::function<std::string()> should_stop);

  // Writes the motion and waits for the driver's answer. A malformed answer, a timeout, a stop
  // or any other error writes `stop` (withdrawing the motion) and throws Error naming the file.
  MotionAnswer move(const std::vector<robot::XarmRow>& rows, const std::string& comment);
  CaptureAnswer capture();

  // Writes DIR/stop (the drivers stop at once) and withdraws this writer's unanswered request.
  void stop(const std::string& why);
  bool stopped() const;

  const std::string& directory() const { return directory_; }
  // The name (without suffix) the last request was written under: motion-<session>-<n>.
  const std::string& last_request() const { return last_request_; }

 private:
  std::string claim(const std::string& kind);
  void withdraw();  // removes the last request if it has no answer
  // Runs one request's exchange; any error writes `stop` (withdrawing the request) first.
  template <class F>
  auto stopping_on_error(F&& exchange) -> decltype(exchange());  // the next request name not used in the directory
  // Waits until one of `names` exists; returns its index. Throws after `timeout` or on a stop.
  std::size_t wait_for(const std::vector<std::string>& names, std::chrono::milliseconds timeout,
                       const std::string& what);
  std::string path(const std::string& name) const { return directory_ + "/" + name; }

  std::string directory_;
  long session_;
  std::chrono::milliseconds motion_timeout_, capture_timeout_;
  std::function<std::string()> should_stop_;
  long counter_ = 0;
  std::string last_request_;
};

// "j1,...,j7,gripper" as a driver's .done holds it; throws Error naming `what` otherwise.
MotionAnswer parse_done(const std::string& text, const std::string& what);

}  // namespace qte::robot_step
