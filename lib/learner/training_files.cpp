#include "learner/training_files.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include "common/atomic_file.hpp"
#include "common/error.hpp"
#include "replay/growing_stream.hpp"
#include "stream/reader.hpp"

namespace qte::learner {

struct InputFollower::Input {
  std::unique_ptr<replay::GrowingStream> growing;  // a regular file being followed
  // A FIFO or stdin, read by a thread into `pending`.
  std::thread thread;
  std::mutex mutex;
  std::deque<stream::Record> pending;
  std::exception_ptr failure;
  bool closed = false;
};

InputFollower::InputFollower(const std::vector<std::string>& paths, bool follow) {
  for (const std::string& path : paths) {
    auto input = std::make_unique<Input>();
    struct stat info {};
    const bool regular = path != "-" && ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
    if (follow && regular) {
      input->growing = std::make_unique<replay::GrowingStream>(path);
    } else if (follow) {
      Input* in = input.get();
      in->thread = std::thread([in, path] {
        try {
          stream::RecordReader reader(path);
          while (auto record = reader.next()) {
            std::lock_guard<std::mutex> lock(in->mutex);
            in->pending.push_back(std::move(*record));
          }
        } catch (...) {
          std::lock_guard<std::mutex> lock(in->mutex);
          in->failure = std::current_exception();
        }
        std::lock_guard<std::mutex> lock(in->mutex);
        in->closed = true;
      });
    } else {
      stream::RecordReader reader(path);
      while (auto record = reader.next()) input->pending.push_back(std::move(*record));
      input->closed = true;
    }
    inputs_.push_back(std::move(input));
  }
}

InputFollower::~InputFollower() {
  // A reader thread blocked on a FIFO ends with its writers; the process may exit first.
  for (auto& input : inputs_)
    if (input->thread.joinable()) input->thread.detach();
}

std::vector<stream::Record> InputFollower::poll() {
  std::vector<stream::Record> records;
  for (auto& input : inputs_) {
    if (input->growing) {
      for (auto& r : input->growing->poll()) records.push_back(std::move(r));
      continue;
    }
    std::lock_guard<std::mutex> lock(input->mutex);
    while (!input->pending.empty()) {
      records.push_back(std::move(input->pending.front()));
      input->pending.pop_front();
    }
    if (input->failure) std::rethrow_exception(input->failure);
  }
  return records;
}

bool InputFollower::only_files() const {
  for (const auto& input : inputs_)
    if (!input->growing) return false;
  return true;
}

bool InputFollower::finished() const {
  for (const auto& input : inputs_) {
    if (input->growing) return false;
    std::lock_guard<std::mutex> lock(input->mutex);
    if (!input->closed || !input->pending.empty()) return false;
  }
  return true;
}

CheckpointDirectory::CheckpointDirectory(std::string dir, int keep) : dir_(std::move(dir)), keep_(std::max(1, keep)) {
  std::error_code error;
  created_ = std::filesystem::create_directories(dir_, error);
  if (error) throw Error("cannot create checkpoint directory " + dir_ + ": " + error.message());
  remove_stale_temporaries(dir_);  // step-N.rec.tmp.PID of a run killed while it wrote
}

std::string CheckpointDirectory::path_for(int64_t step) const {
  char name[40];
  std::snprintf(name, sizeof name, "/step-%08lld.rec", static_cast<long long>(step));
  return dir_ + name;
}

void CheckpointDirectory::discard(int64_t step) {
  std::error_code ignored;  // best effort: the run is failing already
  std::filesystem::remove(latest(), ignored);
  std::filesystem::remove(path_for(step), ignored);
  if (created_ && std::filesystem::is_empty(dir_, ignored)) std::filesystem::remove(dir_, ignored);
}

void CheckpointDirectory::publish(int64_t step) {
  const std::string temporary = dir_ + "/.latest.rec.tmp";
  ::unlink(temporary.c_str());
  if (::link(path_for(step).c_str(), temporary.c_str()) != 0 || ::rename(temporary.c_str(), latest().c_str()) != 0)
    throw_system_error("cannot point " + latest() + " at " + path_for(step));
  // Keep the newest `keep_` numbered checkpoints (names sort by step).
  std::vector<std::string> steps;
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("step-", 0) == 0 && stream::ends_with(name, ".rec")) steps.push_back(entry.path().string());
  }
  std::sort(steps.begin(), steps.end());
  for (std::size_t i = 0; i + keep_ < steps.size(); ++i) std::filesystem::remove(steps[i]);
}

}  // namespace qte::learner
