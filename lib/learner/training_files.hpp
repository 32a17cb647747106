// The files around a training run: the inputs it reads (whole files, files being appended,
// FIFOs or standard input) and the checkpoint directory it writes.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "stream/record.hpp"

namespace qte::learner {

// Records of several inputs, in order per input. Without `follow` every input is read to its
// end at construction. With `follow`, poll() returns what has arrived since the last call:
// regular files are re-read as they grow (whole records only), FIFOs and '-' are read by a
// thread each until their writers close them.
class InputFollower {
 public:
  InputFollower(const std::vector<std::string>& paths, bool follow);
  ~InputFollower();
  InputFollower(const InputFollower&) = delete;
  InputFollower& operator=(const InputFollower&) = delete;

  std::vector<stream::Record> poll();  // throws the StreamError of a damaged input
  // True when no input can grow any more (no follow, or every FIFO closed; files can always grow).
  bool finished() const;
  // True when every input is a followed regular file: poll() reads each to its current end.
  bool only_files() const;

 private:
  struct Input;
  std::vector<std::unique_ptr<Input>> inputs_;
};

// DIR/step-NNNNNNNN.rec for every checkpoint, DIR/latest.rec a hard link to the newest (so a
// reader always opens a complete file), the oldest removed beyond `keep`.
class CheckpointDirectory {
 public:
  CheckpointDirectory(std::string dir, int keep);
  std::string latest() const { return dir_ + "/latest.rec"; }
  std::string path_for(int64_t step) const;
  // Call after path_for(step) was written completely.
  void publish(int64_t step);
  // Removes the checkpoint of `step` and latest.rec (published as it), and the directory when
  // this object created it and it is now empty: a run that failed before it saved anything of
  // value leaves nothing behind.
  void discard(int64_t step);

 private:
  std::string dir_;
  int keep_;
  bool created_ = false;  // the directory did not exist before
};

}  // namespace qte::learner
