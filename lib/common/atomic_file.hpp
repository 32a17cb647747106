// Output files appear whole or not at all: bytes go to "<path>.tmp.<pid>", which commit()
// renames to <path>. A destructor without commit(), SIGINT, SIGTERM or SIGHUP removes the
// temporary file, so a failed or interrupted tool never leaves a half file under the final name.
// A path that exists and is not a regular file (/dev/null, a FIFO, a terminal) is written
// directly: renaming over it would replace the device or pipe with a file. A path that is a
// symbolic link is followed: the file it names is replaced (atomically, beside that file), the
// link stays, as a shell's `>` would do; a dangling link's target is created.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace qte {

class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t n);
  // fsync, then rename over the final name. After this the file is complete on disk.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;         // as given (messages name it)
  std::string target_path_;  // where the bytes go: path_, or the file a symbolic link names
  std::string temp_path_;
  int fd_ = -1;
};

// Writes all of `data` to `fd` (retrying on EINTR and short writes). Throws BrokenPipe on
// EPIPE, Error otherwise; `what` names the destination in the message.
void write_all(int fd, const void* data, std::size_t n, const std::string& what);

// Removes what a killed writer left: files in `dir` named <name>.tmp.<pid> whose process is
// gone, for <name> `name` (or any name when `name` is empty). A SIGKILL gives no chance to
// clean up, so the next program writing there does. Returns how many it removed.
int remove_stale_temporaries(const std::string& dir, const std::string& name = "");

// Creates the directory `path` where output files go, unless it exists (parents are not made).
// Throws Error naming it otherwise. Returns true when it created it.
bool make_output_directory(const std::string& path);

// The files of a program that writes several (pictures, joint files, arrays) appear all or none:
// they are written into a staging directory inside DIR (DIR/.qte-staging.tmp.<pid>, so libraries
// that write to a path can be given staging()), and commit() moves them into DIR. Without
// commit() (an error, SIGINT, SIGTERM, SIGHUP) the staging directory is removed, DIR keeps the
// files it had, and DIR itself is removed again when this run created it; what a SIGKILL left
// is removed by the next writer into DIR.
class OutputDirectory {
 public:
  explicit OutputDirectory(std::string dir);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  // Where files are written until commit().
  const std::string& staging() const { return staging_; }
  std::string path(const std::string& name) const { return staging_ + "/" + name; }
  void write_file(const std::string& name, const void* data, std::size_t n);
  // Moves every staged file into DIR (in name order) and removes the staging directory.
  void commit();

 private:
  std::string dir_, staging_;
  bool created_dir_ = false, committed_ = false;
};

// A file to write (created or truncated, holding `text`) when SIGINT, SIGTERM or SIGHUP ends the
// process, before its temporary files are removed: robot-step's spool `stop`, so that the arm
// halts when the program driving it is interrupted. One such file per process; the last call wins.
void write_on_fatal_signal(const std::string& path, const std::string& text);

// `hook` (async-signal-safe calls only) runs first when SIGINT, SIGTERM or SIGHUP ends the
// process: robot-step's terminal put back out of raw mode. One hook per process; null for none.
void call_on_fatal_signal(void (*hook)());

// While it lives, `path` is removed if SIGINT, SIGTERM or SIGHUP ends the process: a request
// that must not outlive the program waiting for its answer (robot-step's motions).
class RemovedOnSignal {
 public:
  explicit RemovedOnSignal(std::string path);
  ~RemovedOnSignal();
  RemovedOnSignal(const RemovedOnSignal&) = delete;
  RemovedOnSignal& operator=(const RemovedOnSignal&) = delete;

 private:
  std::string path_;
};

// Convenience: the whole file at once, atomically.
void write_file_atomically(const std::string& path, const void* data, std::size_t n);

}  // namespace qte
